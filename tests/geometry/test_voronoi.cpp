#include "rsph/geometry/voronoi.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <numbers>
#include <numeric>
#include <random>

using namespace rsph;
using namespace rsph::geometry;

namespace {

std::vector<Point> jittered(int n, double jitter, unsigned seed, double shear = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::vector<Point> x;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double px = (i + 0.5 + u(rng)) * dx + shear * ((j + 0.5) * dx - 0.5);
      px -= std::floor(px);  // sheared rows wrap in the periodic x
      x.emplace_back(px, (j + 0.5 + u(rng)) * dx);
    }
  return x;
}

/// O(N^2) oracle: each cell cut by every other point's bisector, images included.
std::vector<double> brute_force_areas(const std::vector<Point>& x, const Box<2>& box) {
  std::vector<double> out;
  for (std::size_t a = 0; a < x.size(); ++a) {
    ConvexPolygon cell = geometry::detail::initial_cell(x[a], box, 1.0, 0.0);
    for (std::size_t b = 0; b < x.size(); ++b)
      for (int ix = -1; ix <= 1; ++ix)
        for (int iy = -1; iy <= 1; ++iy) {
          if ((ix != 0 && !box.periodic(0)) || (iy != 0 && !box.periodic(1))) continue;
          if (b == a && ix == 0 && iy == 0) continue;
          const Point img = x[b] + Point(ix * (box.hi[0] - box.lo[0]), iy * (box.hi[1] - box.lo[1]));
          const Point d = img - x[a];
          clip_halfplane(cell, d, 0.5 * d.squaredNorm());  // keeps the half nearer x[a]
        }
    out.push_back(area(cell));
  }
  return out;
}

template <class B>
std::vector<double> areas_of(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing = {}) {
  B builder;
  return cell_areas(builder, x, box, closing);
}

double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

Box<2> box_with(Edge ex, Edge ey) {
  Box<2> b;
  b.edge = {ex, ey};
  return b;
}

}  // namespace

TEST_CASE("Voronoi cells tile a periodic box and match the brute-force oracle", "[voronoi]") {
  const auto box = box_with(Edge::periodic, Edge::periodic);
  const auto x = jittered(14, 0.45, 1);
  const auto oracle = brute_force_areas(x, box);
  const auto local = areas_of<LocalVoronoi>(x, box);
  const auto boost = areas_of<BoostVoronoi>(x, box);
  CHECK(sum(local) == Approx(1.0).epsilon(1e-13));
  CHECK(sum(boost) == Approx(1.0).epsilon(1e-13));
  for (std::size_t a = 0; a < x.size(); ++a) {
    CHECK(local[a] == Approx(oracle[a]).epsilon(1e-11));
    CHECK(boost[a] == Approx(local[a]).epsilon(1e-9));
  }
}

TEST_CASE("the dual hull settles almost every cell and leaves walls and near-coincident sites to the clips",
          "[voronoi]") {
  // Each set's cells against the brute-force oracle, and how many took their first cut from the dual hull.
  struct Case {
    const char* name;
    std::vector<Point> x;
    Box<2> box;
    double min_share, max_share;  // of cells from the hull
  };
  auto paired = jittered(16, 0.3, 9);
  for (std::size_t a = 0; a + 1 < paired.size(); a += 5) paired[a + 1] = paired[a] + Point(1e-9, 0.4e-9);
  const std::vector<Case> cases = {
      {"jittered, periodic", jittered(16, 0.3, 8), box_with(Edge::periodic, Edge::periodic), 0.99, 1.0},
      {"regular lattice (co-circular sites)", jittered(16, 0.0, 8), box_with(Edge::periodic, Edge::periodic), 1.0, 1.0},
      // cells at the walls are clipped to the box: 60 of the 256 touch a wall
      {"jittered, walls", jittered(16, 0.3, 8), box_with(Edge::reflecting, Edge::reflecting), 0.7, 0.78},
      // a pair 1e-9 apart bounds each other's cells by nearly parallel sides, and so do their neighbours' cells
      {"near-coincident pairs", paired, box_with(Edge::periodic, Edge::periodic), 0.3, 0.9},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    LocalVoronoi builder;
    const auto local = cell_areas(builder, c.x, c.box);
    const auto oracle = brute_force_areas(c.x, c.box);
    double worst = 0.0;
    for (std::size_t a = 0; a < c.x.size(); ++a) worst = std::max(worst, std::abs(local[a] - oracle[a]) / oracle[a]);
    CHECK(worst < 1e-11);
    CHECK(sum(local) == Approx(1.0).epsilon(1e-12));
    const double share = static_cast<double>(builder.cells_from_hull()) / static_cast<double>(c.x.size());
    INFO("share from the hull " << share);
    CHECK(share >= c.min_share);
    CHECK(share <= c.max_share);
  }
}

