#pragma once
// §3.1 of the paper: an isothermal linear sound wave in a periodic 2D box of 2 x 0.5 wavelengths,
// equal-mass particles on a Cartesian lattice displaced for a 0.1 % density amplitude.
#include "common/runner.hpp"
#include "linear_wave/analysis.hpp"
#include "rsph/rsph.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace rsph::scenes {

struct LinearWaveParams {
  int wavelength_cells = 24;  ///< lambda / Delta
  double amplitude = 1e-3;    ///< delta rho / rho
  double h_over_dx = 1.2;
  double cs = 1.0;  ///< isothermal sound speed; lambda = 1, so P_w = 1 / cs
  int periods = 100;
  double courant = 0.3;
  double jitter = 0.0;          ///< random displacement in units of Delta, to seed instabilities
  double r = 4.25;              ///< RSPH: T_reg / P_w (0: plain SPH; the default is Fig. 3's longest cycle)
  std::string remap = "first";  ///< RSPH: the remap's order, first (eqs. 6-9) or second
  double alpha = 0.0;           ///< plain SPH: artificial viscosity alpha, beta = 2 alpha

  void validate() const {
    examples::check_remap(remap);
    require(wavelength_cells >= 4 && wavelength_cells % 2 == 0,
            "linear wave: lambda/Delta must be an even number >= 4");
    require(h_over_dx > 0.0, "linear wave: h/Delta must be positive (got " + std::to_string(h_over_dx) + ")");
    require(amplitude > 0.0 && amplitude < 0.1, "linear wave: the amplitude must be small and positive");
    require(periods >= 2, "linear wave: run at least two periods");
    require(r >= 0.0, "linear wave: r = T_reg / P_w must be non-negative");
    require(alpha >= 0.0, "linear wave: alpha must be non-negative");
  }
  double spacing() const { return 1.0 / wavelength_cells; }
  double period() const { return 1.0 / cs; }
  Box<2> box() const {
    Box<2> b;
    b.hi = Vec<2>(2.0, 0.5);
    b.edge = {Edge::periodic, Edge::periodic};
    return b;
  }
};

/// Equal masses on the lattice, displaced by xi = -(A / k) sin(k x0) so rho = rho0 (1 + A cos kx);
/// v = A c cos(k x): a wave travelling in +x. `perturbed = false` gives the bare lattice (no wave, no jitter).
inline ParticleSet<2, false> linear_wave_particles(const LinearWaveParams& s, bool perturbed = true) {
  s.validate();
  const double dx = s.spacing(), k = 2.0 * std::numbers::pi;
  const double A = perturbed ? s.amplitude : 0.0, jitter = perturbed ? s.jitter : 0.0;
  const int nx = 2 * s.wavelength_cells, ny = s.wavelength_cells / 2;
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<2, false> p;
  p.reserve(static_cast<std::size_t>(nx) * ny);
  const Box<2> box = s.box();
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x0 = (i + 0.5) * dx, y0 = (j + 0.5) * dx;
      Vec<2> x(x0 - A / k * std::sin(k * x0) + jitter * dx * u(rng), y0 + jitter * dx * u(rng));
      box.wrap(x);
      p.add(dx * dx, x, Vec<2>(A * s.cs * std::cos(k * x0), 0.0), s.h_over_dx * dx);
    }
  return p;
}

/// SPH interpolation of the density at a fixed point (the sensor of §3.1), periodic images included.
template <class Kernel, class P>
double sensor_density(const P& p, const Box<2>& box, const Vec<2>& at) {
  double rho = 0.0;
  for (std::size_t b = 0; b < p.n_real; ++b) {
    const Vec<2> r = box.separation(at, p.x[b]);
    const double reach = Kernel::support * p.h[b];
    if (r.squaredNorm() < reach * reach) rho += p.m[b] * kernel::W<Kernel, 2>(r.norm(), p.h[b]);
  }
  return rho;
}

struct LinearWaveResult : examples::RunCost {
  std::vector<double> t, delta_rho;
  double gamma = 0.0, phase_error = 0.0;
  double noise_initial = 0.0, noise_final = 0.0;  ///< rms transverse velocity over c A, after one period and at the end
  double amplitude_growth = 0.0;                  ///< S_{N-1} / S_0
  double dissipated = 0.0;                        ///< kinetic energy the remaps removed (no u to put it in)
};

namespace detail {
/// The rms of v_y over every rank's particles.
template <class Sim>
double transverse_noise(const Sim& sim) {
  std::array<double, 2> sums{};  // sum of v_y^2, count
  const auto& p = sim.particles();
  for (std::size_t a = 0; a < p.n_real; ++a) sums[0] += p.v[a][1] * p.v[a][1];
  sums[1] = static_cast<double>(p.n_real);
  examples::sum_over_ranks(sim, sums);
  return std::sqrt(sums[0] / sums[1]);
}

/// The sensor's density, summed over every rank's particles.
template <class Kernel, class Sim>
double sensor_density_of(const Sim& sim, const Box<2>& box, const Vec<2>& at) {
  std::array<double, 1> rho{sensor_density<Kernel>(sim.particles(), box, at)};
  examples::sum_over_ranks(sim, rho);
  return rho[0];
}
}  // namespace detail

