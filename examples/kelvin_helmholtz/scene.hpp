#pragma once
// §3.3 of the paper: Kelvin-Helmholtz instability at density ratio 10 (Agertz et al. 2007 setup):
// (-0.5, 0.5) x (0, 0.5), periodic in x, reflecting walls at y = 0 and 0.5; rho = 10 above y = 0.25 and
// 1 below; P = 2.5; gamma = 5/3; v_x = 0.5 below, -0.5 above; v_y = A sin(-k (x + 0.5)) within 0.025 of
// the interface, A = 0.025, k = 12 pi; no artificial viscosity. The box holds six wavelengths of the seeded
// mode; `wavelengths` narrows it (periodic, so one wavelength evolves the seeded mode alike at a sixth of the cost).
// In 3D the layer is extruded along z over `depth` lattice spacings, periodic in z.
#include "common/blocks.hpp"
#include "common/runner.hpp"
#include "rsph/rsph.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::scenes {

struct KelvinHelmholtzParams {
  int cells = 256;  ///< 1 / Delta (RSPH lattice; SPH's low-density spacing)
  double h_over_dx = 1.2;
  std::uint64_t reg_steps = 48;
  double alpha_u = 0.0;  ///< artificial conductivity (0: off)
  double chi = 10.0;     ///< density ratio
  double P = 2.5, gamma = 5.0 / 3.0, dv = 1.0;
  double A = 0.025, k = 12.0 * std::numbers::pi, layer = 0.025;
  double t_end = 0.0;  ///< 0: tau_KH
  double courant = 0.3;
  int wavelengths = 6;  ///< box width in wavelengths 2 pi / k of the seeded mode (6: the paper's -0.5 < x < 0.5)
  int depth = 8;        ///< 3D: the box's depth along z in lattice spacings (periodic)
  std::string remap = "first";  ///< RSPH: the remap's order, first (eqs. 6-9) or second

  /// Lattice columns across the box: the box is columns() * Delta wide.
  int columns() const { return static_cast<int>(std::lround(cells * wavelengths * 2.0 * std::numbers::pi / k)); }
  void validate() const {
    require(cells >= 16 && cells % 2 == 0,
            "Kelvin-Helmholtz: need an even number of cells >= 16 (got " + std::to_string(cells) + ")");
    require(wavelengths >= 1 && wavelengths <= 6,
            "Kelvin-Helmholtz: the box holds 1 to 6 wavelengths (got " + std::to_string(wavelengths) + ")");
    require(std::abs(cells * wavelengths * 2.0 * std::numbers::pi / k - columns()) < 1e-6,
            "Kelvin-Helmholtz: " + std::to_string(wavelengths) + " wavelengths of 1/6 must span a whole number of " +
                "lattice spacings 1/" + std::to_string(cells) + " (take --cells a multiple of 6)");
    require(h_over_dx > 0.0, "Kelvin-Helmholtz: h/Delta must be positive (got " + std::to_string(h_over_dx) + ")");
    require(chi >= 1.0, "Kelvin-Helmholtz: the density ratio must be >= 1");
    require(reg_steps >= 1, "Kelvin-Helmholtz: regularize at least every step");
    require(depth >= 2, "Kelvin-Helmholtz: the 3D box needs a depth of at least 2 spacings");
    require(alpha_u >= 0.0, "Kelvin-Helmholtz: alpha_u must be non-negative");
    require(A >= 0.0, "Kelvin-Helmholtz: the seed amplitude must be non-negative");
    examples::check_remap(remap);
  }
  /// 2 pi over the incompressible growth rate k dv sqrt(chi) / (1 + chi): 0.58 for the paper's setup.
  double tau_KH() const { return 2.0 * std::numbers::pi / (k * dv * std::sqrt(chi) / (1.0 + chi)); }
  double end_time() const { return t_end > 0.0 ? t_end : tau_KH(); }
  template <int D = 2>
  Box<D> box() const {
    Box<D> b;
    b.lo.setZero();
    b.lo[0] = -0.5;
    b.hi[0] = -0.5 + static_cast<double>(columns()) / cells;
    b.hi[1] = 0.5;
    b.edge[0] = Edge::periodic;
    b.edge[1] = Edge::reflecting;
    if constexpr (D == 3) {
      b.hi[2] = static_cast<double>(depth) / cells;
      b.edge[2] = Edge::periodic;
    }
    return b;
  }
  template <int D>
  Vec<D> velocity(const Vec<D>& x) const {
    Vec<D> v = Vec<D>::Zero();
    v[0] = x[1] < 0.25 ? 0.5 * dv : -0.5 * dv;
    v[1] = std::abs(x[1] - 0.25) < layer ? A * std::sin(-k * (x[0] + 0.5)) : 0.0;
    return v;
  }
};

