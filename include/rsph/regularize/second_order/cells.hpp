#pragma once
// The old cells as the second-order remap needs them all at once: each cell's vertices (relative to its
// particle), its volume, centroid and central second moments, and its Voronoi neighbours with the shared
// faces. The first-order remap visits each cell once and forgets it; gradients need the neighbours' cells.
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/voronoi.hpp"
#include "rsph/neighbors/cell_list.hpp"
#include "rsph/regularize/remap.hpp"
#include "rsph/regularize/second_order/reconstruction.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <span>
#include <vector>

namespace rsph::regularize::second_order {

/// Integrals of 1, x and x x^T over a region, x relative to the old particle.
template <int D>
struct PieceMoments {
  double area = 0.0;
  Vec<D> first = Vec<D>::Zero();
  Mat<D> second = Mat<D>::Zero();
  PieceMoments& operator+=(const PieceMoments& o) {
    area += o.area;
    first += o.first;
    second += o.second;
    return *this;
  }
};

inline PieceMoments<2> piece_moments(const geometry::Moments& m) {
  PieceMoments<2> p;
  p.area = m.area;
  p.first = m.first;
  p.second << m.xx, m.xy, m.xy, m.yy;
  return p;
}
/// The interval [l, r] (relative to the particle).
inline PieceMoments<1> interval_moments(double l, double r) {
  PieceMoments<1> p;
  p.area = r - l;
  p.first[0] = 0.5 * (r * r - l * l);
  p.second(0, 0) = (r * r * r - l * l * l) / 3.0;
  return p;
}

/// Every old cell: vertices and faces in one array each, cell a's from start[a] to start[a + 1]; face k
/// is the side that ends at vertex k (in 1D: the left end, then the right end).
template <int D>
struct CellStore {
  static constexpr std::uint32_t no_neighbour = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::size_t> start;
  std::vector<Vec<D>> vertices;
  std::vector<Face<D>> faces;
  std::vector<double> volume;
  std::vector<Vec<D>> centroid;  ///< relative to the particle
  std::vector<Mat<D>> inertia;   ///< int (x - x_c)(x - x_c)^T dA
  std::vector<double> reach;     ///< the distance from the particle to the cell's farthest point; -1: not built

  std::size_t size() const { return volume.size(); }
  /// Whether cell a was built (a remap may build some cells only); one not built has no volume.
  bool built(std::size_t a) const { return volume[a] > 0.0; }
  std::span<const Vec<D>> vertices_of(std::size_t a) const {
    return {vertices.data() + start[a], start[a + 1] - start[a]};
  }
  std::span<const Face<D>> faces_of(std::size_t a) const { return {faces.data() + start[a], start[a + 1] - start[a]}; }
  /// The cell as a polygon (2D).
  geometry::ConvexPolygon polygon(std::size_t a) const requires(D == 2) {
    geometry::ConvexPolygon p;
    for (const auto& v : vertices_of(a)) p.push(v);
    return p;
  }
};

/// Per-thread buffers the builder's visitor fills: (particle, first vertex, count) and the vertices.
struct CellsByThread {
  struct alignas(64) Part {
    std::vector<std::uint32_t> who;
    std::vector<std::uint32_t> first, count;
    std::vector<geometry::Point> vertices;
  };
  std::vector<Part> parts;
};

/// The builder's visitor: closes each cell with the region and keeps it.
template <class Region>
struct KeepCells {
  const Region* region;
  const std::vector<Vec<2>>* x;
  CellsByThread* out;
  void restart() {
    for (auto& t : out->parts) {
      t.who.clear();
      t.first.clear();
      t.count.clear();
      t.vertices.clear();
    }
  }
  void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
    auto& own = out->parts[static_cast<std::size_t>(thread)];
    geometry::ConvexPolygon closed = cell;
    if constexpr (Region::clips) region->clip((*x)[a], closed);
    own.who.push_back(static_cast<std::uint32_t>(a));
    own.first.push_back(static_cast<std::uint32_t>(own.vertices.size()));
    own.count.push_back(static_cast<std::uint32_t>(closed.n));
    for (int k = 0; k < closed.n; ++k) own.vertices.push_back(closed[k]);
  }
};