/// The scene's methods: RSPH regularized every r wave periods, and plain SPH with artificial viscosity.
template <class Order = regularize::FirstOrder>
using WaveRegularizer =
    regularize::LatticeRegularizer<lattice::Square, schedule::EveryT, geometry::LocalVoronoi, region::Unbounded, Order>;
/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <class Kernel, class Order = regularize::FirstOrder, class... Extra>
using RsphWave = Simulation<2, Kernel, eos::Isothermal, WaveRegularizer<Order>, Extra...>;
template <class Kernel, class... Extra>
using SphWave = Simulation<2, Kernel, eos::Isothermal, regularize::None, physics::ArtificialViscosity, Extra...>;

inline TimeStepParams wave_time_steps(const LinearWaveParams& s) {
  TimeStepParams ts;
  ts.courant = s.courant;
  return ts;
}

template <class Kernel, class Order = regularize::FirstOrder, class... Extra>
RsphWave<Kernel, Order, Extra...> make_rsph_wave(const LinearWaveParams& s, Order order = {}, Extra... extra) {
  return RsphWave<Kernel, Order, Extra...>(
      linear_wave_particles(s), s.box(), eos::Isothermal{s.cs},
      WaveRegularizer<Order>(lattice::Square{s.spacing()}, schedule::EveryT{s.r * s.period()},
                             {.remap = {s.h_over_dx}, .order = order}),
      wave_time_steps(s), std::move(extra)...);
}

template <class Kernel, class... Extra>
SphWave<Kernel, Extra...> make_sph_wave(const LinearWaveParams& s, Extra... extra) {
  return SphWave<Kernel, Extra...>(linear_wave_particles(s), s.box(), eos::Isothermal{s.cs}, regularize::None{},
                                   wave_time_steps(s), physics::ArtificialViscosity{s.alpha, 2.0 * s.alpha},
                                   std::move(extra)...);
}

/// Runs a simulation of the scene for `periods` periods (examples::run_stops), sampling the sensor every
/// step, and measures gamma (eq. 11), the phase error and the noise; on_step(sim) after each step,
/// at_stop(sim, k) at the start (k = -1) and at the end (k = 0).
template <class Kernel, class Sim, class OnStep, class AtStop>
LinearWaveResult run_wave(Sim& sim, const LinearWaveParams& s, OnStep&& on_step, AtStop&& at_stop,
                          examples::Checkpoints* checkpoints) {
  const Box<2> box = s.box();
  const Vec<2> sensor(0.5 * s.spacing(), 0.25);  // on a lattice column, mid-height
  // The reference density: the sensor on the unperturbed lattice (removes the lattice-sum bias).
  const double rho_ref = sensor_density<Kernel>(linear_wave_particles(s, false), box, sensor);
  LinearWaveResult res;
  auto record = [&](const auto& sm) {
    res.t.push_back(sm.time());
    res.delta_rho.push_back(detail::sensor_density_of<Kernel>(sm, box, sensor) - rho_ref);
  };
  record(sim);
  bool early_noted = false;
  const auto part = examples::add_part(checkpoints, "linear_wave", [&](io::Archive& ar) {
    ar("t", res.t);
    ar("delta_rho", res.delta_rho);
    ar("noise_initial", res.noise_initial);
    ar("early_noted", early_noted);
  });
  static_cast<examples::RunCost&>(res) = examples::run_stops(
      sim, examples::at_times({s.periods * s.period()}),
      [&](const auto& sm) {
        record(sm);
        if (!early_noted && sm.time() >= s.period()) {  // after one period: the seeded noise has spread
          res.noise_initial = detail::transverse_noise(sm) / (s.amplitude * s.cs);
          early_noted = true;
        }
        on_step(sm);
      },
      at_stop, checkpoints);
  res.noise_final = detail::transverse_noise(sim) / (s.amplitude * s.cs);
  res.gamma = analysis::damping_rate(res.t, res.delta_rho, s.period(), s.periods);
  res.phase_error = analysis::phase_error(res.t, res.delta_rho, s.period());
  std::vector<double> S(2, 0.0);
  for (std::size_t i = 0; i < res.t.size(); ++i) {
    const double k = std::floor(res.t[i] / s.period());
    if (k == 0) S[0] = std::max(S[0], std::abs(res.delta_rho[i]));
    if (k == s.periods - 1) S[1] = std::max(S[1], std::abs(res.delta_rho[i]));
  }
  res.amplitude_growth = S[1] / S[0];
  res.dissipated = sim.kinetic_energy_removed();
  return res;
}

/// Runs RSPH when r > 0, else plain SPH, on the ranks of mpiexec where built with MPI (examples::with_ranks).
template <class Kernel, class OnStep, class AtStop = examples::NoHook>
LinearWaveResult run_linear_wave(const LinearWaveParams& s, OnStep&& on_step, AtStop&& at_stop = {},
                                 examples::Checkpoints* checkpoints = nullptr) {
  return examples::with_ranks<2>([&](auto... domain) {
    if (s.r > 0.0)
      return examples::with_remap(s.remap, [&](auto order) {
        auto sim = make_rsph_wave<Kernel>(s, order, domain...);
        return run_wave<Kernel>(sim, s, on_step, at_stop, checkpoints);
      });
    auto sim = make_sph_wave<Kernel>(s, domain...);
    return run_wave<Kernel>(sim, s, on_step, at_stop, checkpoints);
  });
}

}  // namespace rsph::scenes
