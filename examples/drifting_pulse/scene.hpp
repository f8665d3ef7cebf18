#pragma once
// §2.1 of the paper: a force-free 1D square density pulse drifting with v_d through a periodic line,
// regularized every T_reg; the remap alone diffuses it, most when T_reg v_d / Delta = 1/2.
#include "common/run_helpers.hpp"
#include "rsph/rsph.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace rsph::scenes {

struct DriftingPulseParams {
  int cells = 128;         ///< lattice sites on the periodic line
  int pulse_width = 4;     ///< pulse width in spacings (the paper: 4 Delta)
  double contrast = 2.0;   ///< density inside the pulse over the background
  double h_over_dx = 1.4;  ///< the paper: h = 1.4 Delta
  double shift = 0.5;      ///< T_reg v_d / Delta
  double v_drift = 1.0;
  std::string remap = "first";  ///< the remap's order, first (eqs. 6-9) or second

  void validate() const {
    require(cells >= 8, "drifting pulse: need at least 8 lattice cells (got " + std::to_string(cells) + ")");
    require(pulse_width >= 1 && pulse_width < cells / 2,
            "drifting pulse: the pulse must be narrower than half the line");
    require(h_over_dx > 0.0, "drifting pulse: h/dx must be positive (got " + std::to_string(h_over_dx) + ")");
    require(shift > 0.0, "drifting pulse: T_reg v_d / Delta must be positive");
    require(v_drift > 0.0, "drifting pulse: the drift speed must be positive");
    require(contrast > 0.0, "drifting pulse: the density contrast must be positive");
    examples::check_remap(remap);
  }
  double spacing() const { return 1.0 / cells; }
  double T_reg() const { return shift * spacing() / v_drift; }
};

template <class Order = regularize::FirstOrder>
using DriftRegularizer = regularize::LatticeRegularizer<lattice::Uniform1D, schedule::EveryT, geometry::LocalVoronoi,
                                                        region::Unbounded, Order>;
template <class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder>
using DriftingPulse = Simulation<1, Kernel, eos::Pressureless, DriftRegularizer<Order>>;

template <class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder>
DriftingPulse<Kernel, Order> make_drifting_pulse(const DriftingPulseParams& s, Order order = {}) {
  s.validate();
  const double dx = s.spacing();
  ParticleSet<1, false> p;
  const int first = s.cells / 2 - s.pulse_width / 2;
  for (int i = 0; i < s.cells; ++i) {
    const double rho = (i >= first && i < first + s.pulse_width) ? s.contrast : 1.0;
    p.add(rho * dx, Vec<1>((i + 0.5) * dx), Vec<1>(s.v_drift), s.h_over_dx * dx);
  }
  Box<1> box;
  box.edge = {Edge::periodic};
  TimeStepParams ts;
  ts.dt_max = s.T_reg();  // force-free: one step per regularization
  return DriftingPulse<Kernel, Order>(std::move(p), box, eos::Pressureless{},
                                      DriftRegularizer<Order>(lattice::Uniform1D{dx}, schedule::EveryT{s.T_reg()},
                                                              {.remap = {s.h_over_dx}, .order = order}),
                                      ts);
}

/// Positions in the frame moving with the drift, wrapped so the pulse sits where it started.
template <class Sim>
std::vector<double> comoving_positions(const Sim& sim, double v_drift) {
  std::vector<double> x;
  const auto& p = sim.particles();
  for (std::size_t a = 0; a < p.n_real; ++a) {
    double xc = p.x[a][0] - v_drift * sim.time();
    xc -= std::floor(xc);
    x.push_back(xc);
  }
  return x;
}

/// Pulse width: sqrt of the second central moment of the excess mass over the background, in Delta.
template <class Sim>
double pulse_width_mass(const Sim& sim, const DriftingPulseParams& s) {
  const auto x = comoving_positions(sim, s.v_drift);
  const auto& p = sim.particles();
  const double background = s.spacing();  // background mass per particle (rho = 1)
  double M = 0.0, mean = 0.0, var = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    M += p.m[a] - background;
    mean += (p.m[a] - background) * x[a];
  }
  mean /= M;
  for (std::size_t a = 0; a < p.n_real; ++a) var += (p.m[a] - background) * (x[a] - mean) * (x[a] - mean);
  return std::sqrt(std::max(var / M, 0.0)) / s.spacing();
}

}  // namespace rsph::scenes
