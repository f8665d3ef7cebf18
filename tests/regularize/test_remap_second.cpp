// The second-order remap: exact on linear fields, exactly conservative, bounded, and its gradient and
// limiter against brute-force computations.
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "../geometry/boost_oracle.hpp"
#include "conservation_check.hpp"
#include "particle_sets.hpp"

using namespace rsph;
using regularize::RemapParams;
using regularize::SecondOrderParams;
using test::box_with;
using test::jittered_gas;
namespace so = regularize::second_order;

namespace {

/// The old cells of p (closed in `box`), as the second-order remap sees them.
template <bool E>
so::CellStore<2> cells_of(const ParticleSet<2, E>& p, const Box<2>& box, RemapParams params = {}) {
  geometry::LocalVoronoi builder;
  so::CellStore<2> cells;
  so::CellsByThread by_thread;
  neighbors::CellList<2> lookup;
  std::vector<double> closing;
  so::collect_cells(p, box, builder, params, region::Unbounded{}, closing, by_thread, lookup, cells);
  return cells;
}

/// Gives every particle the cell averages of linear fields: m = rho(x_c) V, v = v(x_m), u = u(x_m), with x_c
/// the centroid and x_m = x_c + I grad rho / m the mass centroid of its cell.
struct LinearFields {
  Vec<2> rho_grad{0.3, -0.2}, u_grad{0.4, 0.25};
  Eigen::Matrix2d v_grad;
  bool uniform_v = false;
  LinearFields() { v_grad << -0.1, 0.4, 0.2, 0.0; }
  double rho(const Vec<2>& x) const { return 1.0 + rho_grad.dot(x); }
  Vec<2> v(const Vec<2>& x) const { return uniform_v ? Vec<2>(0.5, -0.3) : Vec<2>(Vec<2>(0.5, -0.3) + v_grad * x); }
  double u(const Vec<2>& x) const { return 2.0 + u_grad.dot(x); }
  void set(ParticleSet<2, true>& p, const Box<2>& box) const {
    const auto cells = cells_of(p, box);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const Vec<2> x_c = p.x[a] + cells.centroid[a];
      p.m[a] = cells.volume[a] * rho(x_c);
      const Vec<2> x_m = x_c + cells.inertia[a] * rho_grad / p.m[a];
      p.v[a] = v(x_m);
      p.u[a] = u(x_m);
    }
  }
  /// The mass centroid of a square lattice cell of side dx at x: x + dx^2/12 grad rho / rho(x).
  Vec<2> mass_centroid(const Vec<2>& x, double dx) const { return x + dx * dx / 12.0 * rho_grad / rho(x); }
};

struct FieldErrors {
  double mass = 0.0, velocity = 0.0, u = 0.0;
};

/// Largest errors of the new particles against the exact cell integrals, over those at least `margin` from
/// the box's edges (1 x 1).
FieldErrors errors_against(const ParticleSet<2, true>& p, const LinearFields& f, double dx, double margin) {
  FieldErrors e;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const Vec<2> x = p.x[a];
    if (x.minCoeff() < margin || x.maxCoeff() > 1.0 - margin) continue;
    const double m = f.rho(x) * dx * dx;
    e.mass = std::max(e.mass, std::abs(p.m[a] - m) / m);
    e.velocity = std::max(e.velocity, (p.v[a] - f.v(f.mass_centroid(x, dx))).norm());
    e.u = std::max(e.u, std::abs(p.u[a] - f.u(f.mass_centroid(x, dx))) / f.u(x));
  }
  return e;
}

/// The second-order remap may also turn heat into kinetic energy (its pieces carry velocity differences that
/// the old particles' means do not), so only conservation is checked, not the direction of the exchange.
template <int D, bool E, class Lattice>
regularize::RemapStats remap_checking_conservation(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice,
                                                   RemapParams params = {}, SecondOrderParams second = {}) {
  geometry::LocalVoronoi builder;
  return test::check_conserved(
      p, [&](ParticleSet<D, E>& q) { return regularize::remap_second_order(q, box, lattice, builder, params, second); },
      false);
}

}  // namespace

