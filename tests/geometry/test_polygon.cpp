#include "rsph/geometry/polygon.hpp"

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "boost_oracle.hpp"

using namespace rsph::geometry;
using rsph::test::oracle_intersection_area;

namespace {
// A random convex polygon: the hull of points on a jittered circle, as a regular polygon cut by half-planes.
ConvexPolygon random_convex(std::mt19937& rng, const Point& c, double R) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ConvexPolygon p = ConvexPolygon::regular(c, R, 16);
  for (int k = 0; k < 5; ++k) {
    const double phi = 6.283185307179586 * u(rng);
    const Point nrm(std::cos(phi), std::sin(phi));
    clip_halfplane(p, nrm, nrm.dot(c) + R * (0.3 + 0.6 * u(rng)));
  }
  return p;
}
}  // namespace

TEST_CASE("polygon area, centroid and half-plane clipping", "[geometry]") {
  const auto sq = ConvexPolygon::rectangle(0, 0, 2, 1);
  CHECK(area(sq) == Approx(2.0));
  CHECK((centroid(sq) - Point(1.0, 0.5)).norm() < 1e-15);
  ConvexPolygon half = sq;
  clip_halfplane(half, Point(1, 0), 0.5);  // keep x <= 0.5
  CHECK(area(half) == Approx(0.5));
  ConvexPolygon none = sq;
  clip_halfplane(none, Point(1, 0), -1.0);
  CHECK(none.empty());
  CHECK(area(ConvexPolygon::regular(Point(0, 0), 1.0, 6)) == Approx(1.5 * std::sqrt(3.0)));
}

TEST_CASE("area and bounds in one pass equal the two passes to the bit", "[geometry]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const ConvexPolygon p = random_convex(rng, Point(u(rng), u(rng)), 0.1 + std::abs(u(rng)));
    Bounds b;
    CHECK(area_and_bounds(p, b) == area(p));
    CHECK(b.lo == bounds(p).lo);
    CHECK(b.hi == bounds(p).hi);
  }
  ConvexPolygon degenerate;  // two vertices: no area, bounds of the two
  degenerate.push(Point(0.0, 1.0));
  degenerate.push(Point(2.0, -1.0));
  Bounds b;
  CHECK(area_and_bounds(degenerate, b) == 0.0);
  CHECK(b.lo == Point(0.0, -1.0));
  CHECK(b.hi == Point(2.0, 1.0));
}

TEST_CASE("clipping agrees with Boost.Geometry's intersection", "[geometry]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const ConvexPolygon a = random_convex(rng, Point(u(rng), u(rng)), 0.5 + 0.5 * std::abs(u(rng)));
    const ConvexPolygon b = random_convex(rng, Point(u(rng), u(rng)), 0.5 + 0.5 * std::abs(u(rng)));
    CHECK(area(clip_convex(a, b)) == Approx(oracle_intersection_area(a, b)).margin(1e-13));
    // the copy-free area takes the same cuts: equal to the bit
    CHECK(intersection_area(a, b) == area(clip_convex(a, b)));
    // the sides of b moved by a shift cut as b moved does
    const Point shift(0.3 * u(rng), 0.3 * u(rng));
    ConvexPolygon moved = b;
    moved.translate(shift);
    const Sides sides = sides_of(b);
    CHECK(area_within_sides(a, sides, shift, (1u << sides.n) - 1) ==
          Approx(oracle_intersection_area(a, moved)).margin(1e-13));
    const double x0 = u(rng), y0 = u(rng);
    const auto rect = ConvexPolygon::rectangle(x0, y0, x0 + 0.4, y0 + 0.3);
    CHECK(clipped_area_rect(a, x0, y0, x0 + 0.4, y0 + 0.3) == Approx(oracle_intersection_area(a, rect)).margin(1e-13));
  }
}

TEST_CASE("rectangles tiling the plane partition a polygon's area to round-off", "[geometry]") {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 100; ++trial) {
    const ConvexPolygon cell = random_convex(rng, Point(0.013, -0.021), 0.05);
    const double dx = 0.0173;
    double sum = 0.0;
    for (int j = -5; j <= 5; ++j)
      for (int i = -5; i <= 5; ++i) sum += clipped_area_rect(cell, i * dx, j * dx, (i + 1) * dx, (j + 1) * dx);
    CHECK(std::abs(sum - area(cell)) / area(cell) < 1e-13);
  }
}

TEST_CASE("grid overlaps by Green's theorem agree with Boost.Geometry cell by cell", "[geometry]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> areas;
  for (int trial = 0; trial < 200; ++trial) {
    const ConvexPolygon cell = random_convex(rng, Point(0.3 * u(rng), 0.3 * u(rng)), 0.05 + 0.2 * std::abs(u(rng)));
    const double dx = 0.0731, dy = 0.0519;
    const Bounds b = bounds(cell);
    const int i0 = static_cast<int>(std::floor(b.lo.x() / dx)), i1 = static_cast<int>(std::floor(b.hi.x() / dx));
    const int j0 = static_cast<int>(std::floor(b.lo.y() / dy)), j1 = static_cast<int>(std::floor(b.hi.y() / dy));
    std::vector<double> xs, ys;
    for (int i = i0; i <= i1 + 1; ++i) xs.push_back(i * dx);
    for (int j = j0; j <= j1 + 1; ++j) ys.push_back(j * dy);
    const int n_i = i1 - i0 + 1, n_j = j1 - j0 + 1;
    grid_overlaps(cell, xs.data(), n_i, ys.data(), n_j, areas);
    double sum = 0.0;
    for (int i = 0; i < n_i; ++i)
      for (int j = 0; j < n_j; ++j) {
        const auto rect = ConvexPolygon::rectangle(xs[i], ys[j], xs[i + 1], ys[j + 1]);
        const double a = areas[static_cast<std::size_t>(i * n_j + j)];
        CHECK(a == Approx(oracle_intersection_area(cell, rect)).margin(1e-15));
        sum += a;
      }
    CHECK(std::abs(sum - area(cell)) / area(cell) < 1e-13);
  }
  // a polygon that is itself a grid cell lands in that cell alone, exactly
  const auto square = ConvexPolygon::rectangle(0.25, 0.5, 0.5, 0.75);
  const double xs[] = {0.0, 0.25, 0.5, 0.75}, ys[] = {0.25, 0.5, 0.75, 1.0};
  grid_overlaps(square, xs, 3, ys, 3, areas);
  for (int c = 0; c < 9; ++c) CHECK(areas[static_cast<std::size_t>(c)] == (c == 4 ? 0.0625 : 0.0));
}

