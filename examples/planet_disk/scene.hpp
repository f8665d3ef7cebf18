#pragma once
// §5 of the paper after de Val-Borro et al. (2006): a Jupiter (q = 1e-3) or Neptune (1e-4) on a fixed
// circular orbit at a = 1 in a disk of uniform Sigma_0 (eq. 19) between r = 0.4 and 2.5, locally
// isothermal with c_s / v_K = 0.05 or polytropic (eq. 21). Gas in [0.4, 0.5] and [2.4, 2.5] moves on
// fixed circular orbits. RSPH without artificial viscosity (h/Delta = 1.4, Appendix A's adaptive
// regularization) or equal-mass grad-h SPH with artificial viscosity, on the same initial lattice. In 3D
// (scene3d.hpp) the same Sigma_0 in a vertically isothermal disk, its surface density measured from above.
#include "common/disk_sites.hpp"
#include "common/runner.hpp"
#include "planet_disk/scene3d.hpp"
#include "rsph/paper/damping_zones.hpp"
#include "rsph/paper/disk.hpp"
#include "rsph/paper/keplerian_zones.hpp"
#include "rsph/paper/star_planet.hpp"
#include "rsph/rsph.hpp"

#include <chrono>
#include <cmath>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::scenes {

struct PlanetDiskParams {
  int dim = 2;                     ///< 2: the paper's disk; 3: a vertically isothermal disk of the same Sigma
  double q = 1e-3;                 ///< M_p / (M_* + M_p): 1e-3 Jupiter, 1e-4 Neptune
  std::string eos = "isothermal";  ///< isothermal (§5.2, §5.4) or polytropic (§5.3)
  std::string method = "rsph";     ///< rsph: regularized, no artificial viscosity; sph: grad-h SPH
  double particles = 48000;        ///< target particle count over the disk (LOW 48 000, MED 108 000, HIGH 191 000)
  double h_over_dx = 1.4;          ///< RSPH: h / Delta; SPH: eta of h = eta (m / rho)^(1/2)
  std::string lattice = "square";  ///< the lattice of the start and of RSPH's regularization: square, hexagonal, rings
  std::string remap = "first";     ///< RSPH: the remap's order, first (eqs. 6-9) or second
  double orbits = 100.0;           ///< planet orbits to run
  double r_in = 0.4, r_out = 2.5;  ///< the disk
  double zone_width = 0.1;         ///< width of the boundary zones on fixed orbits
  /// Whether the zones keep the members chosen at the start through every remap (KeplerianZones::members_kept)
  /// instead of deciding membership by radius after each (the paper's zones)
  bool keep_zone_members = false;
  /// Width of the wave-damping zones just inside the fixed ones (paper::DampingZones; 0: none, the paper's
  /// set-up) and their time scale in orbital periods at the zones' edges
  double damping_width = 0.0, damping_tau = 0.1;
  double sigma0 = 0.002 / std::numbers::pi;  ///< eq. (19)'s value 6.366e-4 (de Val-Borro's 0.002 / pi), M_* / a^2
  double aspect = 0.05;                      ///< c_s / v_K
  double gamma = 1.4;                        ///< polytropic exponent (eq. 21)
  double softening = 0.03;                   ///< planet potential, in units of a
  double ramp_orbits = 5.0;                  ///< eq. (20)
  double N_min = 4.5, N_max = 107.0, dN_max = 0.8;  ///< Appendix A, the paper's §5 values
  int max_steps = 160;
  double alpha = 1.0, beta = 2.0;  ///< SPH artificial viscosity
  /// RSPH 2D: an artificial viscosity with Balsara's switch (physics::SwitchedViscosity; 0 and 0: none, the
  /// paper's RSPH)
  double rsph_alpha = 0.0, rsph_beta = 0.0;
  double measure_every = 1.0;          ///< orbits between measurements (mass, gap depth)
  double bin_width = 0.02;             ///< annuli of the azimuthal average
  double courant = 0.3, force = 0.25;  ///< time-step factors
  /// RSPH: individual time steps in bins down to 2^-max_bin of the longest (0: one global step); the
  /// force condition at the inner edge sets the shortest, r = 2.4 could step 5 times longer. SPH: global.
  int max_bin = 3;
  /// 3D: the gas and the lattice reach |z| <= surface H(R), H = aspect R (3 H leaves out 0.3 % of the column)
  double surface = 3.0;
  /// 3D: h / Delta of the cubic lattice unless given (59 neighbours, as Sedov's and Sod's)
  static constexpr double h_over_dx_3d = 1.2;