/// Vector from a to the image of b nearest to the point `near` (relative to a), across periodic axes.
template <int D>
Vec<D> image_offset(const Vec<D>& xa, const Vec<D>& xb, const Vec<D>& near, const Box<D>& box) {
  Vec<D> d = xb - xa;
  for (int k = 0; k < D; ++k)
    if (box.periodic(k)) {
      const double L = box.hi[k] - box.lo[k];
      d[k] += L * std::round((near[k] - d[k]) / L);
    }
  return d;
}

/// Cell a's faces: the side from vertex k-1 to k lies on the bisector of a and the particle at twice its foot
/// (relative to a); that particle, found in `lookup` to within 1e-6 of the distance, is the neighbour. Sides
/// on walls, closing discs and regions find none and are left out of the fit, as are sides too short for
/// their direction to be known to that accuracy.
template <bool E>
void find_faces(const ParticleSet<2, E>& p, const Box<2>& box, const neighbors::CellList<2>& lookup, std::size_t a,
                std::span<const Vec<2>> vertices, std::span<Face<2>> faces) {
  const std::size_t n = vertices.size();
  for (std::size_t k = 0; k < n; ++k) {
    Face<2>& f = faces[k];
    f.b = CellStore<2>::no_neighbour;
    const Vec<2> v0 = vertices[(k + n - 1) % n], v1 = vertices[k];
    const Vec<2> e = v1 - v0;
    const double length = e.norm();
    if (!(length > 0.0)) continue;
    const Vec<2> normal(e.y() / length, -e.x() / length);
    const double foot = normal.dot(v0);
    if (!(foot > 0.0)) continue;
    const Vec<2> predicted = 2.0 * foot * normal;
    Vec<2> target = p.x[a] + predicted;
    for (int ax = 0; ax < 2; ++ax)
      if (box.periodic(ax)) {
        const double L = box.hi[ax] - box.lo[ax];
        target[ax] -= L * std::floor((target[ax] - box.lo[ax]) / L);
      }
    const double tolerance = 1e-6 * 2.0 * foot;
    lookup.for_each_within(target, tolerance, [&](std::uint32_t b) {
      if (b == a) return;
      const Vec<2> d = image_offset<2>(p.x[a], p.x[b], predicted, box);
      if ((d - predicted).squaredNorm() <= tolerance * tolerance) {
        f.b = b;
        f.d = d;
        f.length = length;
      }
    });
  }
}

/// Volume, centroid and central second moments from the cell's own moments.
template <int D>
void set_geometry(CellStore<D>& s, std::size_t a, const PieceMoments<D>& m) {
  s.volume[a] = m.area;
  s.centroid[a] = m.first / m.area;
  s.inertia[a] = m.second - m.area * s.centroid[a] * s.centroid[a].transpose();
}

