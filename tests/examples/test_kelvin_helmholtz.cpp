#include "kelvin_helmholtz/scene.hpp"

#include <catch2/catch.hpp>

#include <array>

using namespace rsph;

TEST_CASE("Kelvin-Helmholtz setup: tau_KH = 0.58 and the seeded mode's amplitude", "[kelvin_helmholtz]") {
  scenes::KelvinHelmholtzParams s;
  CHECK(s.tau_KH() == Approx(0.58).margin(0.005));
  s.cells = 512;  // fine enough that the lattice rows resolve the 0.025-wide seeded strip
  auto p = scenes::kh_lattice(s, s.h_over_dx);
  for (std::size_t a = 0; a < p.n_real; ++a) p.rho[a] = p.m[a] * s.cells * s.cells;  // volume Delta^2 each
  // the seed v_y = A sin(-k (x + 0.5)) within 0.025 of the interface: M(0) = A times the weight of the strip
  const double strip = 1.0 - std::exp(-s.k * s.layer);
  CHECK(scenes::mode_amplitude(p, s.k) == Approx(s.A * strip).epsilon(0.03));
  s.cells = 64;
  const auto q = scenes::kh_equal_mass(s);
  double m_min = 1e300, m_max = 0;
  for (double m : q.m) {
    m_min = std::min(m_min, m);
    m_max = std::max(m_max, m);
  }
  CHECK(m_max / m_min < 1.01);  // plain SPH: equal masses across the density jump
}

TEST_CASE("Kelvin-Helmholtz at density ratio 10: RSPH grows the seeded mode", "[kelvin_helmholtz]") {
  scenes::KelvinHelmholtzParams s;
  s.cells = 128;
  const examples::NoHook none;
  const auto rsph = scenes::run_kelvin_helmholtz(true, s, none, none);
  double peak = 0.0;
  for (double a : rsph.amplitude) peak = std::max(peak, a);
  INFO("RSPH: seed " << rsph.seed << ", final " << rsph.amplitude_final << ", peak " << peak << ", growth rate "
                     << rsph.growth_rate << " (linear theory " << 2 * std::numbers::pi / s.tau_KH() << ")");
  CHECK(peak > 3.0 * rsph.seed);
  CHECK(rsph.amplitude_final > 1.5 * rsph.seed);
  CHECK(rsph.growth_rate > 0.4 * 2.0 * std::numbers::pi / s.tau_KH());
  CHECK(rsph.regularizations >= 8);
  // with conductivity the interface mixes and the mode grows further
  s.alpha_u = 1.0;
  const auto cond = scenes::run_kelvin_helmholtz(true, s, none, none);
  CHECK(cond.amplitude_final > rsph.amplitude_final);
}

TEST_CASE(
    "Kelvin-Helmholtz: RSPH's growth converges towards linear theory, 5x the seed and rolled-up billows at "
    "tau_KH by 1/Delta = 516",
    "[kelvin_helmholtz][long]") {
  // At reduced resolution the remap mixes the interface rows (an s (1 - s) / 8 share of each cell per remap,
  // test_remap.cpp) and slows the mode (2x the seed at 1/Delta = 128, 4.5x at the paper's 256); the issue's
  // 5x holds once the interface is resolved. One wavelength of the six: the box is periodic, so the seeded
  // mode evolves as in the paper's box (at 1/Delta = 258 the same amplitudes and rates to every printed
  // digit; at 516 10.3x, 512 in the full box 10.4x) at a sixth of the cost.
  scenes::KelvinHelmholtzParams s;
  s.wavelengths = 1;
  const examples::NoHook none;
  const double linear = 2.0 * std::numbers::pi / s.tau_KH();
  s.cells = 132;
  const auto coarse = scenes::run_kelvin_helmholtz(true, s, none, none);
  s.cells = 516;
  const auto fine = scenes::run_kelvin_helmholtz(true, s, none, none);
  INFO("1/Delta = 132: " << coarse.amplitude_final / coarse.seed << "x, rate " << coarse.growth_rate << ", overturned "
                         << coarse.folds->overturned_fraction << "; 516: " << fine.amplitude_final / fine.seed
                         << "x, rate " << fine.growth_rate << ", overturned " << fine.folds->overturned_fraction
                         << " (linear theory " << linear << ")");
  CHECK(fine.particles_final == 86 * 258);
  CHECK(fine.amplitude_final > 5.0 * fine.seed);
  CHECK(fine.amplitude_final / fine.seed > 2.0 * coarse.amplitude_final / coarse.seed);
  CHECK(fine.growth_rate > 0.75 * linear);
  CHECK(fine.growth_rate > coarse.growth_rate);
  CHECK(std::abs(fine.energy_error) < 2e-3);
  // the billows curl over across half the width (measured 0.54); at 132 the interface stays single-valued
  CHECK(fine.folds->overturned_fraction > 0.35);
  CHECK(coarse.folds->overturned_fraction < 0.05);
}

