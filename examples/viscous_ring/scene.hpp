#pragma once
// §4 of the paper: a pressureless ring on Keplerian orbits around GM = 1 spreads under a kinematic
// viscosity nu_s (Lynden-Bell & Pringle 1974). Particles start on the regularization lattice over
// the annulus where Sigma(tau*_0 = 0.018) is above a floor, with masses from eq. (16) and velocities
// from eqs. (17)-(18); snapshots at the paper's tau*, each fitted by eq. (16) for an effective
// viscous time and so an effective viscosity nu_eff.
#include "common/disk_sites.hpp"
#include "common/runner.hpp"
#include "rsph/paper/viscous_ring.hpp"
#include "rsph/rsph.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::scenes {

struct ViscousRingParams {
  double nu = 4.8e-5;      ///< nu_s, in units of R_0 sqrt(GM R_0)
  double h = 0.02;         ///< smoothing length (R_0)
  double h_over_dx = 1.6;  ///< h / Delta
  int cycle = 4;           ///< c_r in units of `cycle_unit` steps; 0: never regularize (plain SPH)
  int cycle_unit = 40;
  double tau0 = 0.018;  ///< tau* of the initial state
  std::vector<double> taus{0.054, 0.090, 0.126, 0.162, 0.198};
  double sigma_floor = 1e-4;       ///< the initial annulus: Sigma(tau*_0) above this fraction of its peak
  double inner_radius = 0.1;       ///< particles inside are accreted by the central mass (removed, counted)
  std::string viscosity = "mg";    ///< mg: Monaghan-Gingold with Meglicki's alpha; ns: Navier-Stokes stress
  std::string remap = "first";     ///< RSPH: the remap's order, first (eqs. 6-9) or second
  std::string lattice = "square";  ///< the regularization lattice: square (the paper's), hexagonal or rings
  double bin_width = 0.01;         ///< radial bins of the azimuthal average (R_0)
  double force = 0.25;             ///< time-step force factor
  int max_bin = 0;                 ///< mg: individual time steps in 2^max_bin bins (0: one global step)
  double M = 1.0;                  ///< ring mass

  void validate() const {
    require(nu > 0.0, "viscous ring: nu must be positive (got " + std::to_string(nu) + ")");
    require(h > 0.0 && h < 0.2, "viscous ring: h must lie in (0, 0.2) R_0 (got " + std::to_string(h) + ")");
    require(h_over_dx > 0.0, "viscous ring: h/dx must be positive (got " + std::to_string(h_over_dx) + ")");
    require(cycle >= 0 && cycle_unit >= 1, "viscous ring: the regularization cycle must be >= 0 (0: off)");
    examples::check_remap(remap);
    require(!taus.empty() && std::is_sorted(taus.begin(), taus.end()) && taus.front() > tau0,
            "viscous ring: snapshot times tau* must increase and follow tau*_0 = " + std::to_string(tau0));
    require(sigma_floor > 0.0 && sigma_floor < 1.0, "viscous ring: the initial floor must lie in (0, 1)");
    require(viscosity == "mg" || viscosity == "ns", "viscous ring: unknown viscosity '" + viscosity + "' (mg, ns)");
    require(lattice == "square" || lattice == "hexagonal" || lattice == "rings",
            "viscous ring: unknown lattice '" + lattice + "' (square, hexagonal, rings)");
    require(lattice != "rings" || inner_radius >= spacing(),
            "viscous ring: the rings lattice starts at the accretion radius, which must be at least Delta");
    require(bin_width > 0.0, "viscous ring: the radial bin width must be positive");
    require(inner_radius >= 0.0, "viscous ring: the accretion radius must be non-negative");
    require(max_bin >= 0 && max_bin <= 12, "viscous ring: max_bin must lie in [0, 12]");
    require(max_bin == 0 || viscosity == "mg",
            "viscous ring: individual time steps need a pair viscosity (mg), not the stress tensor (ns)");
  }
  double spacing() const { return h / h_over_dx; }
  paper::ViscousRing ring() const { return {M, 1.0, 1.0, nu}; }
  double time_of(double tau) const { return ring().time_at(tau, tau0); }
  /// Open in both axes; its corner fixes the lattice origin.
  Box<2> box() const {
    Box<2> b;
    b.lo = Vec<2>(-4.0, -4.0);
    b.hi = Vec<2>(4.0, 4.0);
    b.edge = {Edge::open, Edge::open};
    return b;
  }
  /// The annulus x_in < R < x_out where Sigma(tau*_0) exceeds the floor.
  std::pair<double, double> annulus() const {
    const auto r = ring();
    const double peak = r.peak_sigma(tau0);
    double x_in = 1.0, x_out = 1.0;
    while (x_in > 1e-3 && r.sigma(tau0, x_in) > sigma_floor * peak) x_in -= 1e-4;
    while (r.sigma(tau0, x_out) > sigma_floor * peak) x_out += 1e-4;
    return {x_in, x_out};
  }
};

