#include "rsph/analysis/riemann.hpp"

#include <catch2/catch.hpp>

using namespace rsph::analysis;

TEST_CASE("exact Riemann solver: Sod's star state", "[riemann]") {
  const ExactRiemann sod({1.0, 0.0, 1.0}, {0.125, 0.0, 0.1}, 1.4);
  CHECK(sod.p_star() == Approx(0.30313).margin(5e-6));
  CHECK(sod.v_star() == Approx(0.92745).margin(5e-6));
  CHECK(sod.rho_star_left() == Approx(0.42632).margin(5e-5));
  CHECK(sod.rho_star_right() == Approx(0.26557).margin(5e-5));
  CHECK(sod.right_shock_speed() == Approx(1.75216).margin(5e-5));
  // sampled far left and right: the initial states
  CHECK(sod.sample(-10.0).rho == 1.0);
  CHECK(sod.sample(10.0).P == 0.1);
}

TEST_CASE("exact Riemann solver: pressure ratio 1e10 (Xiao 2004) satisfies Rankine-Hugoniot", "[riemann]") {
  const GasState L{1.0, 0.0, 1e10}, R{0.125, 0.0, 0.1};
  const double g = 1.4;
  const ExactRiemann s(L, R, g);
  REQUIRE(std::isfinite(s.p_star()));
  CHECK(s.p_star() > R.P);
  CHECK(s.p_star() < L.P);
  // mass and momentum fluxes across the right shock, in its frame
  const double S = s.right_shock_speed();
  const double rho2 = s.rho_star_right();
  CHECK(R.rho * (R.v - S) == Approx(rho2 * (s.v_star() - S)).epsilon(1e-10));
  CHECK(R.rho * (R.v - S) * (R.v - S) + R.P ==
        Approx(rho2 * (s.v_star() - S) * (s.v_star() - S) + s.p_star()).epsilon(1e-10));
  // strong-shock limit: density jump (g + 1) / (g - 1) = 6
  CHECK(rho2 / R.rho == Approx(6.0).epsilon(1e-4));
  // isentropic left rarefaction: P / rho^g constant
  CHECK(s.p_star() / std::pow(s.rho_star_left(), g) == Approx(L.P / std::pow(L.rho, g)).epsilon(1e-10));
}

TEST_CASE("exact Riemann solver refuses vacuum-generating and unphysical data", "[riemann]") {
  CHECK_THROWS_WITH(ExactRiemann({1.0, -10.0, 1.0}, {1.0, 10.0, 1.0}, 1.4), Catch::Contains("vacuum"));
  CHECK_THROWS_WITH(ExactRiemann({1.0, 0.0, -1.0}, {1.0, 0.0, 1.0}, 1.4), Catch::Contains("must be positive"));
}