TEST_CASE("Kelvin-Helmholtz: the mode grows more at smaller h/Delta, as the paper says of the interface smoothing",
          "[kelvin_helmholtz]") {
  // §3.3: "As h/Delta is increased, the ability to smooth the interface is gradually lost". At 1/Delta = 128,
  // M(tau_KH)/M(0) is 4.7, 3.5 and 2.0 at h/Delta = 1.0, 1.1 and 1.2 (the same to 1e-9 on one and two threads).
  scenes::KelvinHelmholtzParams s;
  s.cells = 128;
  const examples::NoHook none;
  std::array<double, 3> amplification{};
  const std::array<double, 3> h_over_dx{1.0, 1.1, 1.2};
  for (std::size_t i = 0; i < h_over_dx.size(); ++i) {
    s.h_over_dx = h_over_dx[i];
    const auto run = scenes::run_kelvin_helmholtz(true, s, none, none);
    amplification[i] = run.amplitude_final / run.seed;
  }
  INFO("M(tau_KH)/M(0) at h/Delta = 1.0, 1.1, 1.2: " << amplification[0] << ", " << amplification[1] << ", "
                                                     << amplification[2]);
  CHECK(amplification[0] > amplification[1]);
  CHECK(amplification[1] > amplification[2]);
  CHECK(amplification[0] > 1.8 * amplification[2]);
}

TEST_CASE("Kelvin-Helmholtz: the remaps widen an unseeded shear layer, which stays sharp without them",
          "[kelvin_helmholtz]") {
  // Each remap mixes s (1 - s) / 8 of the interface cells across the interface (test_remap.cpp): with no seed
  // the momentum thickness grows from 0 only through the remaps (3.4e-3 = 0.44 Delta at 1/Delta = 128 by tau_KH,
  // 1.2e-5 with no remap in the run).
  scenes::KelvinHelmholtzParams s;
  s.cells = 128;
  s.A = 0.0;
  const examples::NoHook none;
  const auto remapped = scenes::run_kelvin_helmholtz(true, s, none, none);
  s.reg_steps = 1000000;
  const auto kept = scenes::run_kelvin_helmholtz(true, s, none, none);
  INFO("momentum thickness at tau_KH: " << remapped.thickness.back() << " with remaps, " << kept.thickness.back()
                                        << " without");
  CHECK(remapped.regularizations >= 8);
  CHECK(kept.regularizations == 0);
  CHECK(remapped.thickness.front() == 0.0);
  CHECK(remapped.thickness.back() > 0.3 / s.cells);
  CHECK(kept.thickness.back() < 0.01 * remapped.thickness.back());
}