  void validate() const {
    require(dim == 2 || dim == 3, "planet disk: --dim must be 2 or 3 (got " + std::to_string(dim) + ")");
    require(dim == 2 || (eos == "isothermal" && lattice == "square"),
            "planet disk: the 3D disk is locally isothermal on the cubic lattice (--eos isothermal --lattice square)");
    require(dim == 2 || surface > 0.0, "planet disk: --surface must be positive");
    require(q >= 0.0 && q < 0.1, "planet disk: q must lie in [0, 0.1) (got " + std::to_string(q) + ")");
    require(eos == "isothermal" || eos == "polytropic",
            "planet disk: unknown equation of state '" + eos + "' (isothermal, polytropic)");
    require(method == "rsph" || method == "sph", "planet disk: unknown method '" + method + "' (rsph, sph)");
    examples::check_remap(remap);
    require(lattice == "square" || lattice == "hexagonal" || lattice == "rings",
            "planet disk: unknown lattice '" + lattice + "' (square, hexagonal, rings)");
    require(particles >= 100.0, "planet disk: need at least 100 particles (got " + std::to_string(particles) + ")");
    require(h_over_dx > 0.0, "planet disk: h/dx must be positive (got " + std::to_string(h_over_dx) + ")");
    require(orbits > 0.0, "planet disk: the number of orbits must be positive");
    require(r_in > 0.0 && r_out > r_in + 2.0 * zone_width && zone_width > 0.0,
            "planet disk: need 0 < r_in and r_in + 2 zone_width < r_out (an empty disk otherwise)");
    require(damping_width >= 0.0 && r_in + 2.0 * zone_width + 2.0 * damping_width < r_out,
            "planet disk: --damping-width must not be negative, and the damping zones must leave free gas between");
    require(damping_tau > 0.0, "planet disk: --damping-tau must be positive");
    require(r_in < 1.0 && r_out > 1.0, "planet disk: the planet's orbit (r = 1) must lie inside the disk");
    require(sigma0 > 0.0 && aspect > 0.0 && aspect < 0.5, "planet disk: need Sigma_0 > 0 and 0 < c_s/v_K < 0.5");
    require(gamma > 1.0, "planet disk: gamma must exceed 1");
    require(N_min > 0.0 && N_max > N_min && dN_max > 0.0 && max_steps >= 1,
            "planet disk: need 0 < N_min < N_max, dN_max > 0 and max_steps >= 1");
    require(measure_every > 0.0 && bin_width > 0.0, "planet disk: measurement interval and bin width must be positive");
    require(courant > 0.0 && courant <= 1.0 && force > 0.0, "planet disk: bad time-step factors");
    require(max_bin >= 0 && max_bin <= 12, "planet disk: max_bin must lie in [0, 12]");
    require(rsph_alpha >= 0.0 && rsph_beta >= 0.0, "planet disk: --rsph-alpha and --rsph-beta must not be negative");
    require((rsph_alpha == 0.0 && rsph_beta == 0.0) || (dim == 2 && rsph()),
            "planet disk: --rsph-alpha and --rsph-beta are for the 2D RSPH disk (SPH takes --alpha and --beta)");
  }
  bool rsph() const { return method == "rsph"; }
  double area() const { return std::numbers::pi * (r_out * r_out - r_in * r_in); }
  /// 3D: the flared disk's volume, r_in <= R <= r_out and |z| <= surface aspect R.
  double volume() const {
    return 4.0 * std::numbers::pi / 3.0 * surface * aspect * (r_out * r_out * r_out - r_in * r_in * r_in);
  }
  /// Delta for the particle count: the square's side, the hexagonal lattice's nearest-neighbour distance
  /// (cells of area sqrt(3)/2 Delta^2), or the rings' width, rounded so that whole rings fill the disk; every
  /// lattice holds about `particles`.
  double spacing() const {
    if (dim == 3) return method == "sph" ? sph_column_spacing() : std::cbrt(volume() / particles);
    const double d = std::sqrt(area() / particles / (lattice == "hexagonal" ? std::numbers::sqrt3 / 2.0 : 1.0));
    if (lattice != "rings") return d;
    return (r_out - r_in) / std::max(1.0, std::round((r_out - r_in) / d));
  }
  /// The boundary zones' width: on the rings lattice whole rings.
  double zone() const {
    return lattice == "rings" ? std::max(1.0, std::round(zone_width / spacing())) * spacing() : zone_width;
  }
  double h() const { return h_over_dx * spacing(); }
  /// 3D: the vertical profile of the isothermal disk, cut at the surface.
  VerticalProfile vertical() const { return VerticalProfile(aspect, surface * aspect); }
  /// 3D SPH: particles per column, so that their spacing in the plane at r = 1 is about the columns' spacing
  /// Delta (area / Delta^2 columns of I / Delta particles hold the particle count), and Delta that makes the
  /// count with that whole number per column.
  int sph_column_particles() const {
    const double I = vertical().integral();
    return std::max(1, static_cast<int>(std::lround(I / std::cbrt(area() * I / particles))));
  }
  double sph_column_spacing() const { return std::sqrt(area() * sph_column_particles() / particles); }
  paper::StarAndPlanet star_planet() const { return {1.0, q, 1.0, softening, ramp_orbits}; }
  double period() const { return star_planet().period(); }
  /// Pressure support: v_phi^2 = v_K^2 (1 - aspect^2 / Gamma) for Sigma uniform and P ~ Sigma / r, with
  /// Gamma = 1 for the isothermal and gamma for the polytropic disk (whose P starts at c_s^2 Sigma / gamma). In
  /// 3D the midplane's P = c_s^2 rho ~ 1 / r^2: v_phi^2 = v_K^2 (1 - 2 aspect^2), and less above it
  /// (KeplerianZones::Omega).
  double v_factor() const {
    if (dim == 3) return std::sqrt(1.0 - 2.0 * aspect * aspect);
    return std::sqrt(1.0 - aspect * aspect / (eos == "polytropic" ? gamma : 1.0));
  }
  paper::KeplerianZones zones() const { return {1.0, r_in + zone(), r_out - zone(), v_factor(), keep_zone_members}; }
  paper::DampingZones damping() const { return {zones(), damping_width, damping_width, damping_tau}; }
  physics::SwitchedViscosity rsph_viscosity() const { return {{rsph_alpha, rsph_beta}}; }
  Box<2> box() const {
    Box<2> b;
    b.lo = Vec<2>(-r_out - 1.0, -r_out - 1.0);
    b.hi = Vec<2>(r_out + 1.0, r_out + 1.0);
    b.edge = {Edge::open, Edge::open};
    return b;
  }
};

