#include "rsph/analysis/sedov.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using rsph::analysis::SedovTaylor;

TEST_CASE("Sedov-Taylor: the energy integral gives Kamm & Timmes' alpha in every symmetry", "[analysis][sedov]") {
  // alpha = xi0^-(j+2) (Kamm & Timmes 2007, "On efficient generation of numerically robust Sedov solutions") for gamma
  // = 1.4
  const double alpha_14[] = {1.0767, 0.9841, 0.8511};
  for (int j = 1; j <= 3; ++j) {
    const SedovTaylor s(j, 1.4);
    INFO("j = " << j);
    CHECK(std::pow(s.xi0(), -(j + 2.0)) == Approx(alpha_14[j - 1]).margin(1e-4));
    // the swept-up mass is the mass the sphere held: an independent check of the integrated profile
    CHECK(s.mass_ratio() == Approx(1.0).margin(2e-5));
  }
  // gamma = 5/3, spherical: xi0 = 1.15167
  const SedovTaylor s(3, 5.0 / 3.0);
  CHECK(s.xi0() == Approx(1.15167).margin(2e-5));
  CHECK(s.mass_ratio() == Approx(1.0).margin(2e-5));
}

TEST_CASE("Sedov-Taylor: the shock's jump, its radius law and the centre's limits", "[analysis][sedov]") {
  const double gamma = 5.0 / 3.0, E = 2.5, rho0 = 0.7;
  const SedovTaylor s(3, gamma, E, rho0);
  const double t = 0.05, R = s.shock_radius(t);
  CHECK(R == Approx(s.xi0() * std::pow(E * t * t / rho0, 0.2)).epsilon(1e-14));
  CHECK(s.time_at_radius(R) == Approx(t).epsilon(1e-12));
  // just inside the shock: the strong-shock jump, v = 2 U / (gamma + 1), P = 2 rho0 U^2 / (gamma + 1)
  const double U = 0.4 * R / t;
  const auto in = s.at(R * (1.0 - 1e-12), t);
  CHECK(in.rho == Approx(4.0 * rho0).epsilon(1e-9));
  CHECK(in.v == Approx(2.0 * U / (gamma + 1.0)).epsilon(1e-9));
  CHECK(in.P == Approx(2.0 * rho0 * U * U / (gamma + 1.0)).epsilon(1e-9));
  const auto out = s.at(1.01 * R, t);
  CHECK(out.rho == rho0);
  CHECK(out.v == 0.0);
  // towards the centre: v -> r / (gamma t') with U f = U lambda / gamma, the pressure flat, the density gone
  const auto c = s.similarity(0.01);
  CHECK(c.f == Approx(0.01 / gamma).epsilon(1e-3));
  CHECK(s.similarity(0.02).h == Approx(c.h).epsilon(1e-3));
  CHECK(c.g < 1e-6);
  // the density falls monotonically from the shock inwards
  double last = s.similarity(1.0).g;
  for (double l = 0.99; l > 0.05; l -= 0.01) {
    const double g = s.similarity(l).g;
    CHECK(g < last);
    last = g;
  }
  CHECK_THROWS(SedovTaylor(4, gamma));
  CHECK_THROWS(SedovTaylor(3, 1.0));
  CHECK_THROWS(SedovTaylor(3, gamma, -1.0));
}
