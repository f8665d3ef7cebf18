#pragma once
// The Sedov-Taylor blast: energy E deposited at the centre of a uniform gas at rest (rho = 1, P = 1e-5, gamma =
// 5/3) in a periodic box of unit side, run until the shock reaches 0.35 of the box, in 3D (and 2D, where it is
// the cylindrical blast). Plain grad-h SPH against RSPH (the adaptive regularization of Appendix A onto the
// cubic or square lattice), both with Monaghan-Gingold viscosity; the exact solution is analysis::SedovTaylor.
#include "common/blocks.hpp"
#include "common/runner.hpp"
#include "rsph/rsph.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace rsph::scenes {

struct SedovParams {
  double E = 1.0, rho0 = 1.0, P0 = 1e-5, gamma = 5.0 / 3.0;
  int n = 0;               ///< particles (lattice cells) along each side of the box (0: 32 in 3D, 128 in 2D)
  double r_end = 0.35;     ///< the exact shock radius at the end, in box lengths
  double h_over_dx = 1.2;  ///< SPH: eta of h = eta (m / rho)^(1/D); RSPH: h / Delta
  double alpha = 1.0, beta = 2.0;
  double courant = 0.3;
  int max_bin = 0;         ///< individual time steps down to 2^-max_bin of the longest (0: one global step)
  double injection = 2.0;  ///< the energy goes to the particles within this many h of the centre, weighted by W
  // RSPH: Appendix A's schedule between h/Delta bounds of the local lattice, with the paper's dN_max
  double h_min = 0.9, h_max = 2.5, dN_max = 0.4;
  std::uint64_t max_steps = 128;
  std::string remap = "first";
  int bins = 0;  ///< radial bins of the profile inside the exact shock radius R, half as many beyond (0: about
                 ///< one per lattice spacing)

  int side(int D) const { return n > 0 ? n : (D == 3 ? 32 : 128); }
  void validate() const {
    require(std::isfinite(E) && E > 0.0, "Sedov: the blast energy E must be positive");
    require(std::isfinite(rho0) && rho0 > 0.0 && std::isfinite(P0) && P0 > 0.0,
            "Sedov: the ambient density and pressure must be positive");
    require(std::isfinite(gamma) && gamma > 1.0, "Sedov: gamma must exceed 1");
    require(n == 0 || n >= 8, "Sedov: --n must be at least 8 particles along a side");
    require(std::isfinite(r_end) && r_end > 0.0 && r_end < 0.5, "Sedov: --r-end must lie in (0, 0.5)");
    require(std::isfinite(h_over_dx) && h_over_dx > 0.0, "Sedov: h/Delta must be positive");
    require(std::isfinite(injection) && injection > 0.0, "Sedov: --injection must be positive");
    require(alpha >= 0.0 && beta >= 0.0, "Sedov: the viscosity coefficients must not be negative");
    require(std::isfinite(courant) && courant > 0.0, "Sedov: the Courant factor must be positive");
    require(max_bin >= 0 && max_bin <= 20, "Sedov: --max-bin must lie in 0..20");
    require(h_min > 0.0 && h_max > h_min, "Sedov: need 0 < --h-min < --h-max");
    require(bins >= 0, "Sedov: --bins must not be negative");
    examples::check_remap(remap);
  }
};

/// What a run leaves for the report, beside its cost.
struct SedovRun : examples::RunCost {
  double time = 0.0, radius_exact = 0.0, radius = 0.0;  ///< the shock's radius, exact and measured
  double xi0 = 0.0, jump = 0.0;                 ///< the exact solution's R(t) constant and strong-shock density jump
  double peak_density = 0.0, peak_exact = 0.0;  ///< the binned profile's peak, and the exact one over the same bins
  double L1_rho = 0.0;                          ///< mean |rho - exact| over the bins out to about 1.5 R
  double energy_error = 0.0;                    ///< |E_end - E_0| / E_0 (total energy, ambient heat included)
  double momentum = 0.0;                        ///< |sum m v| / sum m |v| at the end
  double central_pressure = 0.0;                ///< the particles' mean pressure within 0.3 R over the exact one there
  std::vector<double> r, rho, rho_exact, v, v_exact, P, P_exact;  ///< the binned profile
};