TEST_CASE("the local and Boost.Polygon builders agree on every cell", "[voronoi]") {
  struct Case {
    const char* name;
    std::vector<Point> x;
    Box<2> box;
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Point> clustered;
  for (int c = 0; c < 6; ++c) {
    const Point centre(0.15 + 0.7 * u(rng), 0.15 + 0.7 * u(rng));
    for (int k = 0; k < 60; ++k) clustered.push_back(centre + 0.08 * Point(u(rng) - 0.5, u(rng) - 0.5));
  }
  for (int k = 0; k < 40; ++k) clustered.emplace_back(u(rng), u(rng));
  const std::vector<Case> cases = {
      {"jittered, walls", jittered(30, 0.4, 2), box_with(Edge::reflecting, Edge::reflecting)},
      {"sheared (Keplerian-like), periodic x", jittered(30, 0.05, 3, 0.73), box_with(Edge::periodic, Edge::reflecting)},
      {"clustered, periodic", clustered, box_with(Edge::periodic, Edge::periodic)},
      {"regular lattice (co-circular points)", jittered(20, 0.0, 4), box_with(Edge::periodic, Edge::periodic)},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    const auto local = areas_of<LocalVoronoi>(c.x, c.box);
    const auto boost = areas_of<BoostVoronoi>(c.x, c.box);
    CHECK(sum(local) == Approx(1.0).epsilon(1e-12));
    double worst = 0.0;
    for (std::size_t a = 0; a < c.x.size(); ++a) worst = std::max(worst, std::abs(local[a] - boost[a]) / local[a]);
    CHECK(worst < 1e-9);
  }
}

TEST_CASE("a build of chosen cells visits exactly those, identical to the full build's", "[voronoi]") {
  const auto box = box_with(Edge::periodic, Edge::reflecting);
  const auto x = jittered(24, 0.3, 7);
  std::vector<std::uint32_t> only;
  for (std::uint32_t a = 3; a < x.size(); a += 7) only.push_back(a);
  auto check = [&](auto builder) {
    const auto all = cell_areas(builder, x, box);
    struct Collect {
      std::vector<double>* out;
      std::vector<int>* visits;
      void restart() {
        std::fill(out->begin(), out->end(), 0.0);
        std::fill(visits->begin(), visits->end(), 0);
      }
      void operator()(int, std::size_t a, const ConvexPolygon& cell) {
        (*out)[a] = area(cell);
        ++(*visits)[a];
      }
    };
    std::vector<double> chosen(x.size(), 0.0);
    std::vector<int> visits(x.size(), 0);
    builder.build(x, box, {}, Collect{&chosen, &visits}, only);
    int visited = 0;
    for (std::size_t a = 0; a < x.size(); ++a) {
      const bool wanted = std::binary_search(only.begin(), only.end(), static_cast<std::uint32_t>(a));
      CHECK(visits[a] == (wanted ? 1 : 0));
      if (wanted) CHECK(chosen[a] == all[a]);  // the same cuts in the same order: the same bits
      visited += visits[a];
    }
    CHECK(visited == static_cast<int>(only.size()));
  };
  check(LocalVoronoi{});
  check(BoostVoronoi{});
}

TEST_CASE("open edges close cells with a disc of the given radius", "[voronoi]") {
  const auto box = box_with(Edge::open, Edge::open);
  const std::vector<Point> x = {Point(0, 0), Point(1, 0), Point(0.5, 0.8)};
  const std::vector<double> R(3, 0.3);
  const auto a = areas_of<LocalVoronoi>(x, box, R);
  const auto b = areas_of<BoostVoronoi>(x, box, R);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(a[i] > 0.9 * 3.14159 * 0.09);  // isolated: the whole (32-gon) disc
    CHECK(a[i] < 1.01 * 3.14159 * 0.09);
    CHECK(b[i] == Approx(a[i]).epsilon(1e-12));
  }
}