/// The seeded mode's amplitude (McNally, Lyra & Passy 2012 eqs. 10-13, one interface at y = 0.25):
/// M = 2 sqrt((s/d)^2 + (c/d)^2), s, c = sum V v_y {sin, cos}(k x) e^(-k |y - 0.25|), d = sum V e^(-k |y - 0.25|).
/// The sums {s, c, d} over a set of particles, and M from them (summed over ranks between the two).
template <class P>
std::array<double, 3> mode_sums(const P& p, double k) {
  std::array<double, 3> sums{};
  auto& [s, c, d] = sums;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const double V = p.m[a] / p.rho[a];
    const double w = V * std::exp(-k * std::abs(p.x[a][1] - 0.25));
    s += w * p.v[a][1] * std::sin(k * p.x[a][0]);
    c += w * p.v[a][1] * std::cos(k * p.x[a][0]);
    d += w;
  }
  return sums;
}
inline double mode_amplitude(const std::array<double, 3>& sums) {
  const auto [s, c, d] = sums;
  return 2.0 * std::sqrt((s / d) * (s / d) + (c / d) * (c / d));
}
template <class P>
double mode_amplitude(const P& p, double k) {
  return mode_amplitude(mode_sums(p, k));
}

/// Momentum thickness of the shear layer, theta = integral of (1/4 - (<v_x> / dv)^2) dy with <v_x> the
/// volume-weighted mean over rows Delta high: 0 for the sharp initial layer, delta / 2 for a layer
/// (dv / 2) tanh(y / delta). What the flow's own mixing and the method's dissipation have widened it to.
/// The rows' sums of V and V v_x (rows first), and theta from them.
template <class P>
std::vector<double> layer_sums(const P& p, const KelvinHelmholtzParams& s) {
  const Box<2> box = s.box();  // the rows along y, in 2D and 3D alike
  const auto rows = static_cast<std::size_t>(s.cells / 2);
  const double dy = box.size()[1] / static_cast<double>(rows);
  std::vector<double> sums(2 * rows, 0.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const auto row = std::min(rows - 1, static_cast<std::size_t>(std::max(0.0, (p.x[a][1] - box.lo[1]) / dy)));
    const double vol = p.m[a] / p.rho[a];
    sums[row] += vol;
    sums[rows + row] += vol * p.v[a][0];
  }
  return sums;
}
inline double momentum_thickness(const std::vector<double>& sums, const KelvinHelmholtzParams& s) {
  const std::size_t rows = sums.size() / 2;
  const double dy = s.box().size()[1] / static_cast<double>(rows);
  double theta = 0.0;
  for (std::size_t j = 0; j < rows; ++j)
    if (sums[j] > 0.0) theta += (0.25 - std::pow(sums[rows + j] / (sums[j] * s.dv), 2)) * dy;
  return theta;
}