/// Lattice sites inside the annulus; masses from eq. (16) times the cell area over the kernel's lattice sum,
/// so rho = Sigma. A hexagonal lattice of the same Delta (nearest-neighbour distance) holds 2/sqrt(3) times
/// the sites.
template <class Kernel = kernel::CubicSpline, class Lattice>
ParticleSet<2, false> ring_particles_on(const ViscousRingParams& s, const Lattice& lat) {
  s.validate();
  const auto ring = s.ring();
  const auto [x_in, x_out] = s.annulus();
  const double bias = examples::lattice_bias<Kernel, Lattice>(s.h_over_dx);
  ParticleSet<2, false> p;
  examples::for_each_site_in_annulus(lat, s.box(), x_in, x_out, [&](const Vec<2>& x, double area) {
    const double R = x.norm();
    const Vec<2> e_R = x / R, e_phi(-e_R[1], e_R[0]);
    const Vec<2> v = ring.v_phi(R) * e_phi + ring.v_R(s.tau0, R) * e_R;
    p.add(ring.sigma(s.tau0, R) * area / bias, x, v, s.h);
  });
  require(p.n_real > 0, "viscous ring: the annulus holds no lattice site (h too large?)");
  return p;
}
/// The scene's lattice: f(lattice) for the one named.
template <class F>
auto with_ring_lattice(const ViscousRingParams& s, F&& f) {
  if (s.lattice == "hexagonal") return f(lattice::Hexagonal{s.spacing()});
  if (s.lattice == "rings") return f(lattice::Rings{s.spacing(), s.inner_radius});
  return f(lattice::Square{s.spacing()});
}
inline ParticleSet<2, false> ring_particles(const ViscousRingParams& s) {
  return with_ring_lattice(s, [&](const auto& lat) { return ring_particles_on(s, lat); });
}

/// Azimuthal statistics of Sigma (the particles' SPH density) in radial bins.
struct RingProfile {
  std::vector<double> x, mean, min, max;
};

/// The profile of the real particles of `p`; `sum_all` and `extreme` (the sums, and the least or largest values,
/// over the ranks, in place) join the bins of the ranks' own particles, or leave them in one process.
template <class P, class Sum, class Extreme>
RingProfile ring_profile(const P& p, double bin_width, Sum&& sum_all, Extreme&& extreme) {
  std::vector<double> R_max{0.0};
  for (std::size_t a = 0; a < p.n_real; ++a) R_max[0] = std::max(R_max[0], p.x[a].norm());
  extreme(R_max, false);
  const auto n_bins = static_cast<std::size_t>(R_max[0] / bin_width) + 1;
  std::vector<double> sum(n_bins, 0.0), lo(n_bins, std::numeric_limits<double>::infinity()), hi(n_bins, 0.0);
  std::vector<double> count(n_bins, 0.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const auto b = static_cast<std::size_t>(p.x[a].norm() / bin_width);
    sum[b] += p.rho[a];
    lo[b] = std::min(lo[b], p.rho[a]);
    hi[b] = std::max(hi[b], p.rho[a]);
    count[b] += 1.0;
  }
  sum_all(sum);
  sum_all(count);
  extreme(lo, true);
  extreme(hi, false);
  RingProfile out;
  for (std::size_t b = 0; b < n_bins; ++b) {
    if (count[b] == 0.0) continue;
    out.x.push_back((static_cast<double>(b) + 0.5) * bin_width);
    out.mean.push_back(sum[b] / count[b]);
    out.min.push_back(lo[b]);
    out.max.push_back(hi[b]);
  }
  return out;
}