TEST_CASE("second-order remap: a linear field is carried onto the lattice exactly", "[regularize]") {
  const int n = 24;
  const double dx = 1.0 / n;
  const Box<2> walls = box_with(Edge::reflecting, Edge::reflecting);
  LinearFields f;
  for (const double jitter : {0.3, 0.45}) {
    INFO("jitter " << jitter);
    auto p = jittered_gas(n, jitter, 3);
    f.set(p, walls);
    auto first = p, unlimited = p;
    geometry::LocalVoronoi builder;
    regularize::remap_onto_lattice(first, walls, lattice::Square{dx}, builder, RemapParams{});
    SecondOrderParams no_limiter;
    no_limiter.limit = false;
    regularize::remap_second_order(unlimited, walls, lattice::Square{dx}, builder, RemapParams{}, no_limiter);
    const auto stats = regularize::remap_second_order(p, walls, lattice::Square{dx}, builder, RemapParams{}, {});
    // unlimited: every new particle; limited: all but the rows next to the walls, where no neighbour lies
    // beyond a cell and a gradient across the wall is cut
    const FieldErrors all = errors_against(unlimited, f, dx, 0.0), inner = errors_against(p, f, dx, 2.0 * dx);
    const FieldErrors coarse = errors_against(first, f, dx, 2.0 * dx);
    CHECK(all.mass < 1e-12);
    CHECK(all.velocity < 1e-12);
    CHECK(inner.mass < 1e-12);
    CHECK(inner.velocity < 1e-12);
    CHECK(coarse.mass > 1e-4);  // first order moves mass by the cells' jitter
    CHECK(coarse.velocity > 1e-4);
    CHECK(stats.limited_cells > 0);
    CHECK(stats.limited_cells < static_cast<std::size_t>(4 * 2 * n));
  }
  SECTION("u too, where v is uniform (a velocity gradient turns e = u + v^2/2 quadratic)") {
    f.uniform_v = true;
    auto p = jittered_gas(n, 0.3, 4);
    f.set(p, walls);
    geometry::LocalVoronoi builder;
    regularize::remap_second_order(p, walls, lattice::Square{dx}, builder, RemapParams{}, {});
    CHECK(errors_against(p, f, dx, 2.0 * dx).u < 1e-12);
  }
  SECTION("a sheared set (periodic in x, the field linear in y)") {
    f.rho_grad = Vec<2>(0.0, 0.3);
    f.u_grad = Vec<2>(0.0, 0.5);
    f.v_grad << 0.0, 0.4, 0.0, -0.2;
    const Box<2> channel = box_with(Edge::periodic, Edge::reflecting);
    for (const double shear : {0.37, 2.5}) {
      auto p = jittered_gas(n, 0.1, 5, shear);
      f.set(p, channel);
      geometry::LocalVoronoi builder;
      regularize::remap_second_order(p, channel, lattice::Square{dx}, builder, RemapParams{}, {});
      const FieldErrors e = errors_against(p, f, dx, 2.0 * dx);
      CHECK(e.mass < 1e-12);
      CHECK(e.velocity < 1e-12);
    }
  }
}

