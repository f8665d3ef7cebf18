#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>

using namespace rsph;

namespace {

using Switched = physics::SwitchedViscosity;
template <class... Terms>
using Gas = Simulation<2, kernel::CubicSpline, eos::IdealGas, regularize::None, Terms...>;

Box<2> periodic_box() {
  Box<2> b;
  b.edge = {Edge::periodic, Edge::periodic};
  return b;
}

/// An n x n lattice in the periodic unit box (jittered by `jitter` spacings) with velocity v(x) and u = 1.
template <class V>
ParticleSet<2, true> lattice_gas(int n, double jitter, V&& v) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  ParticleSet<2, true> p;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec<2> x((i + 0.5 + jitter * U(rng)) * dx, (j + 0.5 + jitter * U(rng)) * dx);
      p.add(dx * dx, x, v(x), 1.3 * dx, 1.0);
    }
  return p;
}

}  // namespace

TEST_CASE("Balsara's factor: one in pure compression, near zero in pure shear or rotation", "[physics]") {
  const Switched sw{{1.0, 2.0}};
  Mat<2> compress = -Mat<2>::Identity();  // v = -x
  Mat<2> shear;                           // v = (y, 0): d v_x / d y = 1
  shear << 0.0, 1.0, 0.0, 0.0;
  Mat<2> rotate;  // v = Omega (-y, x): solid rotation, curl 2 Omega
  rotate << 0.0, -1.0, 1.0, 0.0;
  CHECK(sw.switch_factor<2>(compress, 1.0, 0.01) == Approx(2.0 / (2.0 + 1e-2)).epsilon(1e-14));
  CHECK(sw.switch_factor<2>(shear, 1.0, 0.01) == 0.0);
  CHECK(sw.switch_factor<2>(rotate, 1.0, 0.01) == 0.0);
  Mat<2> mixed = compress + 10.0 * rotate;  // |div| 2, |curl| 20
  CHECK(sw.switch_factor<2>(mixed, 1.0, 0.01) == Approx(2.0 / 22.01).epsilon(1e-14));
  CHECK(physics::curl_norm<3>(Mat<3>::Identity()) == 0.0);
  CHECK(physics::balsara_factor(0.0, 0.0, 0.0, 1.0, 1e-4) == 0.0);  // at rest and cold: off
}

TEST_CASE("the switched viscosity's pair: Monaghan's Pi scaled by the pair's mean factor", "[physics]") {
  physics::Pair<2> pr;
  pr.r_ab = Vec<2>(0.01, 0.0);
  pr.r = 0.01;
  pr.v_ab = Vec<2>(-0.3, 0.1);  // approaching
  pr.grad_W = Vec<2>(-2.0, 0.0);
  pr.h_ab = 0.013;
  pr.m_a = pr.m_b = 1e-4;
  pr.rho_a = pr.rho_b = 1.0;
  pr.cs_a = pr.cs_b = 1.0;
  pr.switch_a = 0.2;
  pr.switch_b = 0.6;
  const auto full = physics::ArtificialViscosity{1.0, 2.0}.pair(pr);
  const auto scaled = physics::ArtificialViscosity{0.4, 0.8}.pair(pr);
  const auto got = Switched{{1.0, 2.0}}.pair(pr);
  CHECK(got.dv_dt.x() == Approx(scaled.dv_dt.x()).epsilon(1e-14));
  CHECK(got.du_dt == Approx(scaled.du_dt).epsilon(1e-14));
  CHECK(std::abs(got.dv_dt.x()) < 0.5 * std::abs(full.dv_dt.x()));
  const auto off = Switched{}.pair(pr);  // alpha = beta = 0
  CHECK(off.dv_dt.norm() == 0.0);
  CHECK(off.du_dt == 0.0);
}

