#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

TEST_CASE("ideal gas: eq. (5) and its sound speed", "[eos]") {
  const eos::IdealGas g{5.0 / 3.0};
  const Vec<2> x = Vec<2>::Zero();
  CHECK(g.pressure(2.0, 3.0, x) == Approx(2.0 / 3.0 * 2.0 * 3.0));
  CHECK(g.sound_speed(2.0, 3.0, x) == Approx(std::sqrt(5.0 / 3.0 * 2.0 / 3.0 * 3.0)));
  CHECK(g.internal_energy(2.0, g.pressure(2.0, 3.0, x)) == Approx(3.0));
  CHECK_THROWS_WITH(eos::IdealGas{1.0}.validate(), Catch::Contains("gamma must exceed 1"));
  STATIC_REQUIRE(eos::IdealGas::has_internal_energy);
}

TEST_CASE("isothermal, locally isothermal, polytropic and pressureless gases", "[eos]") {
  const Vec<2> x(3.0, 4.0);
  const eos::Isothermal iso{0.5};
  CHECK(iso.pressure(2.0, 99.0, x) == Approx(0.5));
  CHECK(iso.sound_speed(2.0, 99.0, x) == Approx(0.5));
  STATIC_REQUIRE(!eos::Isothermal::has_internal_energy);

  // c_s = 0.05 v_K with v_K = r^-1/2, as in the disk of §5
  const eos::LocallyIsothermal local([](const Vec<2>& p) { return 0.05 / std::sqrt(p.norm()); });
  CHECK(local.sound_speed(1.0, 0.0, x) == Approx(0.05 / std::sqrt(5.0)));
  CHECK(local.pressure(2.0, 0.0, x) == Approx(2.0 * 0.0025 / 5.0));

  const eos::Polytropic poly(1.4, [](const Vec<2>& p) { return 0.1 * p.norm(); });
  CHECK(poly.pressure(2.0, 0.0, x) == Approx(0.5 * std::pow(2.0, 1.4)));
  CHECK(poly.sound_speed(2.0, 0.0, x) == Approx(std::sqrt(1.4 * 0.5 * std::pow(2.0, 1.4) / 2.0)));
  CHECK_THROWS_WITH((eos::Polytropic(0.9, eos::ConstantK{1.0}).validate()), Catch::Contains("gamma must exceed 1"));

  const eos::Pressureless dust;
  CHECK(dust.pressure(2.0, 1.0, x) == 0.0);
  CHECK(dust.sound_speed(2.0, 1.0, x) == 0.0);
  CHECK_THROWS_WITH(eos::Isothermal{-1.0}.validate(), Catch::Contains("sound speed must be positive"));
}

TEST_CASE("equations of state say whether the gas exerts pressure", "[eos]") {
  // a pressureless gas skips the pressure terms of the pair loops; the others keep them
  STATIC_REQUIRE(!exerts_pressure<eos::Pressureless>());
  STATIC_REQUIRE(exerts_pressure<eos::IdealGas>());
  STATIC_REQUIRE(exerts_pressure<eos::Isothermal>());
}