TEST_CASE("second-order remap conserves mass, momentum and total energy exactly", "[regularize]") {
  const double dx = 1.0 / 20;
  SECTION("jittered, periodic and walled, square and hexagonal lattices") {
    for (const auto& box : {box_with(Edge::periodic, Edge::periodic), box_with(Edge::reflecting, Edge::reflecting),
                            box_with(Edge::periodic, Edge::reflecting)}) {
      auto p = jittered_gas(20, 0.45, 7);
      const auto stats = remap_checking_conservation(p, box, lattice::Square{dx});
      CHECK(stats.n_after == 400);
      CHECK(stats.limited_cells > 0);  // random fields: the limiter works
      // the hexagonal lattice's rows must fill the box: 24 rows of pitch Delta sqrt(3)/2
      const lattice::Hexagonal hex{1.0 / 20};
      Box<2> rows = box;
      rows.hi[1] = 24 * hex.row_pitch();
      auto q = jittered_gas(20, 0.3, 8);
      for (std::size_t a = 0; a < q.n_real; ++a) q.x[a][1] *= rows.hi[1];
      remap_checking_conservation(q, rows, hex);
    }
  }
  SECTION("sheared as by Keplerian rotation, and without u") {
    for (const double shear : {0.1, 3.7}) {
      auto p = jittered_gas(24, 0.1, 9, shear);
      remap_checking_conservation(p, box_with(Edge::periodic, Edge::periodic), lattice::Square{1.0 / 24});
      auto q = jittered_gas<false>(24, 0.1, 10, shear);
      remap_checking_conservation(q, box_with(Edge::periodic, Edge::periodic), lattice::Square{1.0 / 24});
    }
  }
  SECTION("clustered, with open edges") {
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.5, 0.12);
    std::uniform_real_distribution<double> u(0.5, 1.5);
    ParticleSet<2, true> p;
    for (int k = 0; k < 500; ++k) p.add(u(rng) * 1e-3, Vec<2>(g(rng), g(rng)), Vec<2>(u(rng), -u(rng)), 0.03, u(rng));
    remap_checking_conservation(p, box_with(Edge::open, Edge::open), lattice::Square{0.025});
  }
  SECTION("a strong contact: u jumps by 1e6 across a moving interface (the thermal floor)") {
    auto p = jittered_gas(24, 0.3, 12);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const bool hot = p.x[a][0] > 0.5;
      p.u[a] = hot ? 1e6 : 1.0;
      p.v[a] = Vec<2>(hot ? 30.0 : -30.0, 0.0);
    }
    const auto stats =
        remap_checking_conservation(p, box_with(Edge::periodic, Edge::periodic), lattice::Square{1.0 / 24});
    INFO("first-order cells " << stats.first_order_cells << ", passes " << stats.passes);
    for (std::size_t a = 0; a < p.n_real; ++a) CHECK(p.u[a] >= 0.5);  // the floor: half the coldest feeder's u
  }
  SECTION("1D: periodic, walls and open ends") {
    for (const Edge edge : {Edge::periodic, Edge::reflecting, Edge::open}) {
      std::mt19937 rng(13);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      ParticleSet<1, true> p;
      const int n = 64;
      for (int i = 0; i < n; ++i)
        p.add((1.0 + 0.3 * u(rng)) / n, Vec<1>((i + 0.5 + 0.4 * u(rng)) / n), Vec<1>(u(rng)), 1.2 / n,
              1.0 + 0.5 * u(rng));
      Box<1> box;
      box.edge = {edge};
      remap_checking_conservation(p, box, lattice::Uniform1D{1.0 / n});
    }
  }
}

