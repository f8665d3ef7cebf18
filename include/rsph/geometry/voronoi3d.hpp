#pragma once
// Voronoi cells of 3D particles, closed against the domain, handed one by one to a visitor, as the 2D
// builders do (voronoi.hpp): periodic axes get periodic images of the particles near the faces, reflecting
// axes clip the cell to the box, and open axes close each cell with a polyhedron circumscribing the sphere of
// radius `closing_radius[a]` (the 26 planes normal to the axes, face and space diagonals of a cube).
//
// LocalVoronoi3 cuts each cell out of its initial box by the bisector planes of neighbours gathered from a
// cell list in spheres of growing radius, nearest first, until the security sphere (twice the farthest
// vertex distance) lies inside the sphere gathered: no site beyond can cut. Exact in double precision up to
// the rounding of the planes; per particle, so it runs in parallel. The cut decides topology by vertex
// signs alone (polyhedron.hpp), so sites on a lattice, four or more on one sphere, and faces lying in
// lattice planes need no special case.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/polyhedron.hpp"
#include "rsph/geometry/sites.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace rsph::geometry {

namespace detail {

/// The box a 3D cell is cut from, relative to the particle: the box (walls), the box widened by the image
/// margin (periodic), the cube circumscribing the closing sphere (open axes).
inline ConvexPolyhedron initial_cell(const Point3& xa, const Box<3>& box, double margin, double closing_radius) {
  const auto [lo, hi] = initial_bounds<3>(xa, box, margin, closing_radius);
  return ConvexPolyhedron::box(lo, hi);
}

/// The bisector plane of the particle and a site at d (d2 = |d|^2): d . y = d2 / 2, vertices within 1e-13 |d|
/// of it counting as on it; the face it makes is labelled with `site`.
inline Plane bisector(const Point3& d, double d2, std::int32_t site = -1) {
  return Plane{d, 0.5 * d2, 1e-13 * d2, site};
}

/// The unit normals of the closing polyhedron's planes beyond the cube's six: the 12 face diagonals and the
/// 8 space diagonals. Each plane lies at the closing radius along its normal.
inline const std::array<Point3, 20>& closing_normals() {
  static const std::array<Point3, 20> table = [] {
    std::array<Point3, 20> t;
    std::size_t n = 0;
    const double r2 = 1.0 / std::sqrt(2.0), r3 = 1.0 / std::sqrt(3.0);
    for (int a = 0; a < 3; ++a)
      for (int sa = -1; sa <= 1; sa += 2)
        for (int sb = -1; sb <= 1; sb += 2) {
          Point3 v = Point3::Zero();
          v[a] = sa * r2;
          v[(a + 1) % 3] = sb * r2;
          t[n++] = v;
        }
    for (int sx = -1; sx <= 1; sx += 2)
      for (int sy = -1; sy <= 1; sy += 2)
        for (int sz = -1; sz <= 1; sz += 2) t[n++] = Point3(sx * r3, sy * r3, sz * r3);
    return t;
  }();
  return table;
}

/// Open axes: cuts the cell by the closing polyhedron's diagonal planes that some vertex lies beyond (the
/// cube's own planes bound the initial cell). Returns whether the cell was cut.
inline bool close_with_sphere(ConvexPolyhedron*& cell, ConvexPolyhedron*& scratch, const Box<3>& box,
                              double closing_radius) {
  if (box.edge[0] != Edge::open && box.edge[1] != Edge::open && box.edge[2] != Edge::open) return false;
  if (max_radius2_origin(*cell) <= closing_radius * closing_radius) return false;
  bool cut = false;
  for (const Point3& n : closing_normals()) cut |= clip(cell, scratch, Plane{n, closing_radius});
  return cut;
}

}  // namespace detail

/// Local half-space builder: visit(thread, a, cell) receives each chosen particle's cell (a ConvexPolyhedron)
/// relative to x[a], each face labelled with the particle whose bisector (or whose periodic image's) made it,
/// -1 on walls and the closing polyhedron; particles of one thread arrive in increasing order. When periodic images
/// turn out too few, the builder widens them and starts again, calling visit.restart() first.
class LocalVoronoi3 : public detail::WideningBuilder<LocalVoronoi3> {
 public:
  /// Radius of the first sphere of candidates, in mean spacings: it holds the security sphere of a cubic
  /// lattice's cell (2 x 0.87 spacings), so one gather settles a near-regular cell; each further sphere is
  /// `sphere_growth` times wider.
  static constexpr double first_radius_spacings = 1.9;
  static constexpr double sphere_growth = 1.4;

 private:
  friend class detail::WideningBuilder<LocalVoronoi3>;
  struct Candidate {
    double d2;             ///< squared distance
    Point3 d;              ///< position relative to the cell's particle
    std::uint32_t source;  ///< the particle the site is (an image's source)
  };