/// c_s(x) = aspect v_K(R) about the centre of mass, R the distance from it in the plane (from the z axis in 3D):
/// vertically isothermal.
struct DiskSoundSpeed {
  double aspect = 0.05, GM = 1.0;
  double operator()(const Vec<2>& x) const { return aspect * std::sqrt(GM / x.norm()); }
  double operator()(const Vec<3>& x) const { return aspect * std::sqrt(GM / std::hypot(x.x(), x.y())); }
  template <class F>
  void describe(F&& f) const {
    f("cs_over_vK", aspect);
    f("GM", GM);
  }
};

/// Eq. (21): K(r) = c_s,0(r)^2 / (gamma Sigma_0^(gamma - 1)).
struct DiskPolytropicK {
  DiskSoundSpeed cs;
  double gamma = 1.4, sigma0 = 1.0;
  double operator()(const Vec<2>& x) const {
    const double c = cs(x);
    return c * c / (gamma * std::pow(sigma0, gamma - 1.0));
  }
  template <class F>
  void describe(F&& f) const {
    cs.describe(f);
    f("sigma0", sigma0);
  }
};

/// Lattice sites in r_in <= r <= r_out on circular orbits. RSPH masses carry the cell area over the kernel's
/// lattice sum, so rho = Sigma_0 in the bulk at h = (h/Delta) Delta; SPH particles have equal masses Sigma_0
/// times the cell area.
template <class Kernel = kernel::CubicSpline, class Lattice>
ParticleSet<2, false> disk_particles_on(const PlanetDiskParams& s, const Lattice& lat) {
  s.validate();
  const double bias = s.rsph() ? examples::lattice_bias<Kernel, Lattice>(s.h_over_dx) : 1.0;
  const auto zones = s.zones();
  ParticleSet<2, false> p;
  examples::for_each_site_in_annulus(lat, s.box(), s.r_in, s.r_out, [&](const Vec<2>& x, double area) {
    p.add(s.sigma0 * area / bias, x, zones.velocity(x), s.h());
  });
  require(p.n_real > 0, "planet disk: the annulus holds no lattice site");
  return p;
}
/// The scene's lattice: f(lattice) for the one named (rings from r_in to r_out).
template <class F>
auto with_disk_lattice(const PlanetDiskParams& s, F&& f) {
  if (s.lattice == "hexagonal") return f(lattice::Hexagonal{s.spacing()});
  if (s.lattice == "rings") return f(lattice::Rings{s.spacing(), s.r_in, s.r_out});
  return f(lattice::Square{s.spacing()});
}
inline ParticleSet<2, false> disk_particles(const PlanetDiskParams& s) {
  return with_disk_lattice(s, [&](const auto& lat) { return disk_particles_on(s, lat); });
}