/// One snapshot's measurements.
struct RingSnapshot {
  double tau = 0.0, time = 0.0, tau_fit = 0.0, nu_eff = 0.0, noise = 0.0, mass = 0.0;
  std::size_t particles = 0;
  RingProfile profile;
};

/// Fits the profile and measures the noise error: the bin's max - min, averaged over the bins where the
/// analytic Sigma(tau*) exceeds 1 % of its peak, over that peak.
inline RingSnapshot measure_ring(const ViscousRingParams& s, double tau, double time, RingProfile profile) {
  RingSnapshot snap;
  snap.tau = tau;
  snap.time = time;
  const auto ring = s.ring();
  snap.tau_fit = paper::fit_viscous_time(ring, profile.x, profile.mean, s.tau0 * 1.0001, 20.0 * tau);
  snap.nu_eff = (snap.tau_fit - s.tau0) / (12.0 * time);
  const double peak = ring.peak_sigma(tau);
  double noise = 0.0;
  int bins = 0;
  for (std::size_t i = 0; i < profile.x.size(); ++i)
    if (ring.sigma(tau, profile.x[i]) >= 0.01 * peak) {
      noise += profile.max[i] - profile.min[i];
      ++bins;
    }
  snap.noise = bins > 0 ? noise / (bins * peak) : 0.0;
  snap.profile = std::move(profile);
  return snap;
}

struct RingRun : examples::RunCost {
  std::vector<RingSnapshot> snapshots;
  double nu_eff = 0.0, nu_eff_min = 0.0, nu_eff_max = 0.0, noise_error = 0.0;
  double mass_initial = 0.0, mass_final = 0.0, mass_accreted = 0.0, max_mass_error = 0.0;
  std::size_t particles_accreted = 0;
};