TEST_CASE("second-order remap keeps every new rho and u within the range of the old cells around it", "[regularize]") {
  // The old cells that overlap a new cell, and their Voronoi neighbours, found by brute force (Boost.Geometry
  // intersections of every old cell with every new cell); v is uniform, so u gains no heat from averaging.
  const int n = 12;
  const double dx = 1.0 / n;
  const Box<2> box = box_with(Edge::reflecting, Edge::reflecting);
  for (const unsigned seed : {21u, 22u, 23u}) {
    auto p = jittered_gas(n, 0.4, seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      p.v[a] = Vec<2>(0.3, -0.1);
      p.m[a] *= u(rng) < 0.2 ? 5.0 : 1.0;  // spikes the limiter must hold
      p.u[a] = u(rng) < 0.2 ? 10.0 : 1.0 + u(rng);
    }
    const auto cells = cells_of(p, box);
    const auto old = p;
    geometry::LocalVoronoi builder;
    regularize::remap_second_order(p, box, lattice::Square{dx}, builder, RemapParams{}, {});
    for (std::size_t k = 0; k < p.n_real; ++k) {
      const auto square = lattice::Square{dx}.cell(
          box, {static_cast<std::int64_t>(p.x[k][0] / dx), static_cast<std::int64_t>(p.x[k][1] / dx)}, Vec<2>::Zero());
      so::Range rho, uu;
      for (std::size_t a = 0; a < old.n_real; ++a) {
        geometry::ConvexPolygon c = cells.polygon(a);
        c.translate(old.x[a]);
        if (test::oracle_intersection_area(c, square) <= 1e-12 * dx * dx) continue;
        auto add = [&](std::size_t b) {
          rho.add(old.m[b] / cells.volume[b]);
          uu.add(old.u[b]);
        };
        add(a);
        for (const auto& f : cells.faces_of(a))
          if (f.b != so::CellStore<2>::no_neighbour) add(f.b);
      }
      const double rho_new = p.m[k] / (dx * dx);
      CHECK(rho_new >= rho.lo * (1.0 - 1e-12));
      CHECK(rho_new <= rho.hi * (1.0 + 1e-12));
      CHECK(p.u[k] >= uu.lo * (1.0 - 1e-12));
      CHECK(p.u[k] <= uu.hi * (1.0 + 1e-12));
    }
  }
}

TEST_CASE("second-order remap: the neighbours, gradient and limiter against brute force", "[regularize]") {
  const Box<2> box = box_with(Edge::periodic, Edge::periodic);
  auto p = jittered_gas(8, 0.4, 31);
  const auto cells = cells_of(p, box);
  SECTION("faces: every other particle whose bisector carries a side of the cell, with that side's length") {
    for (std::size_t a = 0; a < p.n_real; ++a) {
      std::vector<std::pair<std::uint32_t, double>> expected, found;
      const auto verts = cells.vertices_of(a);
      for (std::size_t b = 0; b < p.n_real; ++b)
        for (int sx = -1; sx <= 1; ++sx)
          for (int sy = -1; sy <= 1; ++sy) {
            const Vec<2> d = p.x[b] - p.x[a] + Vec<2>(sx, sy);
            if (d.squaredNorm() == 0.0) continue;
            for (std::size_t k = 0; k < verts.size(); ++k) {  // both ends of side k on the bisector
              const Vec<2> v0 = verts[(k + verts.size() - 1) % verts.size()], v1 = verts[k];
              const double s0 = d.dot(v0) - 0.5 * d.squaredNorm(), s1 = d.dot(v1) - 0.5 * d.squaredNorm();
              if (std::abs(s0) < 1e-12 && std::abs(s1) < 1e-12 && (v1 - v0).norm() > 1e-9)
                expected.emplace_back(static_cast<std::uint32_t>(b), (v1 - v0).norm());
            }
          }
      for (const auto& f : cells.faces_of(a))
        if (f.b != so::CellStore<2>::no_neighbour) found.emplace_back(f.b, f.length);
      std::sort(expected.begin(), expected.end());
      std::sort(found.begin(), found.end());
      REQUIRE(found.size() == expected.size());
      for (std::size_t k = 0; k < found.size(); ++k) {
        CHECK(found[k].first == expected[k].first);
        CHECK(found[k].second == Approx(expected[k].second).epsilon(1e-12));
      }
    }
  }
  SECTION("the density gradient is the weighted least-squares fit, solved by QR") {
    std::vector<so::Reconstruction<2>> recon(p.n_real);
    so::reconstruct_density(p, cells, recon, p.n_real);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      std::vector<so::Face<2>> faces;
      for (const auto& f : cells.faces_of(a))
        if (f.b != so::CellStore<2>::no_neighbour) faces.push_back(f);
      Eigen::MatrixXd A(faces.size(), 2);
      Eigen::VectorXd y(faces.size());
      for (std::size_t k = 0; k < faces.size(); ++k) {
        const Vec<2> r = faces[k].d + cells.centroid[faces[k].b] - cells.centroid[a];
        const double w = std::sqrt(faces[k].length / r.squaredNorm());
        A.row(static_cast<Eigen::Index>(k)) = w * r.transpose();
        y[static_cast<Eigen::Index>(k)] = w * (p.m[faces[k].b] / cells.volume[faces[k].b] - p.m[a] / cells.volume[a]);
      }
      const Vec<2> g = A.colPivHouseholderQr().solve(y);
      CHECK((recon[a].g_rho - g).norm() <= 1e-9 * g.norm());
    }
  }
  SECTION("Barth-Jespersen's phi is the largest that keeps every point within its bounds, by bisection") {
    std::mt19937 rng(32);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<Vec<2>> offsets(5);
      std::vector<double> lo(5), hi(5);
      for (std::size_t k = 0; k < 5; ++k) {
        offsets[k] = Vec<2>(u(rng), u(rng));
        lo[k] = -0.2 - std::abs(u(rng));
        hi[k] = 0.2 + std::abs(u(rng));
      }
      const Vec<2> g(3.0 * u(rng), 3.0 * u(rng));
      const double phi = so::barth_jespersen<2>(
          0.0, g, offsets, [&](std::size_t k) { return lo[k]; }, [&](std::size_t k) { return hi[k]; });
      auto inside = [&](double f) {
        for (std::size_t k = 0; k < 5; ++k) {
          const double q = f * g.dot(offsets[k]);
          if (q < lo[k] - 1e-14 || q > hi[k] + 1e-14) return false;
        }
        return true;
      };
      double a = 0.0, b = 1.0;
      if (inside(1.0)) a = 1.0;
      for (int it = 0; it < 60 && a < 1.0; ++it) (inside(0.5 * (a + b)) ? a : b) = 0.5 * (a + b);
      CHECK(phi == Approx(a).margin(1e-12));
    }
  }
}