/// One measurement of the disk.
struct DiskSample {
  double orbit = 0.0, time = 0.0, mass = 0.0, mass_removed = 0.0, gap_depth = 0.0, wall_seconds = 0.0;
  std::size_t particles = 0;
  std::uint64_t steps = 0, regularizations = 0;
};

/// The azimuthally averaged Sigma / Sigma_0 (the SPH sum on a polar grid, rings bin_width apart, 256
/// azimuths) and its minimum near the orbit, 0.8 <= r <= 1.2: the gap depth.
struct DiskProfile {
  std::vector<double> r, sigma;
  double gap_depth = 0.0;
};

/// The profile from `sigma_at`, Sigma at a list of points (the SPH sum over the whole gas).
template <class SigmaAt>
DiskProfile disk_profile_from(SigmaAt&& sigma_at, const PlanetDiskParams& s) {
  const auto n_r = static_cast<std::size_t>(std::ceil((s.r_out - s.r_in) / s.bin_width - 1e-9));
  const paper::PolarGrid grid{s.r_in, s.r_out, 0.0, n_r, 256};
  const auto mean = paper::azimuthal_average(grid, sigma_at(grid.points()));
  DiskProfile out;
  out.gap_depth = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n_r; ++i) {
    out.r.push_back(grid.r(i));
    out.sigma.push_back(mean[i] / s.sigma0);
    if (grid.r(i) >= 0.8 && grid.r(i) <= 1.2) out.gap_depth = std::min(out.gap_depth, mean[i] / s.sigma0);
  }
  return out;
}
/// The profile of the particles `p` (2D, or seen from above), the whole gas.
template <class P>
DiskProfile disk_profile(const P& p, const PlanetDiskParams& s) {
  return disk_profile_from(
      [&](const std::vector<Vec<2>>& points) { return analysis::interpolate_density<kernel::CubicSpline>(p, points); },
      s);
}

struct DiskRun : examples::RunCost {
  std::vector<DiskSample> samples;
  double remap_seconds = 0.0;   ///< the remaps alone; the rest of the regularization time is the schedule's check
  double output_seconds = 0.0;  ///< measurements (Sigma on the polar grid, mass) and what on_sample writes
  double mass_initial = 0.0, mass_final = 0.0, mass_removed = 0.0, max_mass_error = 0.0;
  std::size_t particles_removed = 0;
};

