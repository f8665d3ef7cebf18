#pragma once
// §2.1 of the paper: a force-free 1D square density pulse drifting with v_d through a periodic line,
// regularized every T_reg; the remap alone diffuses it, most when T_reg v_d / Delta = 1/2. In 2D and 3D the
// pulse is a square (cube) drifting along the box's diagonal, v_d along every axis.
#include "common/blocks.hpp"
#include "common/run_helpers.hpp"
#include "rsph/rsph.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::scenes {

struct DriftingPulseParams {
  int cells = 128;         ///< lattice sites along each side of the periodic line (square, cube)
  int pulse_width = 4;     ///< pulse width in spacings (the paper: 4 Delta)
  double contrast = 2.0;   ///< density inside the pulse over the background
  double h_over_dx = 1.4;  ///< the paper: h = 1.4 Delta
  double shift = 0.5;      ///< T_reg v_d / Delta
  double v_drift = 1.0;
  std::string remap = "first";  ///< the remap's order, first (eqs. 6-9) or second

  void validate() const {
    require(cells >= 8, "drifting pulse: need at least 8 lattice cells (got " + std::to_string(cells) + ")");
    require(pulse_width >= 1 && pulse_width < cells / 2,
            "drifting pulse: the pulse must be narrower than half the box");
    require(h_over_dx > 0.0, "drifting pulse: h/dx must be positive (got " + std::to_string(h_over_dx) + ")");
    require(shift > 0.0, "drifting pulse: T_reg v_d / Delta must be positive");
    require(v_drift > 0.0, "drifting pulse: the drift speed must be positive");
    require(contrast > 0.0, "drifting pulse: the density contrast must be positive");
    examples::check_remap(remap);
  }
  double spacing() const { return 1.0 / cells; }
  double T_reg() const { return shift * spacing() / v_drift; }
};

template <class Order = regularize::FirstOrder, int D = 1>
using DriftRegularizer =
    regularize::LatticeRegularizer<lattice::Cartesian<D>, schedule::EveryT,
                                   typename geometry::DefaultCellBuilder<D>::type, region::Unbounded, Order>;
/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder, int D = 1, class... Extra>
using DriftingPulse = Simulation<D, Kernel, eos::Pressureless, DriftRegularizer<Order, D>, Extra...>;

/// The lattice of cells^D sites, density `contrast` in the pulse of pulse_width^D sites at the centre and 1
/// elsewhere, every particle drifting with v_d along each axis.
template <int D = 1, class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder, class... Extra>
DriftingPulse<Kernel, Order, D, Extra...> make_drifting_pulse(const DriftingPulseParams& s, Order order = {},
                                                              Extra... extra) {
  s.validate();
  const double dx = s.spacing();
  ParticleSet<D, false> p;
  const int first = s.cells / 2 - s.pulse_width / 2;
  auto inside = [&](int i) { return i >= first && i < first + s.pulse_width; };
  const int n = s.cells;
  examples::for_each_block_site<D>(
      {n, n, n}, Vec<D>::Zero(), Vec<D>::Constant(dx), [&](const Vec<D>& x, const auto& i) {
        bool in = true;
        for (std::size_t k = 0; k < D; ++k) in = in && inside(i[k]);
        p.add((in ? s.contrast : 1.0) * std::pow(dx, D), x, Vec<D>::Constant(s.v_drift), s.h_over_dx * dx);
      });
  Box<D> box;
  for (int k = 0; k < D; ++k) box.edge[static_cast<std::size_t>(k)] = Edge::periodic;
  TimeStepParams ts;
  ts.dt_max = s.T_reg();  // force-free: one step per regularization
  return DriftingPulse<Kernel, Order, D, Extra...>(
      std::move(p), box, eos::Pressureless{},
      DriftRegularizer<Order, D>(lattice::Cartesian<D>{dx}, schedule::EveryT{s.T_reg()},
                                 {.remap = {s.h_over_dx}, .order = order}),
      ts, std::move(extra)...);
}

/// Positions along `axis` in the frame moving with the drift at time t, wrapped so the pulse sits where it started.
template <class P>
std::vector<double> comoving_positions(const P& p, double t, double v_drift, int axis = 0) {
  std::vector<double> x;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    double xc = p.x[a][axis] - v_drift * t;
    xc -= std::floor(xc);
    x.push_back(xc);
  }
  return x;
}

/// Pulse width along `axis`: sqrt of the second central moment of the excess mass over the background, in
/// Delta, of a whole set of particles at time t.
template <class P>
double pulse_width_mass(const P& p, double t, const DriftingPulseParams& s, int axis = 0) {
  const auto x = comoving_positions(p, t, s.v_drift, axis);
  const double background = std::pow(s.spacing(), P::dim);  // background mass per particle (rho = 1)
  double M = 0.0, mean = 0.0, var = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    M += p.m[a] - background;
    mean += (p.m[a] - background) * x[a];
  }
  mean /= M;
  for (std::size_t a = 0; a < p.n_real; ++a) var += (p.m[a] - background) * (x[a] - mean) * (x[a] - mean);
  return std::sqrt(std::max(var / M, 0.0)) / s.spacing();
}

/// The same of a simulation, its particles gathered on rank 0 and the width sent to every rank.
template <class Sim>
double pulse_width_mass(const Sim& sim, const DriftingPulseParams& s, int axis = 0) {
  decltype(auto) whole = examples::particles_on_root(sim);
  return examples::measured_on_root(
      sim, whole, [&](const auto& all) { return std::array{pulse_width_mass(all, sim.time(), s, axis)}; })[0];
}

/// The widths along every axis, and their root mean square (the 1D width in 1D), of a whole set at time t.
template <class P>
std::pair<std::vector<double>, double> pulse_widths(const P& p, double t, const DriftingPulseParams& s) {
  std::vector<double> w;
  double sum2 = 0.0;
  for (int k = 0; k < P::dim; ++k) {
    w.push_back(pulse_width_mass(p, t, s, k));
    sum2 += w.back() * w.back();
  }
  return {w, std::sqrt(sum2 / P::dim)};
}

/// The same of a simulation from its whole set `whole` on rank 0 (examples::particles_on_root), on every rank.
template <class Sim, class P>
std::pair<std::vector<double>, double> measure_widths(const Sim& sim, const P& whole, const DriftingPulseParams& s) {
  constexpr int D = Sim::dim;
  const auto f = examples::measured_on_root(sim, whole, [&](const auto& all) {
    const auto [axes, rms] = pulse_widths(all, sim.time(), s);
    std::array<double, D + 1> out{};
    std::copy(axes.begin(), axes.end(), out.begin());
    out[D] = rms;
    return out;
  });
  return {std::vector<double>(f.begin(), f.begin() + D), f[D]};
}
/// The same, its particles gathered first.
template <class Sim>
std::pair<std::vector<double>, double> pulse_widths(const Sim& sim, const DriftingPulseParams& s) {
  return measure_widths(sim, examples::particles_on_root(sim), s);
}

}  // namespace rsph::scenes