  /// Cuts the cell by the bisector planes d . y <= |d|^2 / 2 of the candidates, nearest first. Returns false
  /// when one coincides with the particle. r2_max, the squared farthest vertex distance, follows every cut.
  static bool cut_by(std::span<Candidate> candidates, ConvexPolyhedron*& cell, ConvexPolyhedron*& scratch,
                     double& r2_max) {
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& p, const Candidate& q) { return p.d2 < q.d2; });
    for (const auto& [d2, d, source] : candidates) {
      if (d2 == 0.0) return false;
      if (d2 > 4.0 * r2_max * (1.0 + 1e-9)) break;  // sorted: no farther bisector reaches a vertex
      if (clip(cell, scratch, detail::bisector(d, d2, static_cast<std::int32_t>(source))))
        r2_max = max_radius2_origin(*cell);
    }
    return true;
  }

  /// Gathers the candidates with inner2 < d^2 <= outer2 (all beyond inner2 when outer2 is infinite) from the
  /// cells within `radius` of x_a.
  static std::size_t gather(const neighbors::CellList<3>& cells, const std::vector<std::uint32_t>& source,
                            std::size_t a, const Point3& xa, double radius, double inner2, double outer2,
                            std::vector<Candidate>& found) {
    std::size_t n_found = 0;
    cells.for_each_run_within(xa, radius, [&](const std::uint32_t* index, const Point3* at, std::size_t count) {
      grown(found, n_found + count);
      for (std::size_t s = 0; s < count; ++s) {
        const Point3 d = at[s] - xa;
        const double d2 = d.squaredNorm();
        found[n_found] = {d2, d, source[index[s]]};
        n_found += static_cast<std::size_t>((d2 > inner2) & (d2 <= outer2) & (index[s] != a));
      }
    });
    return n_found;
  }

  /// One particle's cell; false when a site coincides with it.
  bool cut_cell(const neighbors::CellList<3>& cells, std::size_t a, const Point3& xa, double spacing,
                ConvexPolyhedron*& cell, ConvexPolyhedron*& scratch, double& r2_max,
                std::vector<Candidate>& found) const {
    r2_max = max_radius2_origin(*cell);
    double inner2 = -1.0;
    for (double radius = first_radius_spacings * spacing;; radius *= sphere_growth) {
      // once the sphere's cube holds every point, the rest are all that can still cut
      const bool last = cells.covers(xa, radius);
      const double outer2 = last ? std::numeric_limits<double>::infinity() : radius * radius;
      const std::size_t n = gather(cells, sites_.source, a, xa, radius, inner2, outer2, found);
      if (!cut_by({found.data(), n}, cell, scratch, r2_max)) return false;
      if (last || 4.0 * r2_max <= outer2) return true;
      inner2 = outer2;
    }
  }

  template <class Visitor>
  bool try_build(const std::vector<Point3>& x, const Box<3>& box, const std::vector<double>& closing_radius,
                 double margin, Visitor& visit, std::span<const std::uint32_t> only) {
    detail::add_periodic_images(x, box, margin, sites_);
    const double spacing = detail::mean_spacing(x, box);
    cells_.build(sites_.x, spacing);
    std::atomic<bool> ok{true};
    rsph::run_parallel(detail::chosen_count(sites_.n_real, only), [&](int thread, std::size_t begin, std::size_t end) {
      ConvexPolyhedron buffers[2];
      std::vector<Candidate> found;
      for (std::size_t k = begin; k < end && ok.load(std::memory_order_relaxed); ++k) {
        const std::size_t a = detail::chosen(only, k);
        const Point3 xa = sites_.x[a];
        const double closing = closing_radius.empty() ? 0.0 : closing_radius[a];
        ConvexPolyhedron* cell = &buffers[0];  // cuts alternate between the buffers instead of copying
        ConvexPolyhedron* scratch = &buffers[1];
        *cell = detail::initial_cell(xa, box, margin, closing);
        double r2_max = 0.0;
        if (!cut_cell(cells_, a, xa, spacing, cell, scratch, r2_max, found) || cell->empty())
          throw InputError("Voronoi cells: particle " + std::to_string(a) + " coincides with another particle");
        if (detail::close_with_sphere(cell, scratch, box, closing)) r2_max = max_radius2_origin(*cell);
        if (detail::needs_more_images(r2_max, xa, box, margin)) {
          ok.store(false, std::memory_order_relaxed);
          break;
        }
        visit(thread, a, *cell);
      }
    });
    return ok;
  }

  // Kept from build to build: a remap every few dozen steps would otherwise fault in fresh pages each time.
  PeriodicSites<3> sites_;
  neighbors::CellList<3> cells_;
};

/// Cell volume of every particle, for tests and diagnostics.
template <class Builder>
std::vector<double> cell_volumes(Builder& builder, const std::vector<Point3>& x, const Box<3>& box,
                                 const std::vector<double>& closing_radius = {}) {
  struct Collect {
    std::vector<double>* out;
    void restart() { std::fill(out->begin(), out->end(), 0.0); }
    void operator()(int, std::size_t a, const ConvexPolyhedron& cell) { (*out)[a] = volume(cell); }
  };
  std::vector<double> volumes(x.size(), 0.0);
  builder.build(x, box, closing_radius, Collect{&volumes});
  return volumes;
}

}  // namespace rsph::geometry
