// Individual time steps in power-of-two bins (TimeStepParams::max_bin): the same answers as one global
// step for less work.
#include "sod/scene.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

using namespace rsph;

namespace {

using K = kernel::CubicSpline;
using Orbits = Simulation<2, K, eos::Pressureless, regularize::None, physics::PointMass<2>>;

/// Pressureless test particles on circular orbits about GM = 1, too far apart to interact.
Orbits circular_orbits(const std::vector<double>& radii, int max_bin) {
  ParticleSet<2, false> p;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    const double r = radii[k], phi = 2.0 * std::numbers::pi * double(k) / double(radii.size());
    const Vec<2> e(std::cos(phi), std::sin(phi));
    p.add(1.0, r * e, std::sqrt(1.0 / r) * Vec<2>(-e[1], e[0]), 0.01);
  }
  Box<2> box;
  box.lo = Vec<2>(-4.0, -4.0);
  box.hi = Vec<2>(4.0, 4.0);
  box.edge = {Edge::open, Edge::open};
  TimeStepParams ts;
  ts.max_bin = max_bin;
  return Orbits(std::move(p), box, {}, {}, ts, physics::PointMass<2>{1.0, Vec<2>::Zero(), 0.0});
}

}  // namespace

TEST_CASE("individual time steps: one bin for all is the global leapfrog, bit for bit", "[integrate]") {
  auto global = circular_orbits({1.0, 1.0, 1.0}, 0);
  auto binned = circular_orbits({1.0, 1.0, 1.0}, 3);
  global.run_until(3.0);
  binned.run_until(3.0);
  REQUIRE(global.steps() == binned.steps());
  for (std::size_t a = 0; a < 3; ++a) {
    CHECK((global.particles().x[a] - binned.particles().x[a]).norm() == 0.0);
    CHECK((global.particles().v[a] - binned.particles().v[a]).norm() == 0.0);
  }
}

TEST_CASE("individual time steps: Kepler orbits from r = 0.5 to 2.5 kept as well, with fewer updates", "[integrate]") {
  const std::vector<double> radii{0.5, 0.8, 1.2, 1.7, 2.5};
  auto global = circular_orbits(radii, 0);
  auto binned = circular_orbits(radii, 3);
  const double t_end = 2.0 * std::numbers::pi * std::pow(2.5, 1.5);  // one orbit of the outermost
  global.run_until(t_end);
  binned.run_until(t_end);
  double worst_global = 0.0, worst_binned = 0.0;
  for (std::size_t a = 0; a < radii.size(); ++a) {
    worst_global = std::max(worst_global, std::abs(global.particles().x[a].norm() / radii[a] - 1.0));
    worst_binned = std::max(worst_binned, std::abs(binned.particles().x[a].norm() / radii[a] - 1.0));
  }
  INFO("radius error: global " << worst_global << ", binned " << worst_binned << "; updates "
                               << global.particle_updates() << " vs " << binned.particle_updates());
  // the force condition gives dt ~ r: strides 1, 1, 2, 2, 4 substeps (the radii span a factor 5), so 13
  // updates where one global step makes 20, and leapfrog's bounded error either way
  CHECK(worst_global < 1e-3);
  CHECK(worst_binned < 1e-3);
  CHECK(binned.particle_updates() < 0.7 * global.particle_updates());
  CHECK(binned.time() == Approx(t_end).epsilon(1e-14));
}

TEST_CASE("individual time steps: RSPH Sod on three levels as accurate as with one global step", "[integrate][sod]") {
  auto run = [](int max_bin) {
    scenes::SodParams s;
    s.n_left = 200;
    scenes::RsphSodParams r;
    r.refinement.levels = 2;
    r.max_bin = max_bin;
    auto sim = scenes::make_rsph_sod<1, K>(s, r);
    const double mass = sim.totals().mass;
    sim.run_until(s.t_end);
    const analysis::ExactRiemann exact(s.left, s.right, s.gamma);
    return std::tuple{analysis::shock_tube_errors(sim.particles(), exact, sim.time(), 0.5).L1_rho,
                      sim.particle_updates(), std::abs(sim.totals().mass - mass) / mass};
  };
  const auto [L1_global, updates_global, mass_global] = run(0);
  const auto [L1_binned, updates_binned, mass_binned] = run(2);
  INFO("L1(rho): global " << L1_global << ", binned " << L1_binned << "; updates " << updates_global << " vs "
                          << updates_binned);
  // most particles sit on the finest level here (levels follow the waves), so the saving is small
  CHECK(mass_binned < 1e-13);
  CHECK(L1_binned < 1.1 * L1_global);
  CHECK(updates_binned < updates_global);
}

TEST_CASE("individual time steps need fixed smoothing lengths", "[integrate]") {
  scenes::SodParams s;
  s.n_left = 50;
  auto p = scenes::make_sod<1, K>(s).particles();
  p.clear_ghosts();
  TimeStepParams ts;
  ts.max_bin = 2;
  Box<1> box;
  box.lo = Vec<1>(0.0);
  box.hi = Vec<1>(1.0);
  box.edge = {Edge::reflecting};
  using GradHSod = Simulation<1, K, eos::IdealGas, regularize::None, physics::GradH<1>>;
  CHECK_THROWS_WITH(GradHSod(p, box, eos::IdealGas{1.4}, {}, ts, physics::GradH<1>{}),
                    Catch::Contains("need fixed smoothing lengths"));
}
