// LocalVoronoi3 against an independent construction: voro++ (Debian's voro++-dev), where it is installed.
#include "rsph/geometry/voronoi3d.hpp"

#include <catch2/catch.hpp>

#include <voro++/voro++.hh>

#include <cmath>
#include <random>
#include <vector>

using namespace rsph;
using namespace rsph::geometry;

TEST_CASE("3D Voronoi cells agree with voro++'s, cell by cell, in periodic and walled boxes", "[geometry][3d]") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 14;
  std::vector<Point3> x;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        x.push_back((Point3(i + 0.5, j + 0.5, k + 0.5) + 0.45 * Point3(u(rng), u(rng), u(rng))) / n);
  for (const bool periodic : {true, false}) {
    Box<3> box;
    const Edge edge = periodic ? Edge::periodic : Edge::reflecting;
    box.edge = {edge, edge, edge};
    LocalVoronoi3 builder;
    const auto ours = cell_volumes(builder, x, box);
    voro::container con(0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 6, 6, 6, periodic, periodic, periodic, 8);
    for (std::size_t a = 0; a < x.size(); ++a) con.put(static_cast<int>(a), x[a].x(), x[a].y(), x[a].z());
    voro::c_loop_all loop(con);
    voro::voronoicell cell;
    double worst = 0.0;
    std::size_t compared = 0;
    if (loop.start()) do
        if (con.compute_cell(cell, loop)) {
          const auto a = static_cast<std::size_t>(loop.pid());
          worst = std::max(worst, std::abs(cell.volume() - ours[a]) / ours[a]);
          ++compared;
        }
      while (loop.inc());
    INFO((periodic ? "periodic" : "walled"));
    CHECK(compared == x.size());
    CHECK(worst < 1e-10);
  }
}
