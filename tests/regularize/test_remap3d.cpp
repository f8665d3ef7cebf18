// The first-order remap (eqs. 6-9) in 3D: exact Voronoi polyhedra split across a cubic lattice.
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "conservation_check.hpp"

using namespace rsph;

namespace {

/// A cubic lattice of n^3 particles in [0, 1]^3 moved by `shift` (in spacings) and jittered by up to
/// `jitter` spacings, with random masses, velocities and internal energies.
ParticleSet<3, true> cubic_set(int n, double jitter, std::mt19937& rng, Vec<3> shift = Vec<3>::Zero()) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<3, true> p;
  const double dx = 1.0 / n;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        Vec<3> x((i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx);
        x += dx * shift + jitter * dx * Vec<3>(u(rng), u(rng), u(rng));
        p.add(dx * dx * dx * (1.0 + 0.5 * u(rng)), x, Vec<3>(u(rng), u(rng), u(rng)), 1.3 * dx, 1.0 + 0.5 * u(rng));
      }
  return p;
}

Box<3> unit_box(Edge edge) {
  Box<3> box;
  box.edge = {edge, edge, edge};
  return box;
}

}  // namespace

TEST_CASE("3D remap conserves mass, momentum and total energy on periodic, walled and open boxes", "[regularize][3d]") {
  std::mt19937 rng(17);
  const int n = 10;
  for (const Edge edge : {Edge::periodic, Edge::reflecting, Edge::open}) {
    for (const double jitter : {0.3, 0.0}) {
      INFO("edge " << static_cast<int>(edge) << ", jitter " << jitter);
      auto p = cubic_set(n, jitter, rng);
      if (edge == Edge::periodic)  // a shear's worth of motion: layers moved against each other, wrapped
        for (std::size_t a = 0; a < p.n_real; ++a) {
          p.x[a][0] += 0.37 / n * std::sin(6.283185307179586 * p.x[a][2]);
          unit_box(edge).wrap(p.x[a]);
        }
      geometry::LocalVoronoi3 builder;
      const auto box = unit_box(edge);
      // on the exact lattice nothing is averaged: the kinetic energy converted is round-off of either sign
      const auto stats = test::check_conserved(
          p,
          [&](auto& q) {
            return regularize::remap_onto_lattice(q, box, lattice::Cubic{1.0 / n}, builder, regularize::RemapParams{});
          },
          jitter > 0.0);
      if (edge != Edge::open) CHECK(stats.n_after == static_cast<std::size_t>(n * n * n));
    }
  }
}

TEST_CASE("3D remap: a set on the lattice's sites maps onto itself", "[regularize][3d]") {
  std::mt19937 rng(19);
  auto p = cubic_set(8, 0.0, rng);
  const auto before = p;
  geometry::LocalVoronoi3 builder;
  const auto box = unit_box(Edge::periodic);
  regularize::remap_onto_lattice(p, box, lattice::Cubic{1.0 / 8}, builder, regularize::RemapParams{1.3});
  REQUIRE(p.n_real == before.n_real);
  double worst = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    worst = std::max({worst, std::abs(p.m[a] - before.m[a]) / before.m[a], (p.x[a] - before.x[a]).norm(),
                      (p.v[a] - before.v[a]).norm(), std::abs(p.u[a] - before.u[a])});
    CHECK(p.h[a] == Approx(1.3 / 8));
  }
  CHECK(worst < 1e-12);
}