TEST_CASE("cells reaching past the closing radius are cut by exactly the closing square and 32-gon", "[voronoi]") {
  const auto box = box_with(Edge::open, Edge::open);
  // The oracle: the square circumscribing the closing disc, cut by every side of the 32-gon.
  auto closed = [](ConvexPolygon cell, double R) {
    clip_halfplane(cell, Point(1, 0), R);
    clip_halfplane(cell, Point(-1, 0), R);
    clip_halfplane(cell, Point(0, 1), R);
    clip_halfplane(cell, Point(0, -1), R);
    for (int k = 0; k < 32; ++k) {
      const double phi = 2.0 * 3.14159265358979323846 * (k + 0.5) / 32.0;
      clip_halfplane(cell, Point(std::cos(phi), std::sin(phi)), R);
    }
    return cell;
  };
  SECTION("an isolated particle") {
    const double R = 0.3;
    const auto a = areas_of<LocalVoronoi>({Point(0.2, -0.1)}, box, {R});
    // The 32-gon of inradius R (area 32 R^2 tan t, t = pi/32) has vertices on the axes at R / cos t; the
    // square cuts off four tips, each a triangle of height R (1 / cos t - 1) on a base 2 R tan(t / 2).
    const double t = std::numbers::pi / 32.0;
    const double exact = 32.0 * R * R * std::tan(t) - 4.0 * R * R * std::tan(0.5 * t) * (1.0 / std::cos(t) - 1.0);
    CHECK(a[0] == Approx(exact).epsilon(1e-13));
    CHECK(area(closed(ConvexPolygon::rectangle(-1, -1, 1, 1), R)) == Approx(exact).epsilon(1e-13));
  }
  SECTION("a jittered patch closed at 0.75 spacings, against cutting every cell by all sides") {
    auto x = jittered(12, 0.3, 9);
    const double dx = 1.0 / 12.0, R = 0.75 * dx;
    const std::vector<double> closing(x.size(), R);
    const auto local = areas_of<LocalVoronoi>(x, box, closing);
    const auto boost = areas_of<BoostVoronoi>(x, box, closing);
    int closed_inside = 0;  // cells of the patch's interior that the closing cut
    for (std::size_t a = 0; a < x.size(); ++a) {
      ConvexPolygon cell = ConvexPolygon::rectangle(-4.0, -4.0, 4.0, 4.0);
      for (std::size_t b = 0; b < x.size(); ++b)
        if (b != a) clip_halfplane(cell, x[b] - x[a], 0.5 * (x[b] - x[a]).squaredNorm());
      const double open_area = area(cell), closed_area = area(closed(cell, R));
      CHECK(local[a] == Approx(closed_area).epsilon(1e-12));
      CHECK(boost[a] == Approx(closed_area).epsilon(1e-12));
      const bool interior = std::min({x[a].x(), x[a].y(), 1.0 - x[a].x(), 1.0 - x[a].y()}) > 2.0 * dx;
      closed_inside += interior && closed_area < open_area * (1.0 - 1e-9);
    }
    CHECK(closed_inside > 10);
  }
}