namespace detail {

/// The uniform lattice of the box [-1/2, 1/2]^D, n sites a side, masses rho0 Delta^D / `bias`; the energy E
/// deposited in the particles within `injection` h of the centre, shared by W(r, h).
template <int D, class Kernel>
ParticleSet<D, true> sedov_particles(const SedovParams& s, double bias) {
  const int n = s.side(D);
  const double dx = 1.0 / n, vol = std::pow(dx, D), h = s.h_over_dx * dx;
  const eos::IdealGas gas{s.gamma};
  ParticleSet<D, true> p;
  examples::for_each_block_site<D>({n, n, n}, Vec<D>::Constant(-0.5), Vec<D>::Constant(dx), [&](const Vec<D>& x, auto) {
    p.add(s.rho0 * vol / bias, x, Vec<D>::Zero(), h, gas.internal_energy(s.rho0, s.P0));
  });
  double weight = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (const double r = p.x[a].norm(); r < s.injection * h) weight += kernel::W<Kernel, D>(r, h);
  require(weight > 0.0, "Sedov: no particle lies within the injection radius");
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (const double r = p.x[a].norm(); r < s.injection * h)
      p.u[a] += s.E * kernel::W<Kernel, D>(r, h) / weight / p.m[a];
  return p;
}

template <int D>
Box<D> sedov_box() {
  Box<D> box;
  box.lo.setConstant(-0.5);
  box.hi.setConstant(0.5);
  for (int k = 0; k < D; ++k) box.edge[static_cast<std::size_t>(k)] = Edge::periodic;
  return box;
}

/// The outermost radius where the profile crosses the midpoint between the ambient density and its peak,
/// interpolated between bin centres.
inline double shock_radius(const std::vector<double>& r, const std::vector<double>& rho, double rho0) {
  const auto peak = std::max_element(rho.begin(), rho.end());
  const double mid = 0.5 * (rho0 + *peak);
  for (std::size_t i = rho.size() - 1; i > 0; --i)
    if (rho[i - 1] >= mid && rho[i] < mid)
      return r[i - 1] + (r[i] - r[i - 1]) * (rho[i - 1] - mid) / (rho[i - 1] - rho[i]);
  return r[static_cast<std::size_t>(peak - rho.begin())];
}

/// The radial profile (particles binned by radius, each bin's mean of the particles' values and of the exact
/// solution at their radii) and the measures made from it.
template <class Sim>
void measure(const Sim& sim, const SedovParams& s, SedovRun& r) {
  constexpr int D = Sim::dim;
  const analysis::SedovTaylor exact(D, s.gamma, s.E, s.rho0);
  const auto& p = sim.particles();
  // bins of about a lattice spacing with the exact shock on a bin edge, so that the exact binned profile and
  // the L1 measured against it do not depend on where the bin edges fall about the shock
  const double t = sim.time(), R = exact.shock_radius(t);
  const int inside = s.bins > 0 ? s.bins : std::max(4, static_cast<int>(std::lround(R * s.side(D))));
  const int bins = inside + inside / 2;
  const double r_max = R * bins / inside;
  std::vector<double> count(static_cast<std::size_t>(bins), 0.0), sums(7 * static_cast<std::size_t>(bins), 0.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const double ra = p.x[a].norm();
    if (ra >= r_max) continue;
    const auto b = static_cast<std::size_t>(ra / r_max * bins);
    const auto e = exact.at(ra, t);
    const double va = ra > 0.0 ? p.v[a].dot(p.x[a]) / ra : 0.0;
    const double values[] = {ra, p.rho[a], e.rho, va, e.v, p.P[a], e.P + s.P0};
    count[b] += 1.0;
    for (std::size_t c = 0; c < 7; ++c) sums[7 * b + c] += values[c];
  }
  examples::sum_over_ranks(sim, count);
  examples::sum_over_ranks(sim, sums);
  std::vector<double>* columns[] = {&r.r, &r.rho, &r.rho_exact, &r.v, &r.v_exact, &r.P, &r.P_exact};
  double l1 = 0.0;
  for (std::size_t b = 0; b < count.size(); ++b) {
    if (count[b] == 0.0) continue;
    for (std::size_t c = 0; c < 7; ++c) columns[c]->push_back(sums[7 * b + c] / count[b]);
    l1 += std::abs(r.rho.back() - r.rho_exact.back());
  }
  require(!r.r.empty(), "Sedov: no particle lies within 1.5 shock radii of the centre");
  r.L1_rho = l1 / static_cast<double>(r.r.size());
  r.time = t;
  r.radius_exact = R;
  r.xi0 = exact.xi0();
  r.jump = exact.density_jump();
  r.radius = shock_radius(r.r, r.rho, s.rho0);
  r.peak_density = *std::max_element(r.rho.begin(), r.rho.end());
  r.peak_exact = *std::max_element(r.rho_exact.begin(), r.rho_exact.end());
  Vec<D> momentum = Vec<D>::Zero();
  double scale = 0.0, P_centre = 0.0, P_centre_exact = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    momentum += p.m[a] * p.v[a];
    scale += p.m[a] * p.v[a].norm();
    if (const double ra = p.x[a].norm(); ra < 0.3 * R) {
      P_centre += p.P[a];
      P_centre_exact += exact.at(ra, t).P + s.P0;
    }
  }
  std::array<double, D + 3> over_ranks;
  for (int k = 0; k < D; ++k) over_ranks[static_cast<std::size_t>(k)] = momentum[k];
  over_ranks[D] = scale, over_ranks[D + 1] = P_centre, over_ranks[D + 2] = P_centre_exact;
  examples::sum_over_ranks(sim, over_ranks);
  for (int k = 0; k < D; ++k) momentum[k] = over_ranks[static_cast<std::size_t>(k)];
  scale = over_ranks[D], P_centre = over_ranks[D + 1], P_centre_exact = over_ranks[D + 2];
  r.central_pressure = P_centre_exact > 0.0 ? P_centre / P_centre_exact : 0.0;
  r.momentum = scale > 0.0 ? momentum.norm() / scale : 0.0;
}

}  // namespace detail