TEST_CASE("3D remap: a uniform drift of s spacings spreads a pulse by s(1 - s) Delta^2 along each axis",
          "[regularize][3d]") {
  // The pulse of §2.1 along every axis at once: the old cells are the lattice's cubes moved by s Delta along
  // each axis, so each hands (1 - s) and s to its neighbours per axis; the mass-weighted variance along every
  // axis grows by exactly s(1 - s) Delta^2 and the centroid stays.
  const int n = 10;
  const double dx = 1.0 / n;
  for (const double s : {0.1, 0.3, 0.5}) {
    ParticleSet<3, false> p;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const bool in_pulse = i >= 3 && i <= 5 && j >= 4 && j <= 5 && k >= 3 && k <= 6;
          p.add(in_pulse ? 1.0 + 0.1 * (i + 2 * j + 3 * k) : 0.0,
                Vec<3>((i + 0.5 + s) * dx, (j + 0.5 + s) * dx, (k + 0.5 + s) * dx), Vec<3>::Zero(), 1.2 * dx);
        }
    auto moments = [](const ParticleSet<3, false>& q) {
      double M = 0.0;
      Vec<3> first = Vec<3>::Zero(), second = Vec<3>::Zero();
      for (std::size_t a = 0; a < q.n_real; ++a) {
        M += q.m[a];
        first += q.m[a] * q.x[a];
        second += q.m[a] * q.x[a].cwiseProduct(q.x[a]);
      }
      const Vec<3> mean = first / M;
      return std::pair{mean, Vec<3>(second / M - mean.cwiseProduct(mean))};
    };
    const auto [mean0, var0] = moments(p);
    geometry::LocalVoronoi3 builder;
    regularize::remap_onto_lattice(p, unit_box(Edge::periodic), lattice::Cubic{dx}, builder, regularize::RemapParams{});
    const auto [mean1, var1] = moments(p);
    for (int k = 0; k < 3; ++k) {
      INFO("s = " << s << ", axis " << k);
      CHECK((var1[k] - var0[k]) / (s * (1.0 - s) * dx * dx) == Approx(1.0).epsilon(1e-11));
      CHECK(std::abs(mean1[k] - mean0[k]) < 1e-13);
    }
  }
}

TEST_CASE("3D remap: new internal energies lie within the old ones around them; bad input is named",
          "[regularize][3d]") {
  std::mt19937 rng(23);
  auto p = cubic_set(8, 0.3, rng);
  for (auto& v : p.v) v.setZero();  // no kinetic energy to convert: u is a plain average
  const auto old = p;
  geometry::LocalVoronoi3 builder;
  const auto box = unit_box(Edge::reflecting);
  regularize::remap_onto_lattice(p, box, lattice::Cubic{1.0 / 8}, builder, regularize::RemapParams{});
  for (std::size_t a = 0; a < p.n_real; ++a) {
    double lo = 1e300, hi = -1e300;
    for (std::size_t b = 0; b < old.n_real; ++b)
      if ((old.x[b] - p.x[a]).norm() < 2.0 / 8) {
        lo = std::min(lo, old.u[b]);
        hi = std::max(hi, old.u[b]);
      }
    CHECK(p.u[a] >= lo * (1.0 - 1e-14));
    CHECK(p.u[a] <= hi * (1.0 + 1e-14));
  }
  auto bad = cubic_set(4, 0.2, rng);
  bad.u[7] = std::nan("");
  CHECK_THROWS_WITH(regularize::remap_onto_lattice(bad, box, lattice::Cubic{0.25}, builder, regularize::RemapParams{}),
                    Catch::Contains("particle 7") && Catch::Contains("internal energy"));
}

TEST_CASE("3D lattice regularizer: the default builder and schedule remap a set", "[regularize][3d]") {
  using Reg = regularize::LatticeRegularizer<lattice::Cubic, schedule::EveryNSteps>;
  std::mt19937 rng(29);
  auto p = cubic_set(6, 0.25, rng);
  const auto before = conservation(p);
  Reg reg(lattice::Cubic{1.0 / 6}, schedule::EveryNSteps{1});
  StepInfo info;
  info.steps_since_last = 1;
  REQUIRE(reg.due(p, unit_box(Edge::periodic), info));
  reg.remap(p, unit_box(Edge::periodic), info);
  CHECK(p.n_real == 216);
  CHECK(std::abs(conservation(p).total_energy() - before.total_energy()) < 1e-13 * before.total_energy());
  CHECK(reg.log().size() == 1);
}