namespace {
/// grid_overlaps of `cell` on the grid of spacing (dx, dy) that covers it, against Boost.Geometry cell by cell:
/// the largest difference (infinite where an area is not finite); `rows` receives the grid's row count.
double grid_discrepancy(const ConvexPolygon& cell, double dx, double dy, int& rows) {
  const Bounds b = bounds(cell);
  const int i0 = static_cast<int>(std::floor(b.lo.x() / dx)), i1 = static_cast<int>(std::floor(b.hi.x() / dx));
  const int j0 = static_cast<int>(std::floor(b.lo.y() / dy)), j1 = static_cast<int>(std::floor(b.hi.y() / dy));
  const int n_i = i1 - i0 + 1, n_j = j1 - j0 + 1;
  rows = n_j;
  std::vector<double> xs, ys, areas;
  for (int i = 0; i <= n_i; ++i) xs.push_back((i0 + i) * dx);
  for (int j = 0; j <= n_j; ++j) ys.push_back((j0 + j) * dy);
  grid_overlaps(cell, xs.data(), n_i, ys.data(), n_j, areas);
  double worst = 0.0;
  for (int i = 0; i < n_i; ++i)
    for (int j = 0; j < n_j; ++j) {
      const double a = areas[static_cast<std::size_t>(i * n_j + j)];
      if (!std::isfinite(a)) return std::numeric_limits<double>::infinity();
      const auto rect = ConvexPolygon::rectangle(xs[i], ys[j], xs[i + 1], ys[j + 1]);
      worst = std::max(worst, std::abs(a - oracle_intersection_area(cell, rect)));
    }
  return worst;
}
}  // namespace

TEST_CASE("grid overlaps on one to three rows and on more agree with Boost.Geometry, degenerate edges included",
          "[geometry]") {
  // Up to three rows the loops over the rows have fixed lengths; more rows take the general loop.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dx = 0.0731, dy = 0.0519;
  std::array<int, 5> by_rows{};  // grids of 1, 2, 3 and more rows
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const ConvexPolygon cell = random_convex(rng, Point(0.3 * u(rng), 0.3 * u(rng)), 0.02 + 0.08 * std::abs(u(rng)));
    int rows = 0;
    worst = std::max(worst, grid_discrepancy(cell, dx, dy, rows) / area(cell));
    ++by_rows[static_cast<std::size_t>(std::min(rows, 4))];
  }
  for (int rows = 1; rows <= 4; ++rows) CHECK(by_rows[static_cast<std::size_t>(rows)] > 20);
  CHECK(worst < 1e-14);
  // Edges on grid lines, vertical and level ones, vertices on grid corners, an edge that rises by one ulp, one
  // a hair from vertical and a sliver: no division by zero, no NaN, the oracle's areas.
  const double x1 = dx, y1 = dy, hair = 1e-300;
  const std::vector<std::vector<Point>> shapes = {
      {{0.0, 0.0}, {x1, 0.0}, {x1, y1}, {0.0, y1}},                                             // a grid cell itself
      {{0.2 * x1, 0.0}, {1.8 * x1, 0.0}, {1.8 * x1, 2.0 * y1}, {0.2 * x1, 2.0 * y1}},           // level and vertical
      {{0.0, 0.5 * y1}, {x1, 0.0}, {2.0 * x1, 0.5 * y1}, {x1, y1}},                             // vertices on lines
      {{0.1 * x1, 0.3 * y1}, {2.5 * x1, std::nextafter(0.3 * y1, 1.0)}, {1.2 * x1, 2.5 * y1}},  // one ulp of rise
      {{0.4 * x1, 0.2 * y1}, {0.4 * x1 + hair, 2.7 * y1}, {0.1 * x1, 1.5 * y1}},                // a hair from vertical
      {{0.5 * x1, 0.5 * y1}, {2.5 * x1, 0.5 * y1}, {2.5 * x1, 0.5 * y1 + 1e-12}},               // a sliver
      {{0.5 * x1, 0.2 * y1}, {0.7 * x1, 0.1 * y1}, {0.9 * x1, 4.5 * y1}},                       // one column, five rows
  };
  for (const auto& vertices : shapes) {
    ConvexPolygon cell;
    for (const Point& v : vertices) cell.push(v);
    REQUIRE(area(cell) > 0.0);
    int rows = 0;  // against a grid cell's area: a sliver's own area is below the round-off of its coordinates
    CHECK(grid_discrepancy(cell, dx, dy, rows) < 1e-15 * dx * dy);
  }
}