namespace detail {

/// The run's snapshots and running figures in a checkpoint (the rest follows from the parameters).
inline void checkpoint_ring_run(io::Archive& ar, RingRun& r) {
  ar.records("snapshots", r.snapshots, [](io::Archive& a, RingSnapshot& snap) {
    a("tau", snap.tau);
    a("time", snap.time);
    a("tau_fit", snap.tau_fit);
    a("nu_eff", snap.nu_eff);
    a("noise", snap.noise);
    a("mass", snap.mass);
    a("particles", snap.particles);
    a("profile_x", snap.profile.x);
    a("profile_mean", snap.profile.mean);
    a("profile_min", snap.profile.min);
    a("profile_max", snap.profile.max);
  });
  ar("mass_accreted", r.mass_accreted);
  ar("particles_accreted", r.particles_accreted);
  ar("max_mass_error", r.max_mass_error);
}

template <class Sim, class OnStep, class OnSnapshot>
RingRun run_ring(Sim& sim, const ViscousRingParams& s, OnStep&& on_step, OnSnapshot&& on_snapshot,
                 examples::Checkpoints* checkpoints) {
  RingRun r;
  const auto part = examples::add_part(checkpoints, "ring", [&](io::Archive& ar) { checkpoint_ring_run(ar, r); });
  r.mass_initial = sim.totals().mass;
  std::vector<double> times;
  for (const double tau : s.taus) times.push_back(s.time_of(tau));
  auto after_step = [&](Sim& sm) {  // gas inside the inner radius is accreted
    r.mass_accreted += examples::remove_particles(
        sm, [r2 = s.inner_radius * s.inner_radius](const Vec<2>& x) { return x.squaredNorm() < r2; },
        r.particles_accreted);
    on_step(sm);
  };
  auto at_snapshot = [&](const Sim& sm, int k) {
    if (k >= 0) {
      const double mass = sm.totals().mass;
      r.max_mass_error = std::max(r.max_mass_error, std::abs(mass + r.mass_accreted - r.mass_initial) / r.mass_initial);
      const auto profile = ring_profile(
          sm.particles(), s.bin_width, [&](std::vector<double>& v) { examples::sum_over_ranks(sm, v); },
          [&](std::vector<double>& v, bool least) { examples::extreme_over_ranks(sm, v, least); });
      auto snap = measure_ring(s, s.taus[static_cast<std::size_t>(k)], sm.time(), profile);
      snap.mass = mass;
      snap.particles = examples::count_over_ranks(sm, sm.particles().n_real);
      r.snapshots.push_back(std::move(snap));
    }
    on_snapshot(sm, k);
  };
  static_cast<examples::RunCost&>(r) =
      examples::run_stops(sim, examples::at_times(times), after_step, at_snapshot, checkpoints);
  r.mass_final = sim.totals().mass;
  double sum = 0.0, noise = 0.0;
  r.nu_eff_min = std::numeric_limits<double>::infinity();
  r.nu_eff_max = -std::numeric_limits<double>::infinity();
  for (const auto& snap : r.snapshots) {
    sum += snap.nu_eff;
    noise += snap.noise;
    r.nu_eff_min = std::min(r.nu_eff_min, snap.nu_eff);
    r.nu_eff_max = std::max(r.nu_eff_max, snap.nu_eff);
  }
  r.nu_eff = sum / static_cast<double>(r.snapshots.size());
  r.noise_error = noise / static_cast<double>(r.snapshots.size());
  return r;
}

}  // namespace detail

/// The scene's methods: RSPH regularized every c_r cycles on a square, hexagonal or rings lattice, and plain SPH
/// (c_r = 0), each with Monaghan-Gingold or Navier-Stokes viscosity, about a point-mass star; with any kernel
/// (the cubic spline by default).
template <class Lattice, class Order = regularize::FirstOrder>
using RingRegularizer =
    regularize::LatticeRegularizer<Lattice, schedule::EveryNSteps, geometry::LocalVoronoi, region::Unbounded, Order>;
/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <class Lattice, class Viscosity, class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline,
          class... Extra>
using RsphRing = Simulation<2, Kernel, eos::Pressureless, RingRegularizer<Lattice, Order>, Viscosity,
                            physics::PointMass<2>, Extra...>;
template <class Viscosity, class Kernel = kernel::CubicSpline, class... Extra>
using SphRing = Simulation<2, Kernel, eos::Pressureless, regularize::None, Viscosity, physics::PointMass<2>, Extra...>;

/// The time-step parameters; individual steps only with the MG viscosity (a stress term needs one step).
template <class Viscosity>
TimeStepParams ring_time_steps(const ViscousRingParams& s) {
  TimeStepParams ts;
  ts.force = s.force;
  if constexpr (!StressTerm<Viscosity, 2>) ts.max_bin = s.max_bin;
  return ts;
}

/// The viscosity of the scene on the particles' lattice (the MG operator's strength depends on it).
template <class Viscosity, class Lattice>
Viscosity ring_viscosity(const ViscousRingParams& s) {
  if constexpr (StressTerm<Viscosity, 2>)
    return Viscosity{s.nu};
  else if constexpr (std::is_same_v<Lattice, lattice::Hexagonal>)
    return Viscosity::on_hexagonal_lattice(s.nu, s.h_over_dx);
  else if constexpr (std::is_same_v<Lattice, lattice::Rings>)
    return Viscosity::on_sheared_rows(s.nu, s.h_over_dx);
  else
    return Viscosity::on_square_lattice(s.nu, s.h_over_dx);
}

