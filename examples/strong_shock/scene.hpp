#pragma once
// §3.2 of the paper: the Xiao (2004) shock tube, pressure ratio 1e10, t = 2.5e-6, in 2D as a strip
// periodic in y with walls at x = 0 and 1. RSPH (h/Delta = 2, adaptive regularization of Appendix A)
// against plain SPH (grad-h, Monaghan-Gingold viscosity).
#include "common/levels.hpp"
#include "common/runner.hpp"
#include "rsph/rsph.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

namespace rsph::scenes {

struct StrongShockParams {
  analysis::GasState left{1.0, 0.0, 1e10}, right{0.125, 0.0, 0.1};
  double gamma = 1.4;
  double t_end = 2.5e-6;
  double courant = 0.2;            ///< 0.3 leaves a 5e-6 energy error from the first steps across the 1e10 jump
  double alpha = 1.0, beta = 2.0;  ///< Monaghan-Gingold viscosity (both methods)
  // RSPH: a uniform lattice of nx x ny with h/Delta = 2 and the paper's Appendix A parameters
  int nx = 512, ny = 8;
  double h_over_dx = 2.0;
  double N_min = 9.5, N_max = 308.0, dN_max = 0.4;
  std::uint64_t max_steps = 128;
  std::string remap = "first";  ///< RSPH: the remap's order, first (eqs. 6-9) or second
  // RSPH on levels 0..levels (0: the uniform lattice above); nx and ny count cells of the finest level
  examples::DensityJumpLevels refinement;
  // plain SPH: the paper's counts, 800 x 32 left and 100 x 4 right, h = eta (m / rho)^(1/2)
  int sph_nx_left = 800, sph_ny_left = 32, sph_nx_right = 100, sph_ny_right = 4;
  double eta = 1.2;

  void validate() const {
    require(nx >= 16 && ny >= 4, "strong shock: the RSPH lattice needs nx >= 16 and ny >= 4");
    require(h_over_dx > 0.0, "strong shock: h/Delta must be positive (got " + std::to_string(h_over_dx) + ")");
    require(eta > 0.0, "strong shock: eta must be positive");
    require(sph_nx_left > 0 && sph_ny_left > 0 && sph_nx_right > 0 && sph_ny_right > 0,
            "strong shock: SPH particle counts must be positive");
    require(std::abs(double(sph_ny_left) / sph_nx_left - double(sph_ny_right) / sph_nx_right) < 1e-12,
            "strong shock: the SPH blocks must tile the same strip width (ny/nx equal left and right)");
    require(t_end > 0.0, "strong shock: t_end must be positive");
    require(gamma > 1.0, "strong shock: gamma must exceed 1");
    refinement.validate("strong shock", 6);
    examples::check_remap(remap);
    const auto fine_per_block = refinement.fine_cells_per_block();
    require(refinement.levels == 0 || (nx % fine_per_block == 0 && ny % fine_per_block == 0),
            "strong shock: nx and ny must be multiples of 2^levels * block_cells = " + std::to_string(fine_per_block));
  }
  double strip_width_rsph() const { return double(ny) / nx; }
  double strip_width_sph() const { return 0.5 * sph_ny_left / sph_nx_left; }
};

/// What a run leaves for the report, beside its cost.
struct ShockRun : examples::RunCost {
  std::vector<double> x, y, rho, v, P, u;
  analysis::ShockTubeErrors errors;
  double shock_position = 0.0, shock_position_exact = 0.0, contact_exact = 0.0;
  double penetration = 0.0;  ///< fraction of particles beyond contact + 2h that carry left-state gas
  double energy_error = 0.0;
};

namespace detail {

/// Adds a block of lattice particles of mass rho dx^2 / lattice_sum: the kernel's lattice sum makes the
/// SPH density of the lattice rho, 1 makes m / V = rho.
template <class P>
void add_block(P& p, const analysis::GasState& s, const eos::IdealGas& gas, double x0, int nx, int ny, double dx,
               double h_over_dx, double lattice_sum) {
  const double m = s.rho * dx * dx / lattice_sum;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      p.add(m, Vec<2>(x0 + (i + 0.5) * dx, (j + 0.5) * dx), Vec<2>(s.v, 0.0), h_over_dx * dx,
            gas.internal_energy(s.rho, s.P));
}

/// The shock: the largest x whose Delta-wide bin has mean density above the midpoint of the pre- and
/// post-shock densities.
template <class P>
double shock_position(const P& p, double threshold, double bin) {
  const int n = static_cast<int>(std::ceil(1.0 / bin));
  std::vector<double> sum(static_cast<std::size_t>(n), 0.0), count(static_cast<std::size_t>(n), 0.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const int i = std::clamp(static_cast<int>(p.x[a][0] / bin), 0, n - 1);
    sum[static_cast<std::size_t>(i)] += p.rho[a];
    count[static_cast<std::size_t>(i)] += 1.0;
  }
  for (int i = n - 1; i >= 0; --i)
    if (count[static_cast<std::size_t>(i)] > 0 &&
        sum[static_cast<std::size_t>(i)] / count[static_cast<std::size_t>(i)] > threshold)
      return (i + 1) * bin;
  return 0.0;
}

/// The figures of the whole final set at time t: L1 errors of rho, v and P against the exact solution, the shock
/// position, and the fraction of particles beyond the contact + 2h that carry left-state gas.
template <class P>
std::array<double, 5> final_figures(const P& p, const StrongShockParams& s, const analysis::ExactRiemann& exact,
                                    double t) {
  const auto errors = analysis::shock_tube_errors(p, exact, t, 0.5);
  double h_max = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) h_max = std::max(h_max, p.h[a]);
  const double shock = shock_position(p, 0.5 * (s.right.rho + exact.rho_star_right()), h_max);
  // left-state gas: log u nearer to the exact left star value than to the right one
  const eos::IdealGas gas{s.gamma};
  const double uL = std::log(gas.internal_energy(exact.rho_star_left(), exact.p_star()));
  const double uR = std::log(gas.internal_energy(exact.rho_star_right(), exact.p_star()));
  const double contact = 0.5 + exact.v_star() * t;
  std::size_t beyond = 0, left_state = 0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    if (p.x[a][0] <= contact + 2.0 * p.h[a]) continue;
    ++beyond;
    const double lu = std::log(std::max(p.u[a], 1e-300));
    if (std::abs(lu - uL) < std::abs(lu - uR)) ++left_state;
  }
  const double penetration = beyond ? static_cast<double>(left_state) / static_cast<double>(beyond) : 0.0;
  return {errors.L1_rho, errors.L1_v, errors.L1_P, shock, penetration};
}