namespace detail {

/// The measuring times: every measure_every orbits, the last at the end of the run.
inline std::vector<examples::AtTime> disk_stops(const PlanetDiskParams& s) {
  const double period = s.period(), t_end = s.orbits * period;
  std::vector<examples::AtTime> stops;
  for (int k = 1;; ++k) {
    stops.push_back({std::min(t_end, k * s.measure_every * period)});
    if (stops.back().t >= t_end * (1.0 - 1e-14)) return stops;
  }
}

/// The run's samples and running figures in a checkpoint (the rest follows from the parameters).
inline void checkpoint_disk_run(io::Archive& ar, DiskRun& r) {
  ar.records("samples", r.samples, [](io::Archive& a, DiskSample& d) {
    a("orbit", d.orbit);
    a("time", d.time);
    a("mass", d.mass);
    a("mass_removed", d.mass_removed);
    a("gap_depth", d.gap_depth);
    a("wall_seconds", d.wall_seconds);
    a("particles", d.particles);
    a("steps", d.steps);
    a("regularizations", d.regularizations);
  });
  ar("mass_removed", r.mass_removed);
  ar("particles_removed", r.particles_removed);
  ar("max_mass_error", r.max_mass_error);
  ar("output_seconds", r.output_seconds);
}

template <class Sim, class OnStep, class OnSample>
DiskRun run_disk(Sim& sim, const PlanetDiskParams& s, OnStep&& on_step, OnSample&& on_sample,
                 examples::Checkpoints* checkpoints) {
  DiskRun r;
  const auto part = examples::add_part(checkpoints, "disk", [&](io::Archive& ar) { checkpoint_disk_run(ar, r); });
  r.mass_initial = sim.totals().mass;
  const double period = s.period();
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  // Gas that leaves the disk by more than a lattice spacing is gone: removed and counted.
  const double r_lo = s.r_in - s.spacing(), r_hi = s.r_out + s.spacing();
  auto after_step = [&](Sim& sm) {
    r.mass_removed += examples::remove_particles(
        sm,
        [&](const Vec<Sim::dim>& x) {
          const double R2 = x.template head<2>().squaredNorm();  // from the centre, in 3D from the z axis
          return R2 < r_lo * r_lo || R2 > r_hi * r_hi;
        },
        r.particles_removed);
    on_step(sm);
  };
  auto sample = [&](const Sim& sm, int) {
    const double t_sample = elapsed();
    DiskSample d;
    d.time = sm.time();
    d.orbit = sm.time() / period;
    d.mass = sm.totals().mass;
    d.mass_removed = r.mass_removed;
    const auto& own = seen_from_above(sm.particles());
    d.gap_depth = disk_profile_from(examples::density_over_ranks<kernel::CubicSpline>(sm, own), s).gap_depth;
    d.particles = examples::count_over_ranks(sm, sm.particles().n_real);
    d.steps = sm.steps();
    d.regularizations = sm.regularizations();
    d.wall_seconds = elapsed();
    r.max_mass_error = std::max(r.max_mass_error, std::abs(d.mass + r.mass_removed - r.mass_initial) / r.mass_initial);
    r.samples.push_back(d);
    on_sample(sm, r.samples.back());
    r.output_seconds += elapsed() - t_sample;
  };
  static_cast<examples::RunCost&>(r) = examples::run_stops(sim, disk_stops(s), after_step, sample, checkpoints);
  r.mass_final = sim.totals().mass;
  if constexpr (requires { sim.regularizer().log(); })
    for (const auto& record : sim.regularizer().log()) r.remap_seconds += record.seconds;
  return r;
}

}  // namespace detail

/// The scene's methods: RSPH with Appendix A's schedule and the annulus closing the edge cells (on the rings
/// lattice the edges are rings, whose cells take in what lies beyond: no region; an artificial viscosity with
/// Balsara's switch, off unless asked for), and equal-mass grad-h SPH with artificial viscosity; both with the star and
/// planet and the boundary zones; with any kernel (the cubic spline by default; the measurements take the cubic spline
/// whatever the run's).
template <class Lattice>
using DiskRegion = std::conditional_t<PerSiteLattice<Lattice>, region::Unbounded, region::Annulus>;
template <class Lattice, class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline>
using DiskRegularizer = regularize::LatticeRegularizer<Lattice, schedule::Adaptive<Kernel, 2>, geometry::LocalVoronoi,
                                                       DiskRegion<Lattice>, Order>;
/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <class Lattice, class EOS, class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline,
          class... Extra>
using RsphDisk = Simulation<2, Kernel, EOS, DiskRegularizer<Lattice, Order, Kernel>, paper::StarAndPlanet,
                            paper::KeplerianZones, paper::DampingZones, physics::SwitchedViscosity, Extra...>;
template <class EOS, class Kernel = kernel::CubicSpline, class... Extra>
using SphDisk = Simulation<2, Kernel, EOS, regularize::None, physics::GradH<2>, physics::ArtificialViscosity,
                           paper::StarAndPlanet, paper::KeplerianZones, paper::DampingZones, Extra...>;

inline TimeStepParams disk_time_steps(const PlanetDiskParams& s) {
  TimeStepParams ts;
  ts.courant = s.courant;
  ts.force = s.force;
  if (s.rsph()) ts.max_bin = s.max_bin;
  return ts;
}