/// RSPH: a square (cubic) lattice; masses give rho through the lattice sum.
template <int D = 2, class Kernel = kernel::CubicSpline>
ParticleSet<D, true> kh_lattice(const KelvinHelmholtzParams& s, double h_over_dx) {
  s.validate();
  const double dx = 1.0 / s.cells;
  const eos::IdealGas gas{s.gamma};
  const double bias = kernel::lattice_sum<Kernel, D>(h_over_dx);
  ParticleSet<D, true> p;
  Vec<D> lo = Vec<D>::Zero();
  lo[0] = -0.5;
  examples::for_each_block_site<D>({s.columns(), s.cells / 2, s.depth}, lo, Vec<D>::Constant(dx),
                                   [&](const Vec<D>& x, auto) {
                                     const double rho = x[1] > 0.25 ? s.chi : 1.0;
                                     const double m = D == 2 ? rho * dx * dx / bias : rho * dx * dx * dx / bias;
                                     p.add(m, x, s.velocity(x), h_over_dx * dx, gas.internal_energy(rho, s.P));
                                   });
  return p;
}

/// Plain SPH: equal masses, spacing Delta below and Delta / chi^(1/D) above (rounded to tile the box; in 3D
/// along z too).
template <int D = 2, class Kernel = kernel::CubicSpline>
ParticleSet<D, true> kh_equal_mass(const KelvinHelmholtzParams& s) {
  s.validate();
  const eos::IdealGas gas{s.gamma};
  const auto size = s.box<D>().size();
  ParticleSet<D, true> p;
  auto block = [&](double rho, double y0, double y1, int nx) {
    const double dx = size[0] / nx;
    const int ny = std::max(1, static_cast<int>(std::lround((y1 - y0) / dx)));
    const int nz = D == 3 ? std::max(1, static_cast<int>(std::lround(size[D - 1] / dx))) : 1;
    const double dy = (y1 - y0) / ny, dz = D == 3 ? size[D - 1] / nz : 1.0;
    const double bias = kernel::lattice_sum<Kernel, D>(s.h_over_dx);
    const double vol = dx * dy * dz;
    Vec<D> lo = Vec<D>::Zero(), spacing = Vec<D>::Constant(dz);
    lo[0] = -0.5;
    lo[1] = y0;
    spacing[0] = dx;
    spacing[1] = dy;
    examples::for_each_block_site<D>({nx, ny, nz}, lo, spacing, [&](const Vec<D>& x, auto) {
      p.add(rho * dx * dy * dz / bias, x, s.velocity(x), s.h_over_dx * (D == 2 ? std::sqrt(dx * dy) : std::cbrt(vol)),
            gas.internal_energy(rho, s.P));
    });
  };
  block(1.0, 0.0, 0.25, s.columns());
  const double ratio = D == 2 ? std::sqrt(s.chi) : std::cbrt(s.chi);  // equal masses: chi^(1/D) more per axis
  block(s.chi, 0.25, 0.5, static_cast<int>(std::lround(s.columns() * ratio)));
  return p;
}

/// The interface rho = sqrt(chi) (between the phases' densities on a log scale), sampled at Delta / 4.
template <class P>
analysis::InterfaceFolds interface_folds(const P& p, const KelvinHelmholtzParams& s) {
  return analysis::interface_folds<kernel::CubicSpline>(p, s.box(), std::sqrt(s.chi), 0.25 / s.cells);
}

/// The same of a simulation, made on its particles gathered on rank 0 and sent to every rank.
template <class Sim>
analysis::InterfaceFolds measure_folds(const Sim& sim, const KelvinHelmholtzParams& s) {
  decltype(auto) whole = examples::particles_on_root(sim);
  const auto f = examples::measured_on_root(sim, whole, [&](const auto& all) {
    const auto folds = interface_folds(all, s);
    return std::array{static_cast<double>(folds.columns), static_cast<double>(folds.rows), folds.overturned_fraction,
                      folds.mean_crossings};
  });
  return {static_cast<std::size_t>(f[0]), static_cast<std::size_t>(f[1]), f[2], f[3]};
}