/// The measures of the final state, made on the whole tube gathered on rank 0 and sent to every rank; the
/// particles' profile (r.x, r.rho, ...) is rank 0's alone.
template <class Sim>
void measure(const Sim& sim, const StrongShockParams& s, ShockRun& r) {
  const analysis::ExactRiemann exact(s.left, s.right, s.gamma);
  decltype(auto) p = examples::particles_on_root(sim);  // the whole tube on rank 0, none on the others
  for (std::size_t a = 0; a < p.n_real; ++a) {
    r.x.push_back(p.x[a][0]);
    r.y.push_back(p.x[a][1]);
    r.rho.push_back(p.rho[a]);
    r.v.push_back(p.v[a][0]);
    r.P.push_back(p.P[a]);
    r.u.push_back(p.u[a]);
  }
  const double t = sim.time();
  r.shock_position_exact = 0.5 + exact.right_shock_speed() * t;
  r.contact_exact = 0.5 + exact.v_star() * t;
  const auto f = examples::measured_on_root(sim, p, [&](const auto& all) { return final_figures(all, s, exact, t); });
  r.errors = {f[0], f[1], f[2]};
  r.shock_position = f[3];
  r.penetration = f[4];
}

}  // namespace detail

template <class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline>
using ShockRegularizer = regularize::LatticeRegularizer<lattice::Square, schedule::Adaptive<Kernel, 2>,
                                                        geometry::LocalVoronoi, region::Unbounded, Order>;
/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline, class... Extra>
using RsphShock =
    Simulation<2, Kernel, eos::IdealGas, ShockRegularizer<Order, Kernel>, physics::ArtificialViscosity, Extra...>;
template <class Kernel = kernel::CubicSpline, class... Extra>
using SphShock =
    Simulation<2, Kernel, eos::IdealGas, regularize::None, physics::ArtificialViscosity, physics::GradH<2>, Extra...>;

template <class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder, class... Extra>
RsphShock<Order, Kernel, Extra...> make_rsph_shock(const StrongShockParams& s, Order order = {}, Extra... extra) {
  s.validate();
  const eos::IdealGas gas{s.gamma};
  const double dx = 1.0 / s.nx;
  ParticleSet<2, true> p;
  const double sum = kernel::lattice_sum<Kernel, 2>(s.h_over_dx);
  detail::add_block(p, s.left, gas, 0.0, s.nx / 2, s.ny, dx, s.h_over_dx, sum);
  detail::add_block(p, s.right, gas, 0.5, s.nx - s.nx / 2, s.ny, dx, s.h_over_dx, sum);
  Box<2> box;
  box.hi = Vec<2>(1.0, s.strip_width_rsph());
  box.edge = {Edge::reflecting, Edge::periodic};
  TimeStepParams ts;
  ts.courant = s.courant;
  return RsphShock<Order, Kernel, Extra...>(
      std::move(p), box, gas,
      ShockRegularizer<Order, Kernel>(lattice::Square{dx},
                                      schedule::Adaptive<Kernel, 2>{s.N_min, s.N_max, s.dN_max, s.max_steps},
                                      {.remap = {s.h_over_dx}, .order = order}),
      ts, physics::ArtificialViscosity{s.alpha, s.beta}, std::move(extra)...);
}