namespace {

/// Old cells' volume, centroid and central second moments (relative to their particles), from the builder.
struct CellGeometry3 {
  std::vector<double> volume;
  std::vector<Vec<3>> centroid;
  std::vector<Mat<3>> inertia;
};
CellGeometry3 geometry_of(const ParticleSet<3, true>& p, const Box<3>& box) {
  CellGeometry3 g;
  g.volume.resize(p.n_real);
  g.centroid.resize(p.n_real);
  g.inertia.resize(p.n_real);
  struct Keep {
    CellGeometry3* g;
    void restart() {}
    void operator()(int, std::size_t a, const geometry::ConvexPolyhedron& cell) {
      const auto m = geometry::moments(cell);
      g->volume[a] = m.volume;
      g->centroid[a] = m.centroid();
      g->inertia[a] = m.second - m.volume * g->centroid[a] * g->centroid[a].transpose();
    }
  };
  geometry::LocalVoronoi3 builder;
  builder.build(p.x, box, {}, Keep{&g});
  return g;
}

/// Cell averages of linear fields in 3D: m = rho(x_c) V, v = v(x_m), u = u(x_m), x_m = x_c + I grad rho / m.
struct LinearFields3 {
  Vec<3> rho_grad{0.3, -0.2, 0.25}, u_grad{0.4, 0.25, -0.3};
  Mat<3> v_grad;
  bool uniform_v = false;
  LinearFields3() { v_grad << -0.1, 0.4, 0.1, 0.2, 0.0, -0.3, 0.05, 0.15, 0.2; }
  double rho(const Vec<3>& x) const { return 1.0 + rho_grad.dot(x); }
  Vec<3> v(const Vec<3>& x) const {
    const Vec<3> v0(0.5, -0.3, 0.2);
    return uniform_v ? v0 : Vec<3>(v0 + v_grad * x);
  }
  double u(const Vec<3>& x) const { return 2.0 + u_grad.dot(x); }
  void set(ParticleSet<3, true>& p, const Box<3>& box) const {
    const auto g = geometry_of(p, box);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const Vec<3> x_c = p.x[a] + g.centroid[a];
      p.m[a] = g.volume[a] * rho(x_c);
      const Vec<3> x_m = x_c + g.inertia[a] * rho_grad / p.m[a];
      p.v[a] = v(x_m);
      p.u[a] = u(x_m);
    }
  }
  /// The largest errors of the new particles (cubes of side dx) at least `margin` inside the unit box: mass
  /// relative, velocity absolute, u relative.
  std::array<double, 3> errors(const ParticleSet<3, true>& p, double dx, double margin) const {
    std::array<double, 3> e{};
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const Vec<3> x = p.x[a];
      if (x.minCoeff() < margin || x.maxCoeff() > 1.0 - margin) continue;
      const double m = rho(x) * dx * dx * dx;
      const Vec<3> x_m = x + dx * dx / 12.0 * rho_grad / rho(x);
      e[0] = std::max(e[0], std::abs(p.m[a] - m) / m);
      e[1] = std::max(e[1], (p.v[a] - v(x_m)).norm());
      e[2] = std::max(e[2], std::abs(p.u[a] - u(x_m)) / u(x));
    }
    return e;
  }
};

regularize::RemapStats remap_second(ParticleSet<3, true>& p, const Box<3>& box, double dx,
                                    regularize::SecondOrderParams second = {}) {
  geometry::LocalVoronoi3 builder;
  return regularize::remap_second_order(p, box, lattice::Cubic{dx}, builder, regularize::RemapParams{}, second);
}

}  // namespace

TEST_CASE("3D second-order remap: linear density, velocity and energy are carried over exactly", "[regularize][3d]") {
  const int n = 10;
  const double dx = 1.0 / n;
  const auto walls = unit_box(Edge::reflecting);
  std::mt19937 rng(31);
  LinearFields3 f;
  auto p = cubic_set(n, 0.3, rng);
  f.set(p, walls);
  auto first = p, unlimited = p;
  geometry::LocalVoronoi3 builder;
  regularize::remap_onto_lattice(first, walls, lattice::Cubic{dx}, builder, regularize::RemapParams{});
  regularize::SecondOrderParams no_limiter;
  no_limiter.limit = false;
  remap_second(unlimited, walls, dx, no_limiter);
  const auto stats = remap_second(p, walls, dx);
  const auto all = f.errors(unlimited, dx, 0.0), inner = f.errors(p, dx, 2.0 * dx),
             coarse = f.errors(first, dx, 2.0 * dx);
  CHECK(all[0] < 1e-12);
  CHECK(all[1] < 1e-12);
  CHECK(inner[0] < 1e-12);
  CHECK(inner[1] < 1e-12);
  CHECK(coarse[0] > 1e-4);  // first order moves mass by the cells' jitter
  CHECK(coarse[1] > 1e-4);
  CHECK(stats.limited_cells < static_cast<std::size_t>(n * n * n - 6 * 6 * 6));  // only near the walls
  SECTION("u too, where v is uniform") {
    f.uniform_v = true;
    auto q = cubic_set(n, 0.3, rng);
    f.set(q, walls);
    remap_second(q, walls, dx);
    CHECK(f.errors(q, dx, 2.0 * dx)[2] < 1e-12);
  }
}