/// How a method treats the contact between the phases, the failure of plain SPH at chi = 10 that Agertz et
/// al. (2007, the gap between the phases) and Price (2008, the pressure blip of a temperature jump without
/// conductivity) describe: the share of the box's area at densities between the phases' (1.5 < rho <
/// chi / 1.5: mixed gas), and the mass-weighted rms of P / P_0 - 1 (0 where pressure stays uniform).
struct ContactMeasures {
  double mixed_area = 0.0, pressure_error = 0.0;
};

/// {area, mixed area, mass, mass-weighted squares of P / P_0 - 1} over a set of particles.
template <class P>
std::array<double, 4> contact_sums(const P& p, const KelvinHelmholtzParams& s) {
  std::array<double, 4> sums{};
  auto& [area, mixed, mass, squares] = sums;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const double V = p.m[a] / p.rho[a], dp = p.P[a] / s.P - 1.0;
    area += V;
    if (p.rho[a] > 1.5 && p.rho[a] < s.chi / 1.5) mixed += V;
    mass += p.m[a];
    squares += p.m[a] * dp * dp;
  }
  return sums;
}

/// The scene's measures of a simulation, its particles' sums taken over every rank.
template <class Sim>
double measure_amplitude(const Sim& sim, const KelvinHelmholtzParams& s) {
  auto sums = mode_sums(sim.particles(), s.k);
  examples::sum_over_ranks(sim, sums);
  return mode_amplitude(sums);
}
template <class Sim>
double measure_thickness(const Sim& sim, const KelvinHelmholtzParams& s) {
  auto sums = layer_sums(sim.particles(), s);
  examples::sum_over_ranks(sim, sums);
  return momentum_thickness(sums, s);
}
template <class Sim>
ContactMeasures measure_contact(const Sim& sim, const KelvinHelmholtzParams& s) {
  auto sums = contact_sums(sim.particles(), s);
  examples::sum_over_ranks(sim, sums);
  const auto [area, mixed, mass, squares] = sums;
  return {mixed / area, std::sqrt(squares / mass)};
}

struct KhRun : examples::RunCost {
  std::vector<double> t, amplitude, thickness;  ///< per step: time, mode amplitude, momentum thickness
  double seed = 0.0, amplitude_final = 0.0, growth_rate = 0.0;
  double energy_error = 0.0;
  /// At the end: how far the interface has rolled up (with two phases, chi > 1).
  std::optional<analysis::InterfaceFolds> folds;
  ContactMeasures contact;  ///< at the end
};

/// Least-squares slope of ln M over [t0, t1]: the growth rate of the linear phase.
inline double fitted_growth_rate(const std::vector<double>& t, const std::vector<double>& M, double t0, double t1) {
  std::vector<double> x, y;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t0 || t[i] > t1 || !(M[i] > 0.0)) continue;
    x.push_back(t[i]);
    y.push_back(std::log(M[i]));
  }
  return x.size() >= 2 ? analysis::least_squares_slope(x, y) : 0.0;
}

/// Runs a simulation of the scene to its end time (examples::run_stops), recording the mode amplitude and
/// the momentum thickness after every step; on_step(sim) after each step, on_end(sim) at the end.
template <class Sim, class OnStep, class OnEnd>
KhRun run_kh(Sim& sim, const KelvinHelmholtzParams& s, OnStep&& on_step, OnEnd&& on_end,
             examples::Checkpoints* checkpoints) {
  KhRun r;
  const auto part = examples::add_part(checkpoints, "kelvin_helmholtz", [&](io::Archive& ar) {
    ar("t", r.t);
    ar("amplitude", r.amplitude);
    ar("thickness", r.thickness);
  });
  const double E0 = sim.totals().total_energy();
  auto record = [&](const auto& sm) {
    r.t.push_back(sm.time());
    r.amplitude.push_back(measure_amplitude(sm, s));
    r.thickness.push_back(measure_thickness(sm, s));
  };
  record(sim);
  r.seed = r.amplitude.front();
  static_cast<examples::RunCost&>(r) = examples::run_stops(
      sim, examples::at_times({s.end_time()}),
      [&](const auto& sm) {
        record(sm);
        on_step(sm);
      },
      examples::NoHook{}, checkpoints);
  on_end(sim);
  r.amplitude_final = r.amplitude.back();
  if constexpr (Sim::dim == 2)
    if (s.chi > 1.0) r.folds = measure_folds(sim, s);
  r.contact = measure_contact(sim, s);
  r.growth_rate = fitted_growth_rate(r.t, r.amplitude, 0.1 * s.tau_KH(), 0.5 * s.tau_KH());
  r.energy_error = std::abs(sim.totals().total_energy() - E0) / E0;
  return r;
}