/// RSPH on levels in factors of two (the paper's variable, time-dependent resolution), the density-jump
/// criterion choosing the levels at every regularization, with consistent gradients at the level faces.
using ShockLevels = lattice::MultiLevel<2, refine::DensityJump>;
template <class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline>
using LevelShockRegularizer = regularize::LatticeRegularizer<ShockLevels, schedule::Adaptive<Kernel, 2>,
                                                             geometry::LocalVoronoi, region::Unbounded, Order>;
template <class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline, class... Extra>
using RsphLevelShock = Simulation<2, Kernel, eos::IdealGas, LevelShockRegularizer<Order, Kernel>,
                                  physics::ArtificialViscosity, physics::ConsistentGradient, Extra...>;

/// The tube on the finest lattice, then one remap onto the level lattice: the membrane on the finest
/// level, the uniform states on level 0; rho = m / V, as the continuity equation takes it.
/// `extra`: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder, class... Extra>
RsphLevelShock<Order, Kernel, Extra...> make_rsph_levels_shock(const StrongShockParams& s, Order order = {},
                                                               Extra... extra) {
  s.validate();
  require(s.refinement.levels > 0, "strong shock: the level lattice needs --levels >= 1");
  const eos::IdealGas gas{s.gamma};
  const double dx = 1.0 / s.nx;
  ParticleSet<2, true> p;
  detail::add_block(p, s.left, gas, 0.0, s.nx / 2, s.ny, dx, s.h_over_dx, 1.0);
  detail::add_block(p, s.right, gas, 0.5, s.nx - s.nx / 2, s.ny, dx, s.h_over_dx, 1.0);
  Box<2> box;
  box.hi = Vec<2>(1.0, s.strip_width_rsph());
  box.edge = {Edge::reflecting, Edge::periodic};
  const regularize::RemapParams remap{s.h_over_dx};
  auto ml = examples::start_on_levels(p, box, dx, s.refinement, remap);
  TimeStepParams ts;
  ts.courant = s.courant;
  return RsphLevelShock<Order, Kernel, Extra...>(
      std::move(p), box, gas,
      LevelShockRegularizer<Order, Kernel>(std::move(ml),
                                           schedule::Adaptive<Kernel, 2>{s.N_min, s.N_max, s.dN_max, s.max_steps},
                                           {.remap = remap, .order = order}),
      ts, physics::ArtificialViscosity{s.alpha, s.beta}, physics::ConsistentGradient{}, std::move(extra)...);
}

template <class Kernel = kernel::CubicSpline, class... Extra>
SphShock<Kernel, Extra...> make_sph_shock(const StrongShockParams& s, Extra... extra) {
  s.validate();
  const eos::IdealGas gas{s.gamma};
  ParticleSet<2, true> p;
  const double sum = kernel::lattice_sum<Kernel, 2>(s.eta);
  detail::add_block(p, s.left, gas, 0.0, s.sph_nx_left, s.sph_ny_left, 0.5 / s.sph_nx_left, s.eta, sum);
  detail::add_block(p, s.right, gas, 0.5, s.sph_nx_right, s.sph_ny_right, 0.5 / s.sph_nx_right, s.eta, sum);
  Box<2> box;
  box.hi = Vec<2>(1.0, s.strip_width_sph());
  box.edge = {Edge::reflecting, Edge::periodic};
  TimeStepParams ts;
  ts.courant = s.courant;
  return SphShock<Kernel, Extra...>(std::move(p), box, gas, regularize::None{}, ts,
                                    physics::ArtificialViscosity{s.alpha, s.beta}, physics::GradH<2>{s.eta},
                                    std::move(extra)...);
}

/// Runs any of the simulations to t_end (examples::run_stops); on_step(sim) after each step, on_end(sim) once
/// at the end.
template <class Sim, class OnStep, class OnEnd>
ShockRun run_shock(Sim sim, const StrongShockParams& s, OnStep&& on_step, OnEnd&& on_end,
                   examples::Checkpoints* checkpoints = nullptr) {
  const double E0 = sim.totals().total_energy();
  ShockRun r;
  static_cast<examples::RunCost&>(r) =
      examples::run_stops(sim, examples::at_times({s.t_end}), on_step, examples::NoHook{}, checkpoints);
  on_end(sim);
  detail::measure(sim, s, r);
  r.energy_error = std::abs(sim.totals().total_energy() - E0) / E0;
  return r;
}

}  // namespace rsph::scenes
