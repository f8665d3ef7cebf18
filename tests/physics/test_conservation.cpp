#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <random>

using namespace rsph;

namespace {

// A jittered periodic 2D gas with random velocities: shocks and shear everywhere, viscosity active.
ParticleSet<2, true> random_gas(int n, unsigned seed, bool equal_mass) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<2, true> p;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec<2> x((i + 0.5 + 0.3 * u(rng)) * dx, (j + 0.5 + 0.3 * u(rng)) * dx);
      const double m = equal_mass ? dx * dx : dx * dx * (1.0 + 0.5 * u(rng));
      p.add(m, x, Vec<2>(0.5 * u(rng), 0.5 * u(rng)), 1.3 * dx, 1.0 + 0.5 * u(rng));
    }
  return p;
}

Box<2> periodic_box() {
  Box<2> b;
  b.edge = {Edge::periodic, Edge::periodic};
  return b;
}

template <class Sim>
void check_conservation(Sim& sim, int steps) {
  const auto start = sim.totals();
  double scale = 0.0;  // sum m |v|: the scale against which momentum round-off is judged
  for (std::size_t a = 0; a < sim.particles().n_real; ++a) scale += sim.particles().m[a] * sim.particles().v[a].norm();
  for (int s = 0; s < steps; ++s) sim.step();
  const auto end = sim.totals();
  CHECK((end.momentum - start.momentum).norm() / scale < 1e-12);
  CHECK(end.mass == Approx(start.mass).epsilon(1e-14));
  // energy: exact in the semi-discrete equations; the leapfrog error is second order in dt
  CHECK(std::abs(end.total_energy() - start.total_energy()) / start.total_energy() < 1e-3);
  CHECK(end.thermal > start.thermal);  // viscosity turns kinetic energy into heat
}

}  // namespace

TEST_CASE("fixed-h SPH (eqs. 2-4) with artificial viscosity conserves momentum to round-off", "[physics]") {
  Simulation<2, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::ArtificialViscosity> sim(
      random_gas(24, 1, false), periodic_box(), eos::IdealGas{1.4}, {}, {}, physics::ArtificialViscosity{1.0, 2.0});
  check_conservation(sim, 40);
}

TEST_CASE("grad-h SPH with artificial viscosity conserves momentum to round-off", "[physics]") {
  Simulation<2, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::ArtificialViscosity, physics::GradH<2>>
      sim(random_gas(24, 2, true), periodic_box(), eos::IdealGas{1.4}, {}, {}, physics::ArtificialViscosity{1.0, 2.0},
          physics::GradH<2>{1.2});
  check_conservation(sim, 40);
  // h and rho satisfy h = eta (m / rho)^(1/2) after the solve
  const auto& p = sim.particles();
  for (std::size_t a = 0; a < p.n_real; ++a) CHECK(p.h[a] == Approx(1.2 * std::sqrt(p.m[a] / p.rho[a])).epsilon(1e-5));
}

TEST_CASE("the artificial viscosity pair term: eq. (3)-(4) shares and zero for receding pairs", "[physics]") {
  physics::Pair<1> pr;
  pr.r_ab = Vec<1>(0.1);
  pr.r = 0.1;
  pr.h_ab = 0.1;
  pr.grad_W = kernel::grad_W<kernel::CubicSpline, 1>(pr.r_ab, pr.r, pr.h_ab);
  pr.m_a = pr.m_b = 1.0;
  pr.rho_a = pr.rho_b = 1.0;
  pr.P_a = pr.P_b = 1.0;
  pr.cs_a = pr.cs_b = 1.0;
  const physics::ArtificialViscosity av{1.0, 2.0};
  pr.v_ab = Vec<1>(0.5);  // receding
  CHECK(av.pair(pr).dv_dt.norm() == 0.0);
  pr.v_ab = Vec<1>(-0.5);  // approaching: mu = h v r / (r^2 + 0.01 h^2)
  const double mu = 0.1 * -0.05 / (0.01 + 0.0001);
  const double Pi = (-1.0 * mu + 2.0 * mu * mu) / 1.0;
  const auto rates = av.pair(pr);
  CHECK(rates.dv_dt[0] == Approx(-Pi * pr.grad_W[0]));
  CHECK(rates.du_dt == Approx(0.5 * Pi * pr.v_ab.dot(pr.grad_W)));
  CHECK(rates.du_dt > 0.0);  // viscosity heats
}