template <class Lattice>
DiskRegion<Lattice> disk_region(const PlanetDiskParams& s) {
  if constexpr (PerSiteLattice<Lattice>)
    return {};
  else
    return region::Annulus{s.r_in, s.r_out};
}

template <class Kernel = kernel::CubicSpline, class Lattice, class EOS, class Order = regularize::FirstOrder,
          class... Extra>
RsphDisk<Lattice, EOS, Order, Kernel, Extra...> make_rsph_disk(const PlanetDiskParams& s, const Lattice& lat, EOS eos,
                                                               Order order = {}, Extra... extra) {
  // Edge cells are closed at 0.75 Delta along the edge and by the disk's circles across it, and a new
  // cell less than half covered hands its share on: the edges stay where the disk ends.
  const regularize::RemapParams remap{s.h_over_dx, 0.5, 0.75 / s.h_over_dx, 1e-6};
  DiskRegularizer<Lattice, Order, Kernel> reg(
      lat, schedule::Adaptive<Kernel, 2>{s.N_min, s.N_max, s.dN_max, static_cast<std::uint64_t>(s.max_steps)},
      {.remap = remap, .region = disk_region<Lattice>(s), .order = order});
  return RsphDisk<Lattice, EOS, Order, Kernel, Extra...>(disk_particles_on<Kernel>(s, lat), s.box(), std::move(eos),
                                                         std::move(reg), disk_time_steps(s), s.star_planet(), s.zones(),
                                                         s.damping(), s.rsph_viscosity(), std::move(extra)...);
}

template <class Kernel = kernel::CubicSpline, class Lattice, class EOS, class... Extra>
SphDisk<EOS, Kernel, Extra...> make_sph_disk(const PlanetDiskParams& s, const Lattice& lat, EOS eos, Extra... extra) {
  return SphDisk<EOS, Kernel, Extra...>(disk_particles_on<Kernel>(s, lat), s.box(), std::move(eos), {},
                                        disk_time_steps(s), physics::GradH<2>{s.h_over_dx},
                                        physics::ArtificialViscosity{s.alpha, s.beta}, s.star_planet(), s.zones(),
                                        s.damping(), std::move(extra)...);
}

/// The 3D disk's methods: RSPH on the cubic lattice inside the flared disk, and equal-mass grad-h SPH.
using Disk3EOS = eos::LocallyIsothermal<DiskSoundSpeed>;
template <class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline>
using DiskRegularizer3 =
    regularize::LatticeRegularizer<lattice::Cubic, schedule::Adaptive<Kernel, 3>, geometry::DefaultCellBuilder<3>::type,
                                   region::FlaredDisk, Order>;
template <class Order = regularize::FirstOrder, class Kernel = kernel::CubicSpline, class... Extra>
using RsphDisk3 = Simulation<3, Kernel, Disk3EOS, DiskRegularizer3<Order, Kernel>, paper::StarAndPlanet,
                             paper::KeplerianZones, paper::DampingZones, Extra...>;
template <class Kernel = kernel::CubicSpline, class... Extra>
using SphDisk3 = Simulation<3, Kernel, Disk3EOS, regularize::None, physics::GradH<3>, physics::ArtificialViscosity,
                            paper::StarAndPlanet, paper::KeplerianZones, paper::DampingZones, Extra...>;

/// RSPH in 3D: Appendix A's schedule with the bounds of the paper's h/Delta (0.9 and 3.0 on the lattice, which
/// give its N_min = 4.5 and N_max = 107 in 2D), edge cells closed by the flared disk's cylinders and cones.
template <class Kernel = kernel::CubicSpline, class Order = regularize::FirstOrder, class... Extra>
RsphDisk3<Order, Kernel, Extra...> make_rsph_disk_3d(const PlanetDiskParams& s, Order order = {}, Extra... extra) {
  s.validate();
  const double dx = s.spacing(), slope = s.surface * s.aspect;
  const Box<3> box = disk_box_3d(s.r_out, dx);
  const regularize::RemapParams remap{s.h_over_dx, 0.5, 0.75 / s.h_over_dx, 1e-6};
  DiskRegularizer3<Order, Kernel> reg(
      lattice::Cubic{dx},
      schedule::Adaptive<Kernel, 3>::for_h_over_dx(0.9, 3.0, s.dN_max, static_cast<std::uint64_t>(s.max_steps)),
      {.remap = remap, .region = region::FlaredDisk{s.r_in, s.r_out, slope}, .order = order});
  auto p = flared_disk_lattice(box, dx, s.h(), s.r_in, s.r_out, slope, s.vertical(), s.sigma0, s.zones());
  require(p.n_real > 0, "planet disk: the flared disk holds no lattice site");
  return RsphDisk3<Order, Kernel, Extra...>(std::move(p), box, Disk3EOS(DiskSoundSpeed{s.aspect, 1.0}), std::move(reg),
                                            disk_time_steps(s), s.star_planet(), s.zones(), s.damping(),
                                            std::move(extra)...);
}