TEST_CASE("3D second-order remap conserves mass, momentum and total energy; rho and u stay within bounds",
          "[regularize][3d]") {
  std::mt19937 rng(37);
  const int n = 8;
  for (const Edge edge : {Edge::periodic, Edge::reflecting, Edge::open}) {
    INFO("edge " << static_cast<int>(edge));
    auto p = cubic_set(n, 0.3, rng);
    const auto box = unit_box(edge);
    test::check_conserved(
        p, [&](auto& q) { return remap_second(q, box, 1.0 / n); }, false);
  }
  auto p = cubic_set(n, 0.3, rng);
  for (auto& v : p.v) v.setZero();
  const auto old = p;
  const auto walls = unit_box(Edge::reflecting);
  const auto cells = geometry_of(old, walls);
  remap_second(p, walls, 1.0 / n);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    double lo_u = 1e300, hi_u = -1e300, lo_rho = 1e300, hi_rho = -1e300;
    for (std::size_t b = 0; b < old.n_real; ++b)
      if ((old.x[b] - p.x[a]).norm() < 2.5 / n) {
        lo_u = std::min(lo_u, old.u[b]);
        hi_u = std::max(hi_u, old.u[b]);
        lo_rho = std::min(lo_rho, old.m[b] / cells.volume[b]);
        hi_rho = std::max(hi_rho, old.m[b] / cells.volume[b]);
      }
    const double rho = p.m[a] * n * n * n;
    CHECK(p.u[a] >= lo_u * (1.0 - 1e-12));
    CHECK(p.u[a] <= hi_u * (1.0 + 1e-12));
    CHECK(rho >= lo_rho * (1.0 - 1e-12));
    CHECK(rho <= hi_rho * (1.0 + 1e-12));
  }
}

TEST_CASE("3D second-order remap spreads a drifting pulse less than first order", "[regularize][3d]") {
  // A smooth pulse on the lattice moved by s = 0.3 spacings along each axis: first order widens it by exactly
  // s(1 - s) Delta^2 per axis; second order, whose pieces carry the density's slope, by far less.
  const int n = 12;
  const double dx = 1.0 / n, s = 0.3;
  auto make = [&] {
    ParticleSet<3, true> p;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const Vec<3> x((i + 0.5 + s) * dx, (j + 0.5 + s) * dx, (k + 0.5 + s) * dx);
          const double r2 = (x - Vec<3>::Constant(0.5)).squaredNorm();
          p.add(dx * dx * dx * (1.0 + std::exp(-r2 / 0.02)), x, Vec<3>::Zero(), 1.2 * dx, 1.0);
        }
    return p;
  };
  auto variance = [&](const ParticleSet<3, true>& p) {
    double M = 0.0, var = 0.0;
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const double excess = p.m[a] - dx * dx * dx;
      M += excess;
      var += excess * (p.x[a] - Vec<3>::Constant(0.5 + s * dx)).squaredNorm();
    }
    return var / M;
  };
  auto first = make(), second = make();
  const double before = variance(first);
  geometry::LocalVoronoi3 builder;
  regularize::remap_onto_lattice(first, unit_box(Edge::periodic), lattice::Cubic{dx}, builder,
                                 regularize::RemapParams{});
  remap_second(second, unit_box(Edge::periodic), dx);
  const double grown_first = variance(first) - before, grown_second = variance(second) - before;
  // (the pulse's tails, 4e-6 of its peak at the faces, wrap across the periodic box: hence 1e-4, not 1e-12)
  CHECK(grown_first / (3.0 * s * (1.0 - s) * dx * dx) == Approx(1.0).epsilon(1e-4));
  INFO("second order's growth over first order's: " << grown_second / grown_first);
  CHECK(std::abs(grown_second) < 0.1 * grown_first);
}