TEST_CASE(
    "Kelvin-Helmholtz at chi = 10 without conductivity: plain SPH keeps the phases apart with a pressure blip at "
    "the contact, where RSPH's remaps mix the interface",
    "[kelvin_helmholtz][long]") {
  // The failure Agertz et al. (2007) and Price (2008) describe, at 1/Delta = 128 by tau_KH (measured): plain SPH
  // (grad-h, equal masses) holds 1.3 % of the area at densities between the phases' and its pressure strays
  // by 10.5 % rms (P / P_0 from 0.14 to 1.98); RSPH holds 4.6 % mixed and strays by 4.3 % (0.73 to 1.28). The
  // suppressed growth Agertz et al. report does not follow here: the mode's amplitude grows in plain SPH too,
  // faster than in RSPH at this resolution (4.3x against 2.0x the seed), and the interface rolls up later (4 %
  // of the width against 18 % at 1/Delta = 256, docs/results/kelvin_helmholtz.md).
  scenes::KelvinHelmholtzParams s;
  s.cells = 128;
  const examples::NoHook none;
  const auto rsph = scenes::run_kelvin_helmholtz(true, s, none, none);
  const auto sph = scenes::run_kelvin_helmholtz(false, s, none, none);
  INFO("mixed area: SPH " << sph.contact.mixed_area << ", RSPH " << rsph.contact.mixed_area << "; pressure error: SPH "
                          << sph.contact.pressure_error << ", RSPH " << rsph.contact.pressure_error
                          << "; amplification: SPH " << sph.amplitude_final / sph.seed << ", RSPH "
                          << rsph.amplitude_final / rsph.seed);
  CHECK(sph.contact.pressure_error > 2.0 * rsph.contact.pressure_error);
  CHECK(sph.contact.mixed_area < 0.5 * rsph.contact.mixed_area);
  CHECK(rsph.contact.mixed_area > 0.02);
  CHECK(sph.amplitude_final > rsph.amplitude_final);  // not suppressed in amplitude (see above)
}

TEST_CASE("Kelvin-Helmholtz in 3D: the chi = 10 layer extruded along z grows as in 2D, with little motion along z",
          "[kelvin_helmholtz][long][3d]") {
  // One wavelength at 1/Delta = 192, eight spacings deep (periodic). Measured: 2D first order 2.8x the seed by
  // tau_KH, 3D 3.5x (first order) and 3.6x (second); at 1/Delta = 96 the 3D mode still decays (0.6x, 1.3x).
  scenes::KelvinHelmholtzParams s;
  s.wavelengths = 1;
  s.cells = 192;
  const examples::NoHook none;
  const double linear = 2.0 * std::numbers::pi / s.tau_KH();
  const auto flat = scenes::run_kelvin_helmholtz<2>(true, s, none, none);
  for (const char* remap : {"first", "second"}) {
    s.remap = remap;
    double vz = 0.0, vz_max = 0.0;  // at the end: mass-weighted rms and largest |v_z|
    const auto r = scenes::run_kelvin_helmholtz<3>(true, s, none, [&](const auto& sim) {
      const auto& p = sim.particles();
      double m = 0.0;
      for (std::size_t a = 0; a < p.n_real; ++a) {
        vz += p.m[a] * p.v[a][2] * p.v[a][2];
        m += p.m[a];
        vz_max = std::max(vz_max, std::abs(p.v[a][2]));
      }
      vz = std::sqrt(vz / m);
    });
    INFO(remap << " order: amplification " << r.amplitude_final / r.seed << " (2D " << flat.amplitude_final / flat.seed
               << "), growth rate " << r.growth_rate << " (linear theory " << linear << "), rms |v_z| " << vz
               << ", max " << vz_max);
    CHECK(r.amplitude_final > 2.5 * r.seed);
    CHECK(r.amplitude_final / r.seed > 0.8 * flat.amplitude_final / flat.seed);
    CHECK(r.growth_rate > 0.5 * linear);
    CHECK(r.energy_error < 5e-3);
    CHECK(r.regularizations >= 10);
    // every layer starts alike, yet the shear's particle-scale noise grows from round-off into motions along z:
    // rms 1.1 % (first order) and 2.3 % (second) of the shear velocity by tau_KH, the largest 0.15 and 0.5
    CHECK(vz < 0.05 * s.dv);
  }
}