/// 2D: builds every old cell (or those `only` names) once (closed at open edges and by the region) and finds its
/// faces.
template <class Builder, bool E, class Region>
void collect_cells(const ParticleSet<2, E>& p, const Box<2>& box, Builder& builder, const RemapParams& params,
                   const Region& region, std::vector<double>& closing, CellsByThread& by_thread,
                   neighbors::CellList<2>& lookup, CellStore<2>& s, std::span<const std::uint32_t> only = {}) {
  const std::size_t n = p.n_real;
  detail::set_closing_radii(p, box, params, closing);
  by_thread.parts.resize(static_cast<std::size_t>(std::max(geometry::builder_threads(), max_threads())));
  KeepCells<Region> keep{&region, &p.x, &by_thread};
  keep.restart();
  builder.build(p.x, box, closing, keep, only);
  s.start.assign(n + 1, 0);
  for (const auto& t : by_thread.parts)
    for (std::size_t k = 0; k < t.who.size(); ++k) s.start[t.who[k] + 1] = t.count[k];
  std::partial_sum(s.start.begin(), s.start.end(), s.start.begin());
  s.vertices.resize(s.start[n]);
  s.faces.resize(s.start[n]);
  for (const auto& t : by_thread.parts)
    for (std::size_t k = 0; k < t.who.size(); ++k)
      std::copy_n(t.vertices.begin() + t.first[k], t.count[k],
                  s.vertices.begin() + static_cast<std::ptrdiff_t>(s.start[t.who[k]]));
  s.volume.resize(n);
  s.centroid.resize(n);
  s.inertia.resize(n);
  s.reach.assign(n, -1.0);
  lookup.build(p.x, geometry::detail::mean_spacing(p.x, box));
  run_parallel(n, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      if (s.start[a] == s.start[a + 1]) {  // not built
        s.volume[a] = 0.0;
        s.centroid[a].setZero();
        s.inertia[a].setZero();
        continue;
      }
      set_geometry<2>(s, a, piece_moments(geometry::moments(s.polygon(a))));
      double r2 = 0.0;
      for (const auto& v : s.vertices_of(a)) r2 = std::max(r2, v.squaredNorm());
      s.reach[a] = std::sqrt(r2);
      const std::span<Face<2>> faces(s.faces.data() + s.start[a], s.start[a + 1] - s.start[a]);
      find_faces(p, box, lookup, a, s.vertices_of(a), faces);
    }
  });
}

/// 1D: the intervals of for_each_old_interval, each with its neighbours in position order.
template <class Lattice, bool E>
void collect_cells(const ParticleSet<1, E>& p, const Box<1>& box, const Lattice& lattice, const RemapParams& params,
                   const detail::CellGrid<1>& grid, CellStore<1>& s) {
  const std::size_t n = p.n_real;
  s.start.resize(n + 1);
  for (std::size_t a = 0; a <= n; ++a) s.start[a] = 2 * a;
  s.vertices.assign(2 * n, Vec<1>::Zero());
  s.faces.assign(2 * n, Face<1>{CellStore<1>::no_neighbour, Vec<1>::Zero(), 0.0});
  s.volume.resize(n);
  s.centroid.resize(n);
  s.inertia.resize(n);
  s.reach.assign(n, -1.0);
  std::vector<std::uint32_t> order;
  order.reserve(n);
  detail::for_each_old_interval(p, box, lattice, params, grid,
                                [&](std::size_t a, double left, double right, const auto&, double) {
                                  s.vertices[2 * a] = Vec<1>(left - p.x[a][0]);
                                  s.vertices[2 * a + 1] = Vec<1>(right - p.x[a][0]);
                                  set_geometry<1>(s, a, interval_moments(left - p.x[a][0], right - p.x[a][0]));
                                  s.reach[a] = std::max(p.x[a][0] - left, right - p.x[a][0]);
                                  order.push_back(static_cast<std::uint32_t>(a));
                                });
  auto link = [&](std::uint32_t a, std::uint32_t b, std::size_t slot, double side) {
    Face<1>& f = s.faces[slot];
    f.b = b;
    f.d = image_offset<1>(p.x[a], p.x[b], Vec<1>(side * 2.0 * std::abs(s.vertices[slot][0])), box);
    f.length = 1.0;
  };
  for (std::size_t k = 0; k < n; ++k) {
    const bool wrap = box.periodic(0) && n > 1;
    if (k > 0 || wrap) link(order[k], order[(k + n - 1) % n], 2 * order[k], -1.0);
    if (k + 1 < n || wrap) link(order[k], order[(k + 1) % n], 2 * order[k] + 1, 1.0);
  }
}

}  // namespace rsph::regularize::second_order