TEST_CASE(
    "3D remap with closing regions: a ball, a box, a cylindrical shell and a flared disk keep the gas inside, "
    "conserving",
    "[regularize][3d]") {
  // A cloud filling each region on open axes: every old cell at the surface is cut by the region's tangent
  // plane, so no new particle sits farther outside than half a cell diagonal; both orders conserve.
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dx = 0.1;
  auto cloud = [&](auto inside) {
    ParticleSet<3, true> p;
    for (int k = -12; k < 12; ++k)
      for (int j = -12; j < 12; ++j)
        for (int i = -12; i < 12; ++i) {
          const Vec<3> x = dx * (Vec<3>(i + 0.5, j + 0.5, k + 0.5) + 0.3 * Vec<3>(u(rng), u(rng), u(rng)));
          if (inside(x)) p.add(1e-3, x, Vec<3>(u(rng), u(rng), u(rng)), 1.3 * dx, 1.0 + 0.5 * u(rng));
        }
    return p;
  };
  Box<3> open;
  const double half_diagonal = 0.5 * std::sqrt(3.0) * dx;
  auto check = [&](auto region, auto inside, auto distance_outside) {
    for (int order = 1; order <= 2; ++order) {
      auto p = cloud(inside);
      INFO("order " << order << ", " << p.n_real << " particles");
      geometry::LocalVoronoi3 builder;
      test::check_conserved(
          p,
          [&](auto& q) {
            const regularize::RemapParams params{.h_over_dx = 1.3, .min_fill = 0.5, .closing_radius_in_h = 0.75 / 1.3};
            if (order == 1) return regularize::remap_onto_lattice(q, open, lattice::Cubic{dx}, builder, params, region);
            return regularize::remap_second_order(q, open, lattice::Cubic{dx}, builder, params, {}, region);
          },
          order == 1);
      double worst = 0.0;
      for (std::size_t a = 0; a < p.n_real; ++a) worst = std::max(worst, distance_outside(p.x[a]));
      CHECK(worst <= half_diagonal);
    }
  };
  check(
      region::Ball{0.8}, [](const Vec<3>& x) { return x.norm() < 0.8; },
      [](const Vec<3>& x) { return x.norm() - 0.8; });
  check(
      region::Cuboid{Vec<3>::Constant(-0.75), Vec<3>::Constant(0.65)},
      [](const Vec<3>& x) { return x.minCoeff() > -0.75 && x.maxCoeff() < 0.65; },
      [](const Vec<3>& x) { return std::max((x.array() - 0.65).maxCoeff(), (-0.75 - x.array()).maxCoeff()); });
  check(
      region::CylindricalShell{0.3, 1.0, -0.45, 0.45},
      [](const Vec<3>& x) {
        const double R = std::hypot(x.x(), x.y());
        return R > 0.3 && R < 1.0 && std::abs(x.z()) < 0.45;
      },
      [](const Vec<3>& x) {
        const double R = std::hypot(x.x(), x.y());
        return std::max({R - 1.0, 0.3 - R, std::abs(x.z()) - 0.45});
      });
  // the cones |z| = 0.6 R: the distance outside measured normal to the cone
  check(
      region::FlaredDisk{0.3, 1.1, 0.6},
      [](const Vec<3>& x) {
        const double R = std::hypot(x.x(), x.y());
        return R > 0.3 && R < 1.1 && std::abs(x.z()) < 0.6 * R;
      },
      [](const Vec<3>& x) {
        const double R = std::hypot(x.x(), x.y());
        return std::max({R - 1.1, 0.3 - R, (std::abs(x.z()) - 0.6 * R) / std::sqrt(1.0 + 0.36)});
      });
}
