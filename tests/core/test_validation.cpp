#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

namespace {
using Sim1 = Simulation<1, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::ArtificialViscosity>;

ParticleSet<1, true> lattice_1d(int n, double h_over_dx) {
  ParticleSet<1, true> p;
  const double dx = 1.0 / n;
  for (int i = 0; i < n; ++i) p.add(dx, Vec<1>((i + 0.5) * dx), Vec<1>::Zero(), h_over_dx * dx, 1.0);
  return p;
}
Box<1> walls() {
  Box<1> b;
  b.edge = {Edge::reflecting};
  return b;
}
}  // namespace

TEST_CASE("bad input is refused with a message naming the cause", "[validation]") {
  CHECK_THROWS_WITH(Sim1(ParticleSet<1, true>{}, walls(), eos::IdealGas{1.4}, {}, {}, {}),
                    Catch::Contains("no particles"));
  CHECK_THROWS_WITH(Sim1(lattice_1d(10, 0.0), walls(), eos::IdealGas{1.4}, {}, {}, {}),
                    Catch::Contains("smoothing length h must be positive"));
  CHECK_THROWS_WITH(Sim1(lattice_1d(10, 1.2), walls(), eos::IdealGas{0.9}, {}, {}, {}),
                    Catch::Contains("gamma must exceed 1"));
  CHECK_THROWS_WITH(Sim1(lattice_1d(10, 1.2), walls(), eos::IdealGas{1.4}, {}, {}, physics::ArtificialViscosity{-1, 2}),
                    Catch::Contains("alpha and beta must be non-negative"));
  auto outside = lattice_1d(10, 1.2);
  outside.x[3][0] = 1.5;
  CHECK_THROWS_WITH(Sim1(outside, walls(), eos::IdealGas{1.4}, {}, {}, {}),
                    Catch::Contains("particle 3: lies outside the box"));
  Box<1> empty = walls();
  empty.hi[0] = empty.lo[0];
  CHECK_THROWS_WITH(Sim1(lattice_1d(10, 1.2), empty, eos::IdealGas{1.4}, {}, {}, {}), Catch::Contains("box is empty"));
  auto nan = lattice_1d(10, 1.2);
  nan.v[2][0] = std::nan("");
  CHECK_THROWS_WITH(Sim1(nan, walls(), eos::IdealGas{1.4}, {}, {}, {}),
                    Catch::Contains("particle 2: position and velocity must be finite"));
}

TEST_CASE("a NaN appearing during a run stops it with the particle named", "[validation]") {
  Sim1 sim(lattice_1d(20, 1.2), walls(), eos::IdealGas{1.4}, {}, {}, {});
  sim.step();
  sim.particles().u[5] = std::nan("");
  CHECK_THROWS_AS(sim.step(), NumericalError);
}

TEST_CASE("mirror ghosts at reflecting walls keep a uniform lattice uniform", "[boundary]") {
  Sim1 sim(lattice_1d(50, 1.2), walls(), eos::IdealGas{1.4}, {}, {}, {});
  const double expected = kernel::lattice_sum<kernel::CubicSpline, 1>(1.2);
  for (std::size_t a = 0; a < sim.particles().n_real; ++a)
    CHECK(sim.particles().rho[a] == Approx(expected).epsilon(1e-12));
  for (int s = 0; s < 20; ++s) sim.step();
  for (std::size_t a = 0; a < sim.particles().n_real; ++a) CHECK(std::abs(sim.particles().v[a][0]) < 1e-12);
}

TEST_CASE("frozen particles follow their prescribed motion and still push their neighbours", "[boundary]") {
  // a 1D column whose first 5 particles are a piston moving at 0.1
  ParticleSet<1, true> p;
  const int n = 40;
  const double dx = 1.0 / n;
  for (int i = 0; i < n; ++i) p.add(dx, Vec<1>((i + 0.5) * dx), Vec<1>(0.0), 1.2 * dx, 1.0);
  for (int i = 0; i < 5; ++i) p.frozen[static_cast<std::size_t>(i)] = 1;
  std::vector<double> x0(p.x.size());
  for (std::size_t a = 0; a < p.x.size(); ++a) x0[a] = p.x[a][0];
  auto run = [&](double speed) {
    auto piston = [x0, speed](std::size_t i, double t, Vec<1>& x, Vec<1>& v) {
      x[0] = x0[i] + speed * t;
      v[0] = speed;
    };
    Box<1> box;  // open
    Simulation<1, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::ArtificialViscosity,
               boundary::PrescribedMotion<decltype(piston)>>
        sim(p, box, eos::IdealGas{1.4}, {}, {}, physics::ArtificialViscosity{}, boundary::PrescribedMotion(piston));
    sim.run_until(0.2);
    const auto& q = sim.particles();
    for (std::size_t i = 0; i < 5; ++i) {
      CHECK(q.x[i][0] == Approx(x0[i] + speed * sim.time()).epsilon(1e-12));
      CHECK(q.v[i][0] == speed);
    }
    return q.v[5][0];
  };
  const double still = run(0.0), pushed = run(0.3);
  CHECK(pushed > still + 0.05);  // the gas ahead of a moving piston is pushed
}