/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <int D, class Kernel, class... Extra>
using SphSedov =
    Simulation<D, Kernel, eos::IdealGas, regularize::None, physics::ArtificialViscosity, physics::GradH<D>, Extra...>;

template <int D, class Kernel, class Order>
using SedovRegularizer =
    regularize::LatticeRegularizer<lattice::Cartesian<D>, schedule::Adaptive<Kernel, D>,
                                   typename geometry::DefaultCellBuilder<D>::type, region::Unbounded, Order>;
template <int D, class Kernel, class Order, class... Extra>
using RsphSedov =
    Simulation<D, Kernel, eos::IdealGas, SedovRegularizer<D, Kernel, Order>, physics::ArtificialViscosity, Extra...>;

inline TimeStepParams sedov_time_steps(const SedovParams& s) {
  TimeStepParams ts;
  ts.courant = s.courant;
  ts.max_bin = s.max_bin;
  return ts;
}

template <int D, class Kernel, class... Extra>
requires(D == 2 || D == 3) SphSedov<D, Kernel, Extra...> make_sph_sedov(const SedovParams& s, Extra... extra) {
  s.validate();
  auto p = detail::sedov_particles<D, Kernel>(s, kernel::lattice_sum<Kernel, D>(s.h_over_dx));
  return SphSedov<D, Kernel, Extra...>(std::move(p), detail::sedov_box<D>(), eos::IdealGas{s.gamma}, regularize::None{},
                                       sedov_time_steps(s), physics::ArtificialViscosity{s.alpha, s.beta},
                                       physics::GradH<D>{s.h_over_dx}, std::move(extra)...);
}

template <int D, class Kernel, class Order, class... Extra>
requires(D == 2 || D == 3) RsphSedov<D, Kernel, Order, Extra...> make_rsph_sedov(const SedovParams& s, Order order = {},
                                                                                 Extra... extra) {
  s.validate();
  auto p = detail::sedov_particles<D, Kernel>(s, kernel::lattice_sum<Kernel, D>(s.h_over_dx));
  const double dx = 1.0 / s.side(D);
  auto schedule = schedule::Adaptive<Kernel, D>::for_h_over_dx(s.h_min, s.h_max, s.dN_max, s.max_steps);
  return RsphSedov<D, Kernel, Order, Extra...>(
      std::move(p), detail::sedov_box<D>(), eos::IdealGas{s.gamma},
      SedovRegularizer<D, Kernel, Order>(lattice::Cartesian<D>{dx}, schedule, {.remap = {s.h_over_dx}, .order = order}),
      sedov_time_steps(s), physics::ArtificialViscosity{s.alpha, s.beta}, std::move(extra)...);
}

/// The end time: when the exact shock reaches r_end.
inline double sedov_end_time(const SedovParams& s, int D) {
  return analysis::SedovTaylor(D, s.gamma, s.E, s.rho0).time_at_radius(s.r_end);
}

/// Runs either simulation to the end time (examples::run_stops); on_step(sim) after each step, on_end(sim)
/// once at the end.
template <class Sim, class OnStep, class OnEnd>
SedovRun run_sedov(Sim sim, const SedovParams& s, OnStep&& on_step, OnEnd&& on_end,
                   examples::Checkpoints* checkpoints = nullptr) {
  const double E0 = sim.totals().total_energy();
  SedovRun r;
  static_cast<examples::RunCost&>(r) = examples::run_stops(sim, examples::at_times({sedov_end_time(s, Sim::dim)}),
                                                           on_step, examples::NoHook{}, checkpoints);
  on_end(sim);
  detail::measure(sim, s, r);
  r.energy_error = std::abs(sim.totals().total_energy() - E0) / E0;
  return r;
}

}  // namespace rsph::scenes