TEST_CASE("artificial conductivity: heat flows from hot to cold and the energy sum is unchanged", "[physics]") {
  ParticleSet<1, true> p;
  p.add(1.0, Vec<1>(0.0), Vec<1>(0.0), 1.0, 2.0);  // hot
  p.add(1.0, Vec<1>(0.8), Vec<1>(0.0), 1.0, 1.0);  // cold
  Box<1> box;                                      // open: two particles alone
  Simulation<1, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::ArtificialConductivity> sim(
      p, box, eos::IdealGas{5.0 / 3.0}, {}, {}, physics::ArtificialConductivity{1.0});
  const auto& q = sim.particles();
  CHECK(q.du_dt[0] < 0.0);
  CHECK(q.du_dt[1] > 0.0);
  CHECK(q.m[0] * q.du_dt[0] + q.m[1] * q.du_dt[1] == Approx(0.0).margin(1e-15));
  // the term alone (no pressure): equal and opposite, and zero for equal energies
  physics::Pair<1> pr;
  pr.r_ab = Vec<1>(-0.8);
  pr.r = 0.8;
  pr.grad_W = kernel::grad_W<kernel::CubicSpline, 1>(pr.r_ab, pr.r, 1.0);
  pr.m_b = 1.0;
  pr.rho_a = pr.rho_b = 1.0;
  pr.P_a = 2.0;
  pr.P_b = 1.0;
  pr.u_a = 3.0;
  pr.u_b = 1.0;
  const double du_a = physics::ArtificialConductivity{1.0}.pair(pr).du_dt;
  std::swap(pr.u_a, pr.u_b);
  std::swap(pr.P_a, pr.P_b);
  pr.r_ab = -pr.r_ab;
  pr.grad_W = -pr.grad_W;
  CHECK(physics::ArtificialConductivity{1.0}.pair(pr).du_dt == Approx(-du_a));
  CHECK(du_a < 0.0);
}

TEST_CASE("point-mass gravity: Kepler's acceleration, softened", "[physics]") {
  const physics::PointMass<2> star{2.0, Vec<2>(1.0, 0.0), 0.0};
  const Vec<2> g = star.acceleration(Vec<2>(1.0, 2.0), 0.0);
  CHECK(g[0] == Approx(0.0).margin(1e-15));
  CHECK(g[1] == Approx(-2.0 / 4.0));
  const physics::PointMass<2> soft{1.0, Vec<2>::Zero(), 0.5};
  CHECK(soft.acceleration(Vec<2>(0.5, 0.0), 0.0)[0] == Approx(-0.5 / std::pow(0.5, 1.5)));
  CHECK(soft.potential(Vec<2>(0.0, 0.0)) == Approx(-2.0));
  // a particle on a circular orbit stays on it: the body force enters the integrator
  ParticleSet<2, false> p;
  p.add(1e-6, Vec<2>(1.0, 0.0), Vec<2>(0.0, 1.0), 0.01);
  Box<2> open;
  TimeStepParams ts;
  ts.dt_max = 1e-3;
  Simulation<2, kernel::CubicSpline, eos::Pressureless, regularize::None, physics::PointMass<2>> sim(
      p, open, eos::Pressureless{}, {}, ts, physics::PointMass<2>{});
  sim.run_until(2.0 * 3.141592653589793);
  CHECK(sim.particles().x[0].norm() == Approx(1.0).epsilon(1e-5));
  CHECK((sim.particles().x[0] - Vec<2>(1.0, 0.0)).norm() < 1e-4);
}
