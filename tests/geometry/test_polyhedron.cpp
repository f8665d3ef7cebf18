#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/polyhedron.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>

using namespace rsph::geometry;
using rsph::Mat;

namespace {

// A random convex polyhedron around c: a cube cut by random planes at 0.3-0.9 of its half-width.
ConvexPolyhedron random_convex(std::mt19937& rng, const Point3& c, double R, int cuts = 12) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  ConvexPolyhedron buffers[2];
  ConvexPolyhedron* p = &buffers[0];
  ConvexPolyhedron* scratch = &buffers[1];
  *p = ConvexPolyhedron::box(c - Point3::Constant(R), c + Point3::Constant(R));
  for (int k = 0; k < cuts; ++k) {
    const Point3 n = Point3(g(rng), g(rng), g(rng)).normalized();
    clip(p, scratch, Plane{n, n.dot(c) + R * (0.3 + 0.6 * u(rng))});
  }
  return *p;
}

double mat_error(const Mat<3>& a, const Mat<3>& b) { return (a - b).cwiseAbs().maxCoeff(); }

// Every face's corners are distinct vertex indices and every directed edge appears once, its reverse once:
// the surface is closed and consistently oriented.
bool closed_surface(const ConvexPolyhedron& p) {
  std::vector<int> count(static_cast<std::size_t>(p.nv * p.nv), 0);
  for (int f = 0; f < p.nf; ++f) {
    const int b = p.face_start[static_cast<std::size_t>(f)], e = p.face_start[static_cast<std::size_t>(f) + 1];
    for (int k = b; k < e; ++k) {
      const int i = p.corner[static_cast<std::size_t>(k)],
                j = p.corner[static_cast<std::size_t>(k + 1 < e ? k + 1 : b)];
      ++count[static_cast<std::size_t>(i * p.nv + j)];
    }
  }
  for (int i = 0; i < p.nv; ++i)
    for (int j = 0; j < p.nv; ++j)
      if (count[static_cast<std::size_t>(i * p.nv + j)] != count[static_cast<std::size_t>(j * p.nv + i)] ||
          count[static_cast<std::size_t>(i * p.nv + j)] > 1)
        return false;
  return true;
}

/// The planes of a grid of spacing dx (through the origin) around a cell, and the cells per axis.
std::pair<std::array<std::array<double, 8>, 3>, std::array<int, 3>> grid_around(const ConvexPolyhedron& cell,
                                                                                double dx) {
  std::array<std::array<double, 8>, 3> planes{};
  std::array<int, 3> n{};
  for (int k = 0; k < 3; ++k) {
    const auto [lo, hi] = extent(cell, k);
    const double first = std::floor(lo / dx);
    n[static_cast<std::size_t>(k)] = static_cast<int>(std::floor(hi / dx) - first) + 1;
    for (int c = 0; c <= n[static_cast<std::size_t>(k)]; ++c)
      planes[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)] = (first + c) * dx;
  }
  return {planes, n};
}

}  // namespace

TEST_CASE("polyhedron: a box's volume and moments are exact", "[geometry][3d]") {
  const Point3 lo(-0.3, 0.2, 1.0), hi(0.5, 1.1, 1.7);
  const auto b = ConvexPolyhedron::box(lo, hi);
  CHECK(closed_surface(b));
  const Moments3 m = moments(b);
  const Point3 L = hi - lo, c = 0.5 * (lo + hi);
  const double V = L.prod();
  CHECK(m.volume == Approx(V).epsilon(1e-14));
  CHECK(volume(b) == Approx(V).epsilon(1e-14));
  CHECK((m.centroid() - c).norm() < 1e-14);
  // int x_i x_j = V (c_i c_j + delta_ij L_i^2 / 12)
  Mat<3> second = V * c * c.transpose();
  for (int k = 0; k < 3; ++k) second(k, k) += V * L[k] * L[k] / 12.0;
  CHECK(mat_error(m.second, second) < 1e-14);
}

