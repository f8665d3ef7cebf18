#include "sod/scene.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

namespace {
struct SodRun {
  analysis::ShockTubeErrors errors;
  double energy_drift;
};
SodRun run_sod_1d(int n_left) {
  scenes::SodParams s;
  s.n_left = n_left;
  auto sim = scenes::make_sod<1, kernel::CubicSpline>(s);
  const auto start = sim.totals();
  sim.run_until(s.t_end);
  const auto end = sim.totals();
  const analysis::ExactRiemann exact(s.left, s.right, s.gamma);
  return {analysis::shock_tube_errors(sim.particles(), exact, sim.time(), 0.5),
          std::abs(end.total_energy() - start.total_energy()) / start.total_energy()};
}
}  // namespace

TEST_CASE("Sod 1D, 400 particles on the left: L1(rho) < 0.01 and first-order convergence", "[sod]") {
  const auto coarse = run_sod_1d(200);
  const auto fine = run_sod_1d(400);
  INFO("L1(rho) at 200: " << coarse.errors.L1_rho << ", at 400: " << fine.errors.L1_rho);
  CHECK(fine.errors.L1_rho < 0.01);
  CHECK(coarse.errors.L1_rho / fine.errors.L1_rho >= 1.6);
  CHECK(fine.errors.L1_v < 0.03);
  CHECK(fine.errors.L1_P < 0.01);
  CHECK(fine.energy_drift < 1e-3);
}

TEST_CASE("Sod as a 2D strip matches the exact solution", "[sod]") {
  scenes::SodParams s;
  s.n_left = 100;
  s.ny_left = 4;
  auto sim = scenes::make_sod<2, kernel::CubicSpline>(s);
  const auto start = sim.totals();
  sim.run_until(s.t_end);
  const analysis::ExactRiemann exact(s.left, s.right, s.gamma);
  const auto e = analysis::shock_tube_errors(sim.particles(), exact, sim.time(), 0.5);
  INFO("2D L1(rho) = " << e.L1_rho);
  CHECK(e.L1_rho < 0.03);
  CHECK(std::abs(sim.totals().total_energy() - start.total_energy()) / start.total_energy() < 1e-3);
  // the strip stays one-dimensional: transverse momentum stays at round-off
  CHECK(std::abs(sim.totals().momentum[1]) < 1e-12);
}
