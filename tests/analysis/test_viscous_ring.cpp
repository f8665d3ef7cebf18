#include "rsph/paper/viscous_ring.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>

using namespace rsph;

TEST_CASE("scaled Bessel I_1/4: the series and the asymptotic branch agree and match known values", "[analysis]") {
  // both branches at the switch point
  const double z = 25.0;
  CHECK(paper::scaled_bessel_i(0.25, z) == Approx(std::cyl_bessel_i(0.25, z) * std::exp(-z)).epsilon(1e-13));
  CHECK(paper::scaled_bessel_i(0.25, 40.0) ==
        Approx(std::cyl_bessel_i(0.25, 40.0) * std::exp(-40.0)).epsilon(1e-13));
  // I_1/2(z) = sqrt(2 / (pi z)) sinh z, exactly
  for (double x : {0.5, 10.0, 30.0, 300.0})
    CHECK(paper::scaled_bessel_i(0.5, x) ==
          Approx(std::sqrt(2.0 / (std::numbers::pi * x)) * 0.5 * (1.0 - std::exp(-2.0 * x))).epsilon(1e-13));
  // far beyond where I_1/4 overflows
  CHECK(std::isfinite(paper::scaled_bessel_i(0.25, 1e4)));
}

TEST_CASE("eq. (16) holds the ring's mass and solves the viscous diffusion equation", "[analysis]") {
  const paper::ViscousRing ring{2.5, 1.0, 1.0, 4.8e-5};
  auto disk_mass = [&](double tau) {  // int Sigma 2 pi R dR, midpoint rule
    double mass = 0.0;
    const double dR = 1e-4;
    for (double R = 0.5 * dR; R < 4.0; R += dR) mass += ring.sigma(tau, R) * 2.0 * std::numbers::pi * R * dR;
    return mass;
  };
  CHECK(disk_mass(0.018) == Approx(2.5).epsilon(1e-9));
  // the central mass accretes: the disk loses a little mass, more as the ring spreads
  const double m090 = disk_mass(0.09), m198 = disk_mass(0.198);
  CHECK(m090 < 2.5);
  CHECK(m198 < m090);
  CHECK(m198 > 2.5 * (1.0 - 1e-3));
  // dSigma/dt = 3/R d/dR [sqrt(R) d/dR (nu Sigma sqrt(R))] (Pringle 1981), with dtau = 12 nu dt
  const double nu = ring.nu, tau = 0.09, e = 1e-4;
  for (double R : {0.7, 0.95, 1.0, 1.2}) {
    auto f = [&](double r) { return nu * ring.sigma(tau, r) * std::sqrt(r); };
    auto g = [&](double r) { return std::sqrt(r) * (f(r + e) - f(r - e)) / (2 * e); };
    const double rhs = 3.0 / R * (g(R + e) - g(R - e)) / (2 * e);
    const double lhs = 12.0 * nu * (ring.sigma(tau + 1e-6, R) - ring.sigma(tau - 1e-6, R)) / 2e-6;
    CHECK(lhs == Approx(rhs).epsilon(1e-4).margin(1e-9));
    // eq. (18) against the direct difference of nu Sigma sqrt(R)
    CHECK(ring.v_R(tau, R) ==
          Approx(-3.0 / (ring.sigma(tau, R) * std::sqrt(R)) * (f(R + e) - f(R - e)) / (2 * e)).epsilon(1e-6));
  }
  CHECK(ring.v_phi(4.0) == Approx(0.5));
  // the peak the noise error is normalised by (0.305 M / (pi R_0^2) at tau* = 0.09 for M = 1)
  CHECK(ring.peak_sigma(0.09) == Approx(2.5 * 0.305).epsilon(2e-3));
  CHECK(ring.tau_at(ring.time_at(0.09, 0.018), 0.018) == Approx(0.09));
}

TEST_CASE("the chi^2 fit recovers the viscous time of a noisy profile", "[analysis]") {
  const paper::ViscousRing ring{1.0, 1.0, 1.0, 4.8e-5};
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<double> x, s;
  for (double r = 0.3; r < 1.8; r += 0.01) {
    x.push_back(r);
    s.push_back(ring.sigma(0.126, r) * (1.0 + noise(rng)));
  }
  CHECK(paper::fit_viscous_time(ring, x, s, 0.018, 1.0) == Approx(0.126).epsilon(0.01));
}