TEST_CASE("polyhedron: a split by any plane conserves volume and moments, each side on its side", "[geometry][3d]") {
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  int both = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const ConvexPolyhedron p = random_convex(rng, Point3(u(rng), u(rng), u(rng)), 1.0);
    REQUIRE(closed_surface(p));
    const Moments3 whole = moments(p);
    const Point3 n = Point3(g(rng), g(rng), g(rng)).normalized();
    const Plane plane{n, n.dot(whole.centroid()) + 0.6 * u(rng)};
    ConvexPolyhedron below, above;
    const Side side = split(p, plane, &below, &above);
    if (side != Side::both) continue;
    ++both;
    REQUIRE(closed_surface(below));
    REQUIRE(closed_surface(above));
    for (int i = 0; i < below.nv; ++i) REQUIRE(plane.distance(below[i]) <= 1e-12);
    for (int i = 0; i < above.nv; ++i) REQUIRE(plane.distance(above[i]) >= -1e-12);
    Moments3 sum = moments(below);
    sum += moments(above);
    const double scale = whole.volume;
    worst = std::max({worst, std::abs(sum.volume - whole.volume) / scale, (sum.first - whole.first).norm() / scale,
                      mat_error(sum.second, whole.second) / scale});
  }
  CHECK(both > 200);
  CHECK(worst < 1e-13);
}

TEST_CASE("polyhedron: degenerate splits (a face in the plane, a plane through an edge or a vertex)",
          "[geometry][3d]") {
  const auto cube = ConvexPolyhedron::box(Point3::Zero(), Point3::Ones());
  ConvexPolyhedron below, above;
  // faces lying in the plane: the cube is wholly on one side
  CHECK(split(cube, AxisPlane{0, 0.0}, &below, &above) == Side::above);
  CHECK(split(cube, AxisPlane{2, 1.0}, &below, &above) == Side::below);
  // a plane through two opposite edges: two prisms of half the volume
  REQUIRE(split(cube, Plane{Point3(1.0, -1.0, 0.0), 0.0}, &below, &above) == Side::both);
  CHECK(volume(below) == Approx(0.5).epsilon(1e-15));
  CHECK(volume(above) == Approx(0.5).epsilon(1e-15));
  CHECK(closed_surface(below));
  CHECK(closed_surface(above));
  // a plane through three vertices cuts off a corner of volume 1/6; the rest keeps 5/6
  REQUIRE(split(cube, Plane{Point3(1.0, 1.0, 1.0), 1.0}, &below, &above) == Side::both);
  CHECK(volume(below) == Approx(1.0 / 6.0).epsilon(1e-15));
  CHECK(volume(above) == Approx(5.0 / 6.0).epsilon(1e-15));
  // the rest split again through the cut's own vertices stays closed and exact
  ConvexPolyhedron b2, a2;
  const ConvexPolyhedron rest = above;
  REQUIRE(split(rest, AxisPlane{0, 0.5}, &b2, &a2) == Side::both);
  CHECK(volume(b2) + volume(a2) == Approx(5.0 / 6.0).epsilon(1e-15));
  CHECK(closed_surface(b2));
  CHECK(closed_surface(a2));
}

TEST_CASE("polyhedron: a face that rounding leaves a hair's breadth either side of the plane splits closed",
          "[geometry][3d]") {
  // the unit cube with the corners of its face x = 1 alternately 1e-15 beyond and short of the plane, as a
  // Voronoi face lying on a lattice plane comes out of rounding: the plane crosses that face four times
  const double e = 1e-15;
  ConvexPolyhedron cube;
  for (int i = 0; i < 8; ++i) {
    double x = (i & 1) ? 1.0 : 0.0;
    if (i == 1 || i == 7) x += e;
    if (i == 3 || i == 5) x -= e;
    cube.add_vertex(Point3(x, (i & 2) ? 1.0 : 0.0, (i & 4) ? 1.0 : 0.0));
  }
  static constexpr std::uint16_t faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                                {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    cube.open_face();
    for (std::uint16_t i : f) cube.add_corner(i);
    cube.close_face();
  }
  REQUIRE(closed_surface(cube));
  ConvexPolyhedron below, above;
  REQUIRE(split(cube, AxisPlane{0, 1.0}, &below, &above) == Side::both);
  CHECK(closed_surface(below));
  CHECK(closed_surface(above));
  CHECK(volume(below) + volume(above) == Approx(volume(cube)).epsilon(1e-15));
  CHECK(std::abs(volume(above)) < 1e-15);
  // and the grid split of the remap goes through it
  GridPieceScratch scratch;
  const double planes[] = {-1.0, 1.0, 2.0}, others[] = {-1.0, 2.0};
  double total = 0.0;
  for_each_grid_piece(cube, {planes, others, others}, {2, 1, 1}, scratch,
                      [&](std::array<int, 3>, const ConvexPolyhedron& piece) { total += volume(piece); });
  CHECK(total == Approx(volume(cube)).epsilon(1e-15));
}

