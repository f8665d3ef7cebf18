// The planet disk in 3D at reduced size: its equilibrium against hydrostatics, its start, and short runs.
#include "planet_disk/scene.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

using namespace rsph;

namespace {
/// The 3D disk at the quick preset's size.
scenes::PlanetDiskParams reduced_3d_disk() {
  scenes::PlanetDiskParams s;
  s.dim = 3;
  s.particles = 20000;
  s.h_over_dx = scenes::PlanetDiskParams::h_over_dx_3d;
  return s;
}
}  // namespace

TEST_CASE("3D disk: the star and planet pull in space as in the plane, and toward the plane above it",
          "[examples][disk][3d]") {
  const paper::StarAndPlanet sp{1.0, 1e-3, 1.0, 0.03, 5.0};
  const double t = 7.3 * sp.period();
  for (const Vec<2>& x : {Vec<2>(1.1, 0.2), Vec<2>(-0.5, 0.7), Vec<2>(0.999, 0.05)}) {
    const Vec<2> g2 = sp.acceleration(x, t);
    const Vec<3> g3 = sp.acceleration(Vec<3>(x.x(), x.y(), 0.0), t);
    CHECK(g3.z() == 0.0);
    CHECK(g3.x() == Approx(g2.x()).epsilon(1e-15));
    CHECK(g3.y() == Approx(g2.y()).epsilon(1e-15));
  }
  // far from the planet, above the plane: the star's pull -x / |x - x_*|^3 to the planet's mass
  const Vec<3> x(-1.5, 0.3, 0.2);
  const Vec<2> star = sp.star_position(t);
  const Vec<3> d = x - Vec<3>(star.x(), star.y(), 0.0);
  CHECK((sp.acceleration(x, t) + d / std::pow(d.norm(), 3)).norm() < 2e-3 / 0.25);
  CHECK(sp.acceleration(x, t).z() < 0.0);
}

TEST_CASE("3D disk: the vertical profile and the zones' rotation are in hydrostatic equilibrium",
          "[examples][disk][3d]") {
  scenes::PlanetDiskParams s;
  s.dim = 3;
  const auto profile = s.vertical();
  // a Gaussian of width aspect to O(aspect^2), cut at the surface 3 H: erf(3 / sqrt 2) of sqrt(2 pi) aspect
  CHECK(profile.integral() ==
        Approx(std::sqrt(2.0 * std::numbers::pi) * 0.05 * std::erf(3.0 / std::sqrt(2.0))).epsilon(5e-3));
  CHECK(profile.rms_zeta() == Approx(0.05 * std::sqrt(0.9733)).epsilon(5e-3));  // 1 - 6 phi(3) / erf
  CHECK(std::abs(profile.zeta_at_fraction(0.5)) < 1e-12);
  CHECK(profile.zeta_at_fraction(0.8413) == Approx(0.05).epsilon(0.02));
  // the column holds Sigma_0 at every radius
  for (const double R : {0.45, 1.0, 2.2}) {
    double column = 0.0;
    const int n = 20000;
    const double z_max = s.surface * s.aspect * R, dz = 2.0 * z_max / n;
    for (int k = 0; k < n; ++k) column += profile.density(Vec<3>(R, 0.0, -z_max + (k + 0.5) * dz), s.sigma0) * dz;
    CHECK(column == Approx(s.sigma0).epsilon(1e-6));
  }
  // force balance of P = c_s(R)^2 rho against the star: radially with the zones' Omega(R, z), and vertically
  const auto zones = s.zones();
  const scenes::DiskSoundSpeed cs{s.aspect, 1.0};
  auto P = [&](const Vec<3>& x) { return cs(x) * cs(x) * profile.density(x, s.sigma0); };
  for (const double R : {0.6, 1.0, 1.7})
    for (const double z_in_H : {0.0, 1.0, 2.0}) {
      const Vec<3> x(R, 0.0, z_in_H * s.aspect * R);
      const double rho = profile.density(x, s.sigma0), r = x.norm(), e = 1e-6;
      const double dPdR = (P(x + Vec<3>(e, 0, 0)) - P(x - Vec<3>(e, 0, 0))) / (2 * e);
      const double dPdz = (P(x + Vec<3>(0, 0, e)) - P(x - Vec<3>(0, 0, e))) / (2 * e);
      const double Omega = zones.Omega(R, x.z());
      INFO("R = " << R << ", z = " << z_in_H << " H");
      CHECK(Omega * Omega * R == Approx(R / (r * r * r) + dPdR / rho).epsilon(1e-6));
      CHECK(dPdz / rho == Approx(-x.z() / (r * r * r)).margin(1e-6));
      CHECK(zones.velocity(x).norm() == Approx(Omega * R).epsilon(1e-14));
    }
  CHECK(zones.Omega(1.0) == Approx(std::sqrt(1.0 - 2.0 * 0.05 * 0.05)).epsilon(1e-14));
}

