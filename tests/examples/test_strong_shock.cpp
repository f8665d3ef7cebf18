#include "strong_shock/scene.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

namespace {
void check_physical(const scenes::ShockRun& r) {
  for (std::size_t a = 0; a < r.rho.size(); ++a) {
    REQUIRE(std::isfinite(r.rho[a]));
    REQUIRE(r.rho[a] > 0.0);
    REQUIRE(r.u[a] >= 0.0);
    REQUIRE(std::isfinite(r.v[a]));
  }
}
}  // namespace

TEST_CASE("strong shock, pressure ratio 1e10: RSPH keeps the shock in place and no gas penetrates", "[strong_shock]") {
  scenes::StrongShockParams s;
  s.nx = 256;
  s.ny = 6;
  const auto r = scenes::run_shock(
      scenes::make_rsph_shock(s), s, [](const auto&) {}, [](const auto&) {});
  INFO("shock " << r.shock_position << " vs " << r.shock_position_exact << ", energy error " << r.energy_error
                << ", L1(rho) " << r.errors.L1_rho << ", regularizations " << r.regularizations);
  check_physical(r);
  CHECK(r.energy_error < 1e-6);
  CHECK(std::abs(r.shock_position - r.shock_position_exact) < 0.01);
  CHECK(r.penetration == 0.0);
  CHECK(r.regularizations >= 1);  // the adaptive schedule of Appendix A fired
  CHECK(r.errors.L1_rho < 0.03);
}

TEST_CASE("strong shock: plain SPH with alpha = 1 runs, conserves energy, and its penetration is reported",
          "[strong_shock]") {
  scenes::StrongShockParams s;
  s.sph_nx_left = 300;
  s.sph_ny_left = 12;
  s.sph_nx_right = 50;
  s.sph_ny_right = 2;
  const auto r = scenes::run_shock(
      scenes::make_sph_shock(s), s, [](const auto&) {}, [](const auto&) {});
  INFO("SPH: shock " << r.shock_position << " vs " << r.shock_position_exact << ", penetration " << r.penetration
                     << ", L1(rho) " << r.errors.L1_rho);
  check_physical(r);
  CHECK(r.energy_error < 1e-6);
  CHECK(std::abs(r.shock_position - r.shock_position_exact) < 0.05);
  CHECK(r.penetration >= 0.0);
}