TEST_CASE("polyhedron: grid pieces tile the cell, a lattice node splits a cube into eight", "[geometry][3d]") {
  GridPieceScratch scratch;
  {
    // a cube centred on a lattice node: eight octants of volume 1, their faces in lattice planes
    const auto cube = ConvexPolyhedron::box(Point3::Constant(-1.0), Point3::Constant(1.0));
    const double lines[3] = {-1.0, 0.0, 1.0};
    int pieces = 0;
    for_each_grid_piece(cube, {lines, lines, lines}, {2, 2, 2}, scratch,
                        [&](std::array<int, 3> idx, const ConvexPolyhedron& piece) {
                          ++pieces;
                          const Moments3 m = moments(piece);
                          CHECK(m.volume == Approx(1.0).epsilon(1e-15));
                          for (int k = 0; k < 3; ++k) CHECK(m.centroid()[k] == Approx(idx[k] == 0 ? -0.5 : 0.5));
                        });
    CHECK(pieces == 8);
  }
  // random cells on a grid of spacing 0.37: each piece equals the cell clipped by its grid cell's six planes,
  // and the pieces' moments sum to the cell's
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_sum = 0.0, worst_piece = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    const ConvexPolyhedron cell = random_convex(rng, Point3(u(rng), u(rng), u(rng)) * 0.2, 0.5);
    const double dx = 0.37;
    const auto [planes, n] = grid_around(cell, dx);
    const Moments3 whole = moments(cell);
    Moments3 sum;
    for_each_grid_piece(cell, {planes[0].data(), planes[1].data(), planes[2].data()}, n, scratch,
                        [&](std::array<int, 3> idx, const ConvexPolyhedron& piece) {
                          const Moments3 m = moments(piece);
                          sum += m;
                          ConvexPolyhedron buffers[2];
                          ConvexPolyhedron *q = &buffers[0], *s = &buffers[1];
                          *q = cell;
                          for (int k = 0; k < 3; ++k) {
                            const auto kk = static_cast<std::size_t>(k);
                            const auto c = static_cast<std::size_t>(idx[kk]);
                            clip(q, s, AxisPlane{k, planes[kk][c + 1]});
                            Point3 nrm = Point3::Zero();
                            nrm[k] = -1.0;
                            clip(q, s, Plane{nrm, -planes[kk][c]});
                          }
                          worst_piece = std::max(worst_piece, std::abs(volume(*q) - m.volume) / whole.volume);
                        });
    worst_sum =
        std::max({worst_sum, std::abs(sum.volume - whole.volume) / whole.volume,
                  (sum.first - whole.first).norm() / whole.volume, mat_error(sum.second, whole.second) / whole.volume});
  }
  CHECK(worst_sum < 1e-13);
  CHECK(worst_piece < 1e-13);
}

TEST_CASE("polyhedron: grid measures (z pieces as differences below planes) equal the pieces' own", "[geometry][3d]") {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  GridPieceScratch scratch;
  double worst = 0.0;
  int pieces = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const ConvexPolyhedron cell = random_convex(rng, Point3(u(rng), u(rng), u(rng)) * 0.2, 0.5);
    const double dx = 0.29;
    const auto [planes, n] = grid_around(cell, dx);
    const std::array<const double*, 3> at{planes[0].data(), planes[1].data(), planes[2].data()};
    std::map<std::array<int, 3>, Moments3> built;
    for_each_grid_piece(cell, at, n, scratch,
                        [&](std::array<int, 3> idx, const ConvexPolyhedron& piece) { built[idx] = moments(piece); });
    const double V = volume(cell);
    for_each_grid_measure<MomentMeasure>(cell, at, n, scratch, [&](std::array<int, 3> idx, const Moments3& m) {
      const Moments3 b = built.count(idx) ? built[idx] : Moments3{};
      worst = std::max({worst, std::abs(m.volume - b.volume) / V, (m.first - b.first).norm() / V,
                        mat_error(m.second, b.second) / V});
      ++pieces;
    });
    for_each_grid_measure<VolumeMeasure>(cell, at, n, scratch, [&](std::array<int, 3> idx, double v) {
      worst = std::max(worst, std::abs(v - (built.count(idx) ? built[idx].volume : 0.0)) / V);
    });
  }
  CHECK(pieces > 500);
  CHECK(worst < 1e-13);
}