template <class Kernel = kernel::CubicSpline, class... Extra>
SphDisk3<Kernel, Extra...> make_sph_disk_3d(const PlanetDiskParams& s, Extra... extra) {
  s.validate();
  const double dx = s.spacing();
  auto p = flared_disk_columns(s.box(), dx, s.sph_column_particles(), s.h_over_dx, s.r_in, s.r_out, s.vertical(),
                               s.sigma0, s.zones());
  require(p.n_real > 0, "planet disk: the disk holds no column");
  return SphDisk3<Kernel, Extra...>(std::move(p), disk_box_3d(s.r_out, dx), Disk3EOS(DiskSoundSpeed{s.aspect, 1.0}), {},
                                    disk_time_steps(s), physics::GradH<3>{s.h_over_dx},
                                    physics::ArtificialViscosity{s.alpha, s.beta}, s.star_planet(), s.zones(),
                                    s.damping(), std::move(extra)...);
}

namespace detail {

/// Either method on the ranks of mpiexec where built with MPI (examples::with_ranks).
template <class Kernel, class Run>
auto with_method_3d(const PlanetDiskParams& s, Run&& run) {
  return examples::with_ranks<3>([&](auto... domain) {
    if (s.rsph())
      return examples::with_remap(s.remap, [&](auto order) {
        auto sim = make_rsph_disk_3d<Kernel>(s, order, domain...);
        return run(sim);
      });
    auto sim = make_sph_disk_3d<Kernel>(s, domain...);
    return run(sim);
  });
}

/// Either method on the ranks of mpiexec where built with MPI.
template <class Kernel, class Lattice, class EOS, class Run>
auto with_method(const PlanetDiskParams& s, const Lattice& lat, EOS eos, Run&& run) {
  auto on = [&](auto... domain) {
    if (s.rsph())
      return examples::with_remap(s.remap, [&](auto order) {
        auto sim = make_rsph_disk<Kernel>(s, lat, eos, order, domain...);
        return run(sim);
      });
    auto sim = make_sph_disk<Kernel>(s, lat, eos, domain...);
    return run(sim);
  };
  return examples::with_ranks<2>(on);
}

/// with_method on the scene's lattice.
template <class Kernel, class EOS, class Run>
auto on_lattice(const PlanetDiskParams& s, EOS eos, Run&& run) {
  return with_disk_lattice(s, [&](const auto& lat) { return with_method<Kernel>(s, lat, eos, run); });
}

}  // namespace detail

/// Runs the disk; on_step(sim) after each step, on_sample(sim, sample) at the start and every
/// measure_every orbits (the last at the end of the run); with checkpoints, as they say (and on resume from
/// the last one).
template <class Kernel = kernel::CubicSpline, class OnStep, class OnSample>
DiskRun run_planet_disk(const PlanetDiskParams& s, OnStep&& on_step, OnSample&& on_sample,
                        examples::Checkpoints* checkpoints = nullptr) {
  s.validate();
  const DiskSoundSpeed cs{s.aspect, 1.0};
  auto run = [&](auto& sim) { return detail::run_disk(sim, s, on_step, on_sample, checkpoints); };
  if (s.dim == 3) return detail::with_method_3d<Kernel>(s, run);
  if (s.eos == "polytropic")
    return detail::on_lattice<Kernel>(
        s, eos::Polytropic<DiskPolytropicK>(s.gamma, DiskPolytropicK{cs, s.gamma, s.sigma0}), run);
  return detail::on_lattice<Kernel>(s, eos::LocallyIsothermal<DiskSoundSpeed>(cs), run);
}

}  // namespace rsph::scenes