template <class Viscosity, class Kernel = kernel::CubicSpline, class Lattice, class Order = regularize::FirstOrder,
          class... Extra>
RsphRing<Lattice, Viscosity, Order, Kernel, Extra...> make_rsph_ring(const ViscousRingParams& s, const Lattice& lat,
                                                                     Order order = {}, Extra... extra) {
  // Open edges: an edge cell closed at 0.75 Delta has about one lattice cell's area, and a new cell
  // less than half covered hands its share to its neighbour, so the edge follows the gas rather
  // than creeping outwards by a closing radius at every regularization; cells with less than 1e-6 of
  // the largest mass join their neighbours, so the far tails (Sigma ~ 1e-6 of its peak) cost nothing.
  const regularize::RemapParams remap{s.h_over_dx, 0.5, 0.75 / s.h_over_dx, 1e-6};
  return RsphRing<Lattice, Viscosity, Order, Kernel, Extra...>(
      ring_particles_on<Kernel>(s, lat), s.box(), {},
      RingRegularizer<Lattice, Order>(lat, schedule::EveryNSteps{std::uint64_t(s.cycle) * s.cycle_unit},
                                      {.remap = remap, .order = order}),
      ring_time_steps<Viscosity>(s), ring_viscosity<Viscosity, Lattice>(s),
      physics::PointMass<2>{1.0, Vec<2>::Zero(), 0.0}, std::move(extra)...);
}

template <class Viscosity, class Kernel = kernel::CubicSpline, class Lattice, class... Extra>
SphRing<Viscosity, Kernel, Extra...> make_sph_ring(const ViscousRingParams& s, const Lattice& lat, Extra... extra) {
  return SphRing<Viscosity, Kernel, Extra...>(ring_particles_on<Kernel>(s, lat), s.box(), {}, {},
                                              ring_time_steps<Viscosity>(s), ring_viscosity<Viscosity, Lattice>(s),
                                              physics::PointMass<2>{1.0, Vec<2>::Zero(), 0.0}, std::move(extra)...);
}

namespace detail {
template <class Kernel, class Lattice, class OnStep, class OnSnapshot>
RingRun run_viscous_ring_on(const ViscousRingParams& s, const Lattice& lat, OnStep&& on_step, OnSnapshot&& on_snapshot,
                            examples::Checkpoints* checkpoints) {
  using MG = physics::ShearViscosityMG<Kernel, 2>;
  using NS = physics::NavierStokesViscosity<2>;
  auto run = [&](auto sim) { return run_ring(sim, s, on_step, on_snapshot, checkpoints); };
  // on the ranks of mpiexec where built with MPI
  auto on = [&](auto... domain) {
    if (s.viscosity == "ns") {
      if (s.cycle == 0) return run(make_sph_ring<NS, Kernel>(s, lat, domain...));
      return examples::with_remap(
          s.remap, [&](auto order) { return run(make_rsph_ring<NS, Kernel>(s, lat, order, domain...)); });
    }
    if (s.cycle == 0) return run(make_sph_ring<MG, Kernel>(s, lat, domain...));
    return examples::with_remap(s.remap,
                                [&](auto order) { return run(make_rsph_ring<MG, Kernel>(s, lat, order, domain...)); });
  };
  return examples::with_ranks<2>(on);
}
}  // namespace detail

/// Runs the ring with the scene's regularization cycle, lattice and viscosity. on_step(sim) after each
/// step; on_snapshot(sim, k) at the start (k = -1) and at each snapshot k; with checkpoints, as they say.
template <class Kernel = kernel::CubicSpline, class OnStep, class OnSnapshot>
RingRun run_viscous_ring(const ViscousRingParams& s, OnStep&& on_step, OnSnapshot&& on_snapshot,
                         examples::Checkpoints* checkpoints = nullptr) {
  s.validate();
  return with_ring_lattice(s, [&](const auto& lat) {
    return detail::run_viscous_ring_on<Kernel>(s, lat, on_step, on_snapshot, checkpoints);
  });
}

}  // namespace rsph::scenes