TEST_CASE("coincident particles and particles outside the domain are refused", "[voronoi]") {
  auto x = jittered(8, 0.2, 6);
  const auto box = box_with(Edge::periodic, Edge::periodic);
  auto dup = x;
  dup[10] = dup[11];
  CHECK_THROWS_WITH(areas_of<LocalVoronoi>(dup, box), Catch::Contains("coincides with another particle"));
  CHECK_THROWS_WITH(areas_of<BoostVoronoi>(dup, box), Catch::Contains("coincides with another particle"));
  auto out = x;
  out[3] = Point(1.5, 0.5);
  CHECK_THROWS_WITH(areas_of<LocalVoronoi>(out, box), Catch::Contains("particle 3 lies outside the domain"));
}

TEST_CASE("sparse, clustered and outlying sets in walled boxes: every cell exact", "[voronoi]") {
  // The local builder stopped once its disc's square held every point, though it had cut only by those in
  // the disc: a neighbour just outside never cut, and cells of sparse walled sets came out too large.
  auto check = [](const std::vector<Point>& x, const Box<2>& box) {
    const auto oracle = brute_force_areas(x, box);
    const auto local = areas_of<LocalVoronoi>(x, box);
    const auto boost = areas_of<BoostVoronoi>(x, box);
    REQUIRE(local.size() == x.size());
    const double domain = (box.hi[0] - box.lo[0]) * (box.hi[1] - box.lo[1]);
    CHECK(std::abs(sum(local) - domain) < 1e-12 * domain);
    CHECK(std::abs(sum(boost) - domain) < 1e-12 * domain);
    double worst = 0.0;
    for (std::size_t a = 0; a < x.size(); ++a) worst = std::max(worst, std::abs(local[a] - oracle[a]) / oracle[a]);
    CHECK(worst < 1e-10);
  };
  for (unsigned seed = 0; seed < 200; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int n = 2 + static_cast<int>(seed % 7);
    std::vector<Point> x;
    for (int i = 0; i < n; ++i) x.push_back(seed % 3 == 0 ? Point(0.1 * u(rng), 0.1 * u(rng)) : Point(u(rng), u(rng)));
    INFO("seed " << seed << ", " << n << " particles");
    check(x, box_with(Edge::reflecting, Edge::reflecting));
  }
  // A cluster of 3000 and three far outliers in the corners of a walled box.
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.3, 0.01);
  std::vector<Point> x;
  for (int i = 0; i < 3000; ++i) x.emplace_back(std::clamp(g(rng), 0.0, 1.0), std::clamp(g(rng), 0.0, 1.0));
  x.emplace_back(0.999, 0.999);
  x.emplace_back(0.001, 0.998);
  x.emplace_back(0.997, 0.002);
  check(x, box_with(Edge::reflecting, Edge::reflecting));
}

TEST_CASE("a collinear set in a walled box goes to BoostVoronoi instead of O(N^2) scans", "[voronoi]") {
  // 2 893 particles on one line: each cell is a strip reaching both walls, and the local builder's discs
  // would gather every particle of the line for every cell (0.96 s here, 57 s before the cell list was capped).
  std::vector<Point> x;
  for (int i = 0; i < 2893; ++i) x.emplace_back((i + 0.5) / 2893, 0.5);
  const auto box = box_with(Edge::reflecting, Edge::reflecting);
  LocalVoronoi local;
  const auto areas = cell_areas(local, x, box);
  CHECK(local.handed_to_boost());
  const auto boost = areas_of<BoostVoronoi>(x, box);
  CHECK(areas == boost);
  CHECK(std::abs(sum(areas) - 1.0) < 1e-12);
  CHECK(areas[1000] == Approx(1.0 / 2893).epsilon(1e-9));
  // a jittered lattice stays with the local builder
  LocalVoronoi regular;
  cell_areas(regular, jittered(32, 0.3, 4), box);
  CHECK(!regular.handed_to_boost());
}
