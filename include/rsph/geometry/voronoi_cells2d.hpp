#pragma once
// What both 2D Voronoi builders (voronoi.hpp, voronoi_boost.hpp) do around the cuts: the polygon a cell is cut
// from, the bisector cut, the closing disc at open edges, and the checks that finish a cell.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/sites.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

namespace rsph::geometry {

/// The sites of a 2D build.
using SitesWithImages = PeriodicSites<2>;

namespace detail {

/// The polygon a cell is cut from, in coordinates relative to the particle: the box (walls), the box
/// widened by the image margin (periodic), and the square circumscribing the closing disc (open axes;
/// the disc itself is applied by close_with_disc once the neighbours have cut the cell).
inline ConvexPolygon initial_cell(const Point& xa, const Box<2>& box, double margin, double closing_radius) {
  const auto [lo, hi] = initial_bounds<2>(xa, box, margin, closing_radius);
  return ConvexPolygon::rectangle(lo[0], lo[1], hi[0], hi[1]);
}

/// The bisector with a site at relative position d keeps |y| <= |y - d|, i.e. d . y <= |d|^2 / 2.
inline bool cut_by_bisector(const ConvexPolygon& in, const Point& d, ConvexPolygon& out) {
  return cut_halfplane(in, d, 0.5 * d.squaredNorm(), out);
}

/// The unit edge normals of the regular 32-gon that closes cells at open edges, computed once: on a sheared
/// disk closed at 0.75 spacings a fifth of the cells reach past the disc, and their sines and cosines, taken
/// per cell, had cost a fifth of the remap. Side k lies at the closing radius along its normal.
inline const Sides& closing_polygon() {
  static const Sides table = [] {
    Sides t;
    t.n = Sides::capacity;
    for (int k = 0; k < t.n; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + 0.5) / t.n;
      t.normal[static_cast<std::size_t>(k)] = Point(std::cos(phi), std::sin(phi));
      t.offset[static_cast<std::size_t>(k)] = 1.0;
    }
    return t;
  }();
  return table;
}

/// Open axes: intersects the cell with a regular 32-gon whose inradius is the closing radius. Only the
/// sides some vertex lies beyond are tried: a side no vertex crosses cannot cut the cell (nor the points
/// between its vertices), and for most cells no vertex reaches past the radius at all. Returns whether
/// the cell was cut.
inline bool close_with_disc(ConvexPolygon*& cell, ConvexPolygon*& scratch, const Box<2>& box, double closing_radius) {
  if (box.edge[0] != Edge::open && box.edge[1] != Edge::open) return false;
  const double R2 = closing_radius * closing_radius;
  const Sides& polygon = closing_polygon();
  std::uint32_t crossed = 0;  // bit k: some vertex lies beyond side k
  for (int i = 0; i < cell->n; ++i) {
    const Point& v = (*cell)[i];
    if (v.squaredNorm() <= R2) continue;
    for (int k = 0; k < polygon.n; ++k)
      crossed |= static_cast<std::uint32_t>(polygon.normal[static_cast<std::size_t>(k)].dot(v) > closing_radius) << k;
  }
  if (crossed == 0) return false;
  *scratch = with_part_within_sides(
      *cell, polygon, crossed, [&](std::size_t k) { return closing_radius * polygon.offset[k]; },
      [](const ConvexPolygon& part) { return part; });
  std::swap(cell, scratch);
  return true;
}

/// Squared distance of the farthest vertex from the particle (cells are given relative to it).
inline double max_radius2_origin(const ConvexPolygon& p) {
  double r2 = 0.0;
  for (int i = 0; i < p.n; ++i) r2 = std::max(r2, p[i].squaredNorm());
  return r2;
}

inline void check_coincident(const ConvexPolygon& cell, std::size_t a) {
  if (cell.empty())
    throw InputError("Voronoi cells: particle " + std::to_string(a) + " coincides with another particle");
}

/// What both builders do once the neighbours have cut a cell: a coincident particle is an error, open
/// edges close the cell, and a cell reaching past the periodic images returns false (wider images needed).
/// `r2_max` is the squared farthest vertex distance of the cell as the neighbours left it (the builders
/// know it already: another pass over the vertices had cost a mispredicted loop exit per cell).
inline bool finish_cell(ConvexPolygon*& cell, ConvexPolygon*& scratch, std::size_t a, const Point& xa,
                        const Box<2>& box, double margin, double closing_radius, double r2_max) {
  check_coincident(*cell, a);
  if (close_with_disc(cell, scratch, box, closing_radius)) r2_max = max_radius2_origin(*cell);
  return !needs_more_images(r2_max, xa, box, margin);
}

}  // namespace detail

}  // namespace rsph::geometry