TEST_CASE("3D disk: RSPH's lattice and SPH's columns fill the flared disk with Sigma_0, nothing above it",
          "[examples][disk][3d]") {
  auto s = reduced_3d_disk();
  for (const std::string method : {"rsph", "sph"}) {
    s.method = method;
    INFO(method);
    const auto p = s.rsph() ? scenes::make_rsph_disk_3d(s).particles() : scenes::make_sph_disk_3d(s).particles();
    CHECK(std::abs(static_cast<double>(p.n_real) / 20000.0 - 1.0) < 0.02);
    double mass = 0.0, outside = 0.0;
    for (std::size_t a = 0; a < p.n_real; ++a) {
      mass += p.m[a];
      const double R = std::hypot(p.x[a].x(), p.x[a].y());
      outside = std::max(outside, std::abs(p.x[a].z()) - s.surface * s.aspect * R);
    }
    CHECK(outside <= 1e-12);
    const auto profile = scenes::disk_profile(scenes::seen_from_above(p), s);
    for (std::size_t i = 0; i < profile.r.size(); ++i)
      if (profile.r[i] > 0.7 && profile.r[i] < 2.2) CHECK(std::abs(profile.sigma[i] - 1.0) < 0.03);
    // the columns hold the disk's mass: RSPH's lattice squares of the annulus, SPH's the same
    CHECK(mass / (s.sigma0 * s.area()) == Approx(1.0).epsilon(0.02));
  }
}

TEST_CASE("3D disk, reduced: RSPH keeps the mass, the vertical equilibrium and opens the gap's start",
          "[examples][disk][3d][long]") {
  auto s = reduced_3d_disk();
  s.orbits = 2.0;
  for (const std::string remap : {"first", "second"}) {
    s.remap = remap;
    double thickness_start = 0.0, thickness_end = 0.0;
    const auto r = scenes::run_planet_disk(
        s, [](const auto&) {},
        [&](const auto& sim, const scenes::DiskSample& d) {
          if constexpr (std::decay_t<decltype(sim)>::dim == 3) {
            const double t = scenes::thickness_ratio(sim.particles(), s.vertical(), 0.5, 2.4);
            (d.steps == 0 ? thickness_start : thickness_end) = t;
          }
        });
    INFO(remap << ": thickness " << thickness_start << " -> " << thickness_end << ", gap depth "
               << r.samples.back().gap_depth << ", " << r.regularizations << " regularizations");
    CHECK(r.max_mass_error < 1e-12);
    CHECK(r.mass_removed < 1e-3 * r.mass_initial);
    CHECK(r.regularizations > 10);
    // the disk stays as thick as hydrostatic equilibrium makes it: no collapse, no puffing up
    CHECK(thickness_start == Approx(1.0).epsilon(0.1));
    CHECK(thickness_end == Approx(1.0).epsilon(0.15));
    // two orbits into the five of the ramp the planet has begun to push gas from its orbit
    CHECK(r.samples.back().gap_depth < 0.97);
    CHECK(r.samples.back().gap_depth > 0.6);
  }
}