TEST_CASE("switched viscosity conserves momentum and heats a random flow", "[physics]") {
  auto gas = lattice_gas(20, 0.3, [](const Vec<2>& x) {
    return Vec<2>(0.5 * std::sin(2 * std::numbers::pi * x.y()) - 0.3 * std::sin(2 * std::numbers::pi * x.x()),
                  0.4 * std::cos(2 * std::numbers::pi * x.x()));
  });
  Gas<Switched> sim(gas, periodic_box(), eos::IdealGas{1.4}, {}, {}, Switched{{1.0, 2.0}});
  const auto start = sim.totals();
  double scale = 0.0;
  for (std::size_t a = 0; a < sim.particles().n_real; ++a) scale += sim.particles().m[a] * sim.particles().v[a].norm();
  for (int s = 0; s < 30; ++s) sim.step();
  const auto end = sim.totals();
  CHECK((end.momentum - start.momentum).norm() / scale < 1e-12);
  CHECK(std::abs(end.total_energy() - start.total_energy()) / start.total_energy() < 1e-3);
  CHECK(end.thermal > start.thermal);
}

TEST_CASE("the switch spares a shear flow and leaves a compression to the viscosity", "[physics]") {
  // The heating rate sum_a m_a du_a/dt of the viscosity alone (less the inviscid gas's) at the start, on a
  // lattice: in the shear layer v_x = 0.2 sin(2 pi y) the velocity gradient's divergence vanishes and the switch
  // turns the viscosity off; in the converging streams v_x = -0.5 sin(2 pi x) there is no curl, and the switch
  // leaves most of it on (f = 1 but where the divergence passes through zero).
  const auto heating = [](const auto& sim) {
    double sum = 0.0;
    for (std::size_t a = 0; a < sim.particles().n_real; ++a) sum += sim.particles().m[a] * sim.particles().du_dt[a];
    return sum;
  };
  const auto rates = [&](auto v) {
    const Gas<physics::ArtificialViscosity> plain(lattice_gas(24, 0.0, v), periodic_box(), eos::IdealGas{1.4}, {}, {},
                                                  physics::ArtificialViscosity{1.0, 2.0});
    const Gas<Switched> switched(lattice_gas(24, 0.0, v), periodic_box(), eos::IdealGas{1.4}, {}, {},
                                 Switched{{1.0, 2.0}});
    const Gas<> inviscid(lattice_gas(24, 0.0, v), periodic_box(), eos::IdealGas{1.4}, {}, {});
    return std::pair{heating(plain) - heating(inviscid), heating(switched) - heating(inviscid)};
  };
  const auto [shear_plain, shear_switched] =
      rates([](const Vec<2>& x) { return Vec<2>(0.2 * std::sin(2 * std::numbers::pi * x.y()), 0.0); });
  CHECK(shear_plain > 1e-4);
  CHECK(std::abs(shear_switched) < 1e-9 * shear_plain);
  const auto [compress_plain, compress_switched] =
      rates([](const Vec<2>& x) { return Vec<2>(-0.5 * std::sin(2 * std::numbers::pi * x.x()), 0.0); });
  CHECK(compress_plain > 1e-3);
  CHECK(compress_switched > 0.9 * compress_plain);
  CHECK(compress_switched <= compress_plain * (1.0 + 1e-12));
}

TEST_CASE("the switched viscosity off changes nothing, with one step or in blocks", "[physics]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-0.2, 0.2);
  const auto v = [&](const Vec<2>&) { return Vec<2>(U(rng), U(rng)); };
  const auto gas = lattice_gas(16, 0.2, v);
  for (int max_bin : {0, 2}) {
    TimeStepParams ts;
    ts.max_bin = max_bin;
    Gas<> without(gas, periodic_box(), eos::IdealGas{1.4}, {}, ts);
    Gas<Switched> with(gas, periodic_box(), eos::IdealGas{1.4}, {}, ts, Switched{});
    for (int s = 0; s < 20; ++s) {
      without.step();
      with.step();
    }
    const auto& a = without.particles();
    const auto& b = with.particles();
    REQUIRE(a.n_real == b.n_real);
    for (std::size_t i = 0; i < a.n_real; ++i) {
      CHECK(a.x[i] == b.x[i]);
      CHECK(a.v[i] == b.v[i]);
      CHECK(a.u[i] == b.u[i]);
    }
  }
}
