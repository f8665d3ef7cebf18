#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/voronoi3d.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "voronoi3d_sets.hpp"

using namespace rsph;
using namespace rsph::geometry;
using rsph::test::brute_force_cell;
using rsph::test::CellRecord;
using rsph::test::collect_cells;

TEST_CASE("3D Voronoi cells equal the brute-force cells (the box cut by every bisector plane)", "[geometry][3d]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Edge kinds[3] = {Edge::periodic, Edge::reflecting, Edge::open};
  double worst_volume = 0.0, worst_centroid = 0.0;
  int compared = 0;
  for (int trial = 0; trial < 27; ++trial) {
    Box<3> box;
    box.hi = Point3(1.0, 0.8, 1.2);
    for (int k = 0; k < 3; ++k)
      box.edge[static_cast<std::size_t>(k)] = kinds[(trial / (k == 0 ? 1 : k == 1 ? 3 : 9)) % 3];
    const int n = 40 + 7 * (trial % 5);
    std::vector<Point3> x;
    for (int i = 0; i < n; ++i) x.emplace_back(u(rng) * box.hi.x(), u(rng) * box.hi.y(), u(rng) * box.hi.z());
    const std::vector<double> closing(x.size(), 0.25);
    LocalVoronoi3 builder;
    const auto cells = collect_cells(builder, x, box, closing);
    for (std::size_t a = 0; a < x.size(); ++a) {
      const Moments3 oracle = moments(brute_force_cell(x, box, a, closing[a]));
      const double V = oracle.volume;
      worst_volume = std::max(worst_volume, std::abs(cells[a].volume - V) / V);
      worst_centroid = std::max(worst_centroid, (cells[a].centroid - oracle.centroid()).norm() / std::cbrt(V));
      ++compared;
    }
  }
  CHECK(compared > 1000);
  CHECK(worst_volume < 1e-12);
  CHECK(worst_centroid < 1e-12);
}

TEST_CASE("3D Voronoi cells tile closed boxes, on random, jittered and degenerate lattice sets", "[geometry][3d]") {
  std::mt19937 rng(5);
  for (const auto& set : rsph::test::voronoi3d_sets(rng, 1500)) {
    for (const Edge edge : {Edge::periodic, Edge::reflecting}) {
      Box<3> box = set.box;
      box.edge = {edge, edge, edge};
      LocalVoronoi3 builder;
      const auto volumes = cell_volumes(builder, set.x, box);
      double total = 0.0, smallest = 1e300;
      for (double v : volumes) {
        total += v;
        smallest = std::min(smallest, v);
      }
      INFO(set.name << (edge == Edge::periodic ? " periodic" : " walled"));
      CHECK(std::abs(total - box.volume()) / box.volume() < 1e-12);
      CHECK(smallest > 0.0);
    }
  }
}

TEST_CASE("3D Voronoi cells on a cubic lattice are the lattice's cubes, sites on nodes and faces in planes",
          "[geometry][3d]") {
  Box<3> box;
  box.edge = {Edge::periodic, Edge::reflecting, Edge::periodic};
  const int n = 6;
  std::vector<Point3> x;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) x.emplace_back((i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n);
  LocalVoronoi3 builder;
  const auto cells = collect_cells(builder, x, box, {});
  for (std::size_t a = 0; a < x.size(); ++a) {
    CHECK(cells[a].volume == Approx(1.0 / (n * n * n)).epsilon(1e-13));
    CHECK(cells[a].centroid.norm() < 1e-14);
    CHECK(cells[a].faces == 6);
  }
}

TEST_CASE("3D Voronoi cells: open axes closed by the sphere's polyhedron, bad input refused", "[geometry][3d]") {
  Box<3> box;  // open on every axis
  const std::vector<Point3> one{Point3(0.3, -2.0, 7.0)};
  LocalVoronoi3 builder;
  const auto cells = collect_cells(builder, one, box, {0.5});
  // the cube cut by the 20 diagonal planes at the radius: between the inscribed sphere and the cube
  CHECK(cells[0].volume > 4.0 / 3.0 * M_PI * 0.125);
  CHECK(cells[0].volume < 1.0);
  CHECK(cells[0].centroid.norm() < 1e-15);
  CHECK(cells[0].faces == 26);

  std::vector<Point3> twins{Point3(0.1, 0.2, 0.3), Point3(0.5, 0.5, 0.5), Point3(0.1, 0.2, 0.3)};
  Box<3> walled;
  walled.edge = {Edge::reflecting, Edge::reflecting, Edge::reflecting};
  CHECK_THROWS_WITH(cell_volumes(builder, twins, walled), Catch::Contains("coincides"));
  twins[2] = Point3(0.1, 1.2, 0.3);
  CHECK_THROWS_WITH(cell_volumes(builder, twins, walled), Catch::Contains("outside the domain along axis 1"));
  twins[2] = Point3(0.1, std::nan(""), 0.3);
  CHECK_THROWS_WITH(cell_volumes(builder, twins, walled), Catch::Contains("non-finite"));
}

TEST_CASE("3D Voronoi faces name their neighbours: symmetric, with equal areas, walls unnamed", "[geometry][3d]") {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Box<3> box;
  box.edge = {Edge::periodic, Edge::reflecting, Edge::periodic};
  std::vector<Point3> x;
  for (int i = 0; i < 300; ++i) x.emplace_back(u(rng), u(rng), u(rng));
  // (a, b) -> area of a's face towards b, summed over faces (a small box can make two faces to one particle);
  // per thread, as the builder visits cells on every thread
  using Areas = std::map<std::pair<std::size_t, std::size_t>, double>;
  std::vector<Areas> per_thread(static_cast<std::size_t>(builder_threads()));
  std::vector<double> wall_per_thread(per_thread.size(), 0.0);
  struct Faces {
    std::vector<Areas>* area;
    std::vector<double>* wall;
    void restart() {}
    void operator()(int thread, std::size_t a, const ConvexPolyhedron& cell) {
      const auto t = static_cast<std::size_t>(thread);
      for (int f = 0; f < cell.nf; ++f) {
        const double A = area_vector(cell, f).norm();
        if (cell.label[static_cast<std::size_t>(f)] < 0)
          (*wall)[t] += A;
        else
          (*area)[t][{a, static_cast<std::size_t>(cell.label[static_cast<std::size_t>(f)])}] += A;
      }
    }
  };
  LocalVoronoi3 builder;
  builder.build(x, box, {}, Faces{&per_thread, &wall_per_thread});
  Areas area;
  double wall_area = 0.0;
  for (std::size_t t = 0; t < per_thread.size(); ++t) {
    for (const auto& [ab, A] : per_thread[t]) area[ab] += A;
    wall_area += wall_per_thread[t];
  }
  CHECK(area.size() > 300 * 10);
  double worst = 0.0;
  for (const auto& [ab, A] : area) {
    const auto it = area.find({ab.second, ab.first});
    REQUIRE(it != area.end());
    worst = std::max(worst, std::abs(it->second - A) / A);
  }
  CHECK(worst < 1e-10);
  CHECK(wall_area == Approx(2.0 * box.size().x() * box.size().z()).epsilon(1e-12));  // the two walls in y
}