TEST_CASE("a smooth shear across rows offset by s Delta: second order mixes less than a tenth of first order",
          "[regularize]") {
  // As the first-order test of the sliding interface (test_remap.cpp), with v_x = U tanh((y - 1/2) / w), w = 4
  // Delta, instead of a step: first order mixes s (1 - s) / 8 of each interface cell's momentum; the
  // second-order reconstruction follows the profile and converts a small fraction of that kinetic energy.
  const int n = 32;
  const double dx = 1.0 / n, U = 1.0, w = 4.0 * dx;
  for (double s : {0.25, 0.5}) {
    auto p = test::offset_halves(n, s, [&](double y) { return U * std::tanh((y - 0.5) / w); });
    const Box<2> box = box_with(Edge::periodic, Edge::reflecting);
    auto first = p;
    geometry::LocalVoronoi builder;
    const auto one = regularize::remap_onto_lattice(first, box, lattice::Square{dx}, builder, RemapParams{});
    const auto two = remap_checking_conservation(p, box, lattice::Square{dx});
    // how far each new velocity lies from the profile the old particles sample (at s = 0 both remaps give it
    // back exactly)
    auto max_error = [&](const ParticleSet<2, true>& q) {
      double e = 0.0;
      for (std::size_t a = 0; a < q.n_real; ++a)
        e = std::max(e, std::abs(q.v[a][0] - U * std::tanh((q.x[a][1] - 0.5) / w)));
      return e;
    };
    const double heat_ratio = std::abs(two.kinetic_converted) / one.kinetic_converted;
    const double mixing_ratio = max_error(p) / max_error(first);
    INFO("s = " << s << ": kinetic energy converted, first order " << one.kinetic_converted << ", second "
                << two.kinetic_converted << "; largest velocity error, first " << max_error(first) << ", second "
                << max_error(p));
    CHECK(one.kinetic_converted > 0.0);
    CHECK(heat_ratio < 0.1);
    CHECK(mixing_ratio < 0.1);
  }
}