/// The scene's methods: RSPH on the square (cubic) lattice, regularized every reg_steps, and grad-h SPH with
/// equal masses; each with Price's conductivity or without, with any kernel (the cubic spline by default).
template <class Order = regularize::FirstOrder, int D = 2>
using KhRegularizer =
    regularize::LatticeRegularizer<lattice::Cartesian<D>, schedule::EveryNSteps,
                                   typename geometry::DefaultCellBuilder<D>::type, region::Unbounded, Order>;
template <int D, class Kernel, class Order, class... Terms>
using RsphKh = Simulation<D, Kernel, eos::IdealGas, KhRegularizer<Order, D>, Terms...>;
template <int D, class Kernel, class... Terms>
using SphKh = Simulation<D, Kernel, eos::IdealGas, regularize::None, physics::GradH<D>, Terms...>;

inline TimeStepParams kh_time_steps(const KelvinHelmholtzParams& s) {
  TimeStepParams ts;
  ts.courant = s.courant;
  return ts;
}

template <int D = 2, class Kernel = kernel::CubicSpline, class Order, class... Terms>
RsphKh<D, Kernel, Order, Terms...> make_rsph_kh(const KelvinHelmholtzParams& s, Order order, Terms... terms) {
  return RsphKh<D, Kernel, Order, Terms...>(
      kh_lattice<D, Kernel>(s, s.h_over_dx), s.box<D>(), eos::IdealGas{s.gamma},
      KhRegularizer<Order, D>(lattice::Cartesian<D>{1.0 / s.cells}, schedule::EveryNSteps{s.reg_steps},
                              {.remap = {s.h_over_dx}, .order = order}),
      kh_time_steps(s), terms...);
}

template <int D = 2, class Kernel = kernel::CubicSpline, class... Terms>
SphKh<D, Kernel, Terms...> make_sph_kh(const KelvinHelmholtzParams& s, Terms... terms) {
  return SphKh<D, Kernel, Terms...>(kh_equal_mass<D, Kernel>(s), s.box<D>(), eos::IdealGas{s.gamma}, regularize::None{},
                                    kh_time_steps(s), physics::GradH<D>{s.h_over_dx}, terms...);
}

/// Runs one of the variants: RSPH (with either remap) or SPH, with conductivity when alpha_u > 0, on the ranks
/// of mpiexec where built with MPI (examples::with_ranks); with checkpoints, as they say.
template <int D = 2, class Kernel = kernel::CubicSpline, class OnStep, class OnEnd>
KhRun run_kelvin_helmholtz(bool rsph, const KelvinHelmholtzParams& s, OnStep&& on_step, OnEnd&& on_end,
                           examples::Checkpoints* checkpoints = nullptr) {
  auto run = [&](auto sim) { return run_kh(sim, s, on_step, on_end, checkpoints); };
  const physics::ArtificialConductivity conduct{s.alpha_u};
  return examples::with_ranks<D>([&](auto... domain) {
    if (rsph)
      return examples::with_remap(s.remap, [&](auto order) {
        return s.alpha_u > 0 ? run(make_rsph_kh<D, Kernel>(s, order, conduct, domain...))
                             : run(make_rsph_kh<D, Kernel>(s, order, domain...));
      });
    return s.alpha_u > 0 ? run(make_sph_kh<D, Kernel>(s, conduct, domain...))
                         : run(make_sph_kh<D, Kernel>(s, domain...));
  });
}

}  // namespace rsph::scenes
