#pragma once
// Test helpers for 3D Voronoi cells: the brute-force oracle, a visitor that records what each cell is, and
// the kinds of point set the builders must survive.
#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/voronoi3d.hpp"

#include <random>
#include <string>
#include <vector>

namespace rsph::test {

using geometry::ConvexPolyhedron;
using geometry::Point3;

/// Particle a's cell from first principles: the box (widened by a period on periodic axes) cut by the
/// bisector of every other site and of every periodic image of every site, then closed at open axes.
inline ConvexPolyhedron brute_force_cell(const std::vector<Point3>& x, const Box<3>& box, std::size_t a,
                                         double closing_radius) {
  ConvexPolyhedron buffers[2];
  ConvexPolyhedron* cell = &buffers[0];
  ConvexPolyhedron* scratch = &buffers[1];
  *cell = geometry::detail::initial_cell(x[a], box, box.size().maxCoeff(), closing_radius);
  const Point3 L = box.size();
  const int reach[3] = {box.periodic(0) ? 1 : 0, box.periodic(1) ? 1 : 0, box.periodic(2) ? 1 : 0};
  for (std::size_t b = 0; b < x.size(); ++b)
    for (int i = -reach[0]; i <= reach[0]; ++i)
      for (int j = -reach[1]; j <= reach[1]; ++j)
        for (int k = -reach[2]; k <= reach[2]; ++k) {
          if (b == a && i == 0 && j == 0 && k == 0) continue;
          const Point3 d = x[b] + Point3(i * L.x(), j * L.y(), k * L.z()) - x[a];
          geometry::clip(cell, scratch, geometry::detail::bisector(d, d.squaredNorm()));
        }
  geometry::detail::close_with_sphere(cell, scratch, box, closing_radius);
  return *cell;
}

/// What a test keeps of each cell.
struct CellRecord {
  double volume = 0.0;
  Point3 centroid = Point3::Zero();  ///< relative to the particle
  int faces = 0;
};

template <class Builder>
std::vector<CellRecord> collect_cells(Builder& builder, const std::vector<Point3>& x, const Box<3>& box,
                                      const std::vector<double>& closing) {
  struct Collect {
    std::vector<CellRecord>* out;
    void restart() { std::fill(out->begin(), out->end(), CellRecord{}); }
    void operator()(int, std::size_t a, const ConvexPolyhedron& cell) {
      const auto m = geometry::moments(cell);
      (*out)[a] = {m.volume, m.centroid(), cell.nf};
    }
  };
  std::vector<CellRecord> cells(x.size());
  builder.build(x, box, closing, Collect{&cells});
  return cells;
}

struct PointSet3 {
  std::string name;
  Box<3> box;  ///< edges left for the caller
  std::vector<Point3> x;
};

/// Point sets of about n points in [0, 1]^3 of the kinds a remap meets: uniform random, clustered, a jittered
/// and an exact cubic lattice (sites on the nodes of the new lattice, faces in its planes), points on a few
/// planes (coplanar), nearly coincident pairs (1e-9 apart), and a lattice with one point on every 5th node
/// moved by 1e-12.
inline std::vector<PointSet3> voronoi3d_sets(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<PointSet3> sets;
  auto inside = [](Point3 p) { return p.cwiseMax(Point3::Zero()).cwiseMin(Point3::Ones()); };
  {
    PointSet3 s{"random", {}, {}};
    for (std::size_t i = 0; i < n; ++i) s.x.emplace_back(u(rng), u(rng), u(rng));
    sets.push_back(s);
  }
  {
    PointSet3 s{"clustered", {}, {}};
    std::vector<Point3> centres;
    for (int c = 0; c < 5; ++c) centres.emplace_back(u(rng), u(rng), u(rng));
    for (std::size_t i = 0; i < n; ++i) s.x.push_back(inside(centres[i % 5] + 0.05 * Point3(g(rng), g(rng), g(rng))));
    sets.push_back(s);
  }
  const auto side = static_cast<int>(std::round(std::cbrt(static_cast<double>(n))));
  const double dx = 1.0 / side;
  for (const double jitter : {0.3, 0.0, 1e-12}) {
    PointSet3 s{jitter == 0.3 ? "jittered lattice" : jitter == 0.0 ? "lattice" : "lattice with 1e-12 moves", {}, {}};
    int m = 0;
    for (int k = 0; k < side; ++k)
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i, ++m) {
          Point3 p((i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx);
          if (jitter == 0.3) p += 0.3 * dx * Point3(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
          if (jitter == 1e-12 && m % 5 == 0) p += 1e-12 * Point3(g(rng), g(rng), g(rng));
          s.x.push_back(p);
        }
    sets.push_back(s);
  }
  {
    PointSet3 s{"coplanar", {}, {}};
    for (std::size_t i = 0; i < n; ++i) s.x.emplace_back(u(rng), u(rng), 0.1 + 0.2 * static_cast<double>(i % 5));
    sets.push_back(s);
  }
  {
    PointSet3 s{"nearly coincident pairs", {}, {}};
    for (std::size_t i = 0; i < n / 2; ++i) {
      const Point3 p(0.01 + 0.98 * u(rng), 0.01 + 0.98 * u(rng), 0.01 + 0.98 * u(rng));
      s.x.push_back(p);
      s.x.push_back(p + 1e-9 * Point3(g(rng), g(rng), g(rng)));
    }
    sets.push_back(s);
  }
  return sets;
}

}  // namespace rsph::test
