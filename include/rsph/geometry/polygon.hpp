#pragma once
// Convex polygons in double precision with a fixed vertex capacity (no allocation in the hot loops):
// area, centroid, and Sutherland-Hodgman clipping by half-planes, rectangles and convex polygons.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace rsph::geometry {

using Point = Vec<2>;

/// A convex polygon, vertices counter-clockwise. Clipping a convex n-gon by a half-plane gives at most
/// n + 1 vertices; Voronoi cells rarely exceed 12 vertices, so the capacity is generous.
struct ConvexPolygon {
  static constexpr int capacity = 64;
  std::array<Point, capacity> v;
  int n = 0;

  ConvexPolygon() = default;
  // Copies only the vertices in use: polygons are copied inside the clipping loops.
  ConvexPolygon(const ConvexPolygon& o) : n(o.n) { std::copy_n(o.v.begin(), o.n, v.begin()); }
  ConvexPolygon& operator=(const ConvexPolygon& o) {
    n = o.n;
    std::copy_n(o.v.begin(), o.n, v.begin());
    return *this;
  }

  void clear() { n = 0; }
  void push(const Point& p) {
    if (n == capacity) throw NumericalError("convex polygon: more than 64 vertices (degenerate Voronoi cell)");
    v[static_cast<std::size_t>(n++)] = p;
  }
  bool empty() const { return n < 3; }
  const Point& operator[](int i) const { return v[static_cast<std::size_t>(i)]; }

  static ConvexPolygon rectangle(double x0, double y0, double x1, double y1) {
    ConvexPolygon r;
    r.push(Point(x0, y0));
    r.push(Point(x1, y0));
    r.push(Point(x1, y1));
    r.push(Point(x0, y1));
    return r;
  }
  /// Regular k-gon of circumradius R around c (a disc, closed from outside).
  static ConvexPolygon regular(const Point& c, double R, int k) {
    ConvexPolygon r;
    for (int i = 0; i < k; ++i) {
      const double phi = 2.0 * 3.14159265358979323846 * i / k;
      r.push(c + R * Point(std::cos(phi), std::sin(phi)));
    }
    return r;
  }
  void translate(const Point& d) {
    for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] += d;
  }
};

/// Shoelace area (positive for counter-clockwise order).
inline double area(const ConvexPolygon& p) {
  if (p.n < 3) return 0.0;
  double a = 0.0;
  for (int i = 0, j = p.n - 1; i < p.n; j = i++) a += p[j].x() * p[i].y() - p[i].x() * p[j].y();
  return 0.5 * a;
}

inline Point centroid(const ConvexPolygon& p) {
  double a = 0.0, cx = 0.0, cy = 0.0;
  for (int i = 0, j = p.n - 1; i < p.n; j = i++) {
    const double c = p[j].x() * p[i].y() - p[i].x() * p[j].y();
    a += c;
    cx += (p[j].x() + p[i].x()) * c;
    cy += (p[j].y() + p[i].y()) * c;
  }
  return a != 0.0 ? Point(cx / (3.0 * a), cy / (3.0 * a)) : p[0];
}

/// Largest vertex distance from c.
inline double max_radius(const ConvexPolygon& p, const Point& c) {
  double r2 = 0.0;
  for (int i = 0; i < p.n; ++i) r2 = std::max(r2, (p[i] - c).squaredNorm());
  return std::sqrt(r2);
}

namespace detail {
/// Sutherland-Hodgman for one edge: keeps the part of `in` where the signed distance beyond the edge,
/// given per vertex in s, is <= 0.
inline void clip_by_distances(const ConvexPolygon& in, const double* s, ConvexPolygon& out) {
  out.clear();
  for (int i = 0, j = in.n - 1; i < in.n; j = i++) {
    const double si = s[i], sj = s[j];
    if ((si > 0.0) != (sj > 0.0)) out.push(in[j] + (sj / (sj - si)) * (in[i] - in[j]));
    if (si <= 0.0) out.push(in[i]);
  }
  if (out.n < 3) out.clear();
}
}  // namespace detail

/// Keeps the part of `in` where normal . x <= offset (Sutherland-Hodgman, one edge).
inline void clip_halfplane(const ConvexPolygon& in, const Point& normal, double offset, ConvexPolygon& out) {
  std::array<double, ConvexPolygon::capacity> s;
  for (int i = 0; i < in.n; ++i) s[static_cast<std::size_t>(i)] = normal.dot(in[i]) - offset;
  detail::clip_by_distances(in, s.data(), out);
}

namespace detail {
/// Cuts `in` by the half-plane normal . x <= offset into `out` (Sutherland-Hodgman on distances computed
/// once). Returns false, leaving `out` alone, when no vertex lies beyond it: most candidate cuts of a
/// Voronoi cell miss it.
inline bool cut_halfplane(const ConvexPolygon& in, const Point& normal, double offset, ConvexPolygon& out) {
  std::array<double, ConvexPolygon::capacity> s;
  bool cuts = false;
  for (int i = 0; i < in.n; ++i) {
    s[static_cast<std::size_t>(i)] = normal.dot(in[i]) - offset;
    cuts |= s[static_cast<std::size_t>(i)] > 0.0;
  }
  if (cuts) clip_by_distances(in, s.data(), out);
  return cuts;
}
}  // namespace detail

/// Clips to the half-plane in place; a polygon no vertex of which lies beyond is left as it is, uncopied.
inline void clip_halfplane(ConvexPolygon& p, const Point& normal, double offset) {
  if (p.n < 3) {  // degenerate: clipping empties it
    p.clear();
    return;
  }
  ConvexPolygon tmp;
  if (detail::cut_halfplane(p, normal, offset, tmp)) p = tmp;
}

/// Axis-aligned bounding box.
struct Bounds {
  Point lo, hi;
};
inline Bounds bounds(const ConvexPolygon& p) {
  Bounds b{p[0], p[0]};
  for (int i = 1; i < p.n; ++i) {
    b.lo = b.lo.cwiseMin(p[i]);
    b.hi = b.hi.cwiseMax(p[i]);
  }
  return b;
}

/// Bounds and shoelace area in one pass over the vertices (a remap asks both of every old cell; each pass
/// over a cell's varying count of vertices ends in a mispredicted branch).
inline double area_and_bounds(const ConvexPolygon& p, Bounds& b) {
  b = {p[0], p[0]};
  double a = 0.0;
  for (int i = 0, j = p.n - 1; i < p.n; j = i++) {
    a += p[j].x() * p[i].y() - p[i].x() * p[j].y();
    b.lo = b.lo.cwiseMin(p[i]);
    b.hi = b.hi.cwiseMax(p[i]);
  }
  return p.n < 3 ? 0.0 : 0.5 * a;
}

/// Area of p inside the rectangle [x0, x1] x [y0, y1]; `pb` are p's bounds and `p_area` its area,
/// so that sides which cannot cut are skipped.
inline double clipped_area_rect(const ConvexPolygon& p, const Bounds& pb, double p_area, double x0, double y0,
                                double x1, double y1) {
  if (pb.lo.x() >= x1 || pb.hi.x() <= x0 || pb.lo.y() >= y1 || pb.hi.y() <= y0) return 0.0;
  const bool cut_x0 = pb.lo.x()<x0, cut_x1 = pb.hi.x()> x1, cut_y0 = pb.lo.y()<y0, cut_y1 = pb.hi.y()> y1;
  if (!(cut_x0 || cut_x1 || cut_y0 || cut_y1)) return p_area;
  ConvexPolygon a = p, b;
  if (cut_x0) {
    clip_halfplane(a, Point(-1, 0), -x0, b);
    a = b;
  }
  if (cut_x1) {
    clip_halfplane(a, Point(1, 0), x1, b);
    a = b;
  }
  if (cut_y0) {
    clip_halfplane(a, Point(0, -1), -y0, b);
    a = b;
  }
  if (cut_y1) {
    clip_halfplane(a, Point(0, 1), y1, b);
    a = b;
  }
  return area(a);
}

/// Area of p inside the rectangle [x0, x1] x [y0, y1].
inline double clipped_area_rect(const ConvexPolygon& p, double x0, double y0, double x1, double y1) {
  Bounds pb;
  const double p_area = area_and_bounds(p, pb);
  return clipped_area_rect(p, pb, p_area, x0, y0, x1, y1);
}

/// grid_overlaps with the number of rows NJ fixed at compile time, or given as n_j where NJ is 0.
/// A piece of edge over one column, y linear from y_min to y_max, has the mean height above a line Y of
/// F(Y) = (y_max - t)^2 / (2 (y_max - y_min)) + (u - Y), u = max(Y, y_min), t = min(u, y_max); row j takes
/// F(ys[j]) - F(ys[j+1]) times the piece's signed width. So `area` first sums, per column, width * F at each
/// line below the top one (the top line lies above the polygon: F = 0), and is differenced in place at the
/// end. The first term is a triangle, d = y_max - t high and min(d |dx / dy|, width) wide: no piece divides.
/// Every line takes every piece without a branch, a loop of fixed length where NJ is given, where the rows'
/// own loops (the rows wholly below a piece, then those it crosses) ended after counts no predictor learns.
template <int NJ = 0>
void grid_overlaps_in_rows(const ConvexPolygon& p, const double* xs, int n_i, const double* ys, int n_j, double* area) {
  const int rows = NJ > 0 ? NJ : n_j;
  std::fill_n(area, static_cast<std::size_t>(n_i) * static_cast<std::size_t>(rows), 0.0);
  for (int e = 0, prev = p.n - 1; e < p.n; prev = e++) {
    const Point& P = p[prev];
    const Point& Q = p[e];
    if (P.x() == Q.x()) continue;  // vertical edges contribute nothing
    const bool rightwards = P.x() < Q.x();
    const Point& l = rightwards ? P : Q;
    const Point& r = rightwards ? Q : P;
    const double sign = rightwards ? -1.0 : 1.0;  // the contour integral runs from P to Q
    const double rise = r.y() - l.y(), slope = rise / (r.x() - l.x());
    // level edges have no height above a line (d = 0): any finite run does
    const double run = std::min(std::abs((r.x() - l.x()) / (rise + static_cast<double>(rise == 0.0))), 1e300);
    int c = 0;
    while (c + 1 < n_i && xs[c + 1] <= l.x()) ++c;
    for (double xa = l.x(), ya = l.y(); c < n_i; ++c) {
      const bool last = c + 1 == n_i || r.x() <= xs[c + 1];
      const double xb = last ? r.x() : xs[c + 1];
      const double yb = last ? r.y() : l.y() + (xb - l.x()) * slope;
      const double width = xb - xa, weight = sign * width;
      const double y_min = std::min(ya, yb), y_max = std::max(ya, yb);
      double* column = area + static_cast<std::size_t>(c) * static_cast<std::size_t>(rows);
      column[0] += weight * (0.5 * (ya + yb) - ys[0]);  // the bottom line lies below: F is the mean height
      for (int k = 1; k < rows; ++k) {
        // min and max of two variables: compilers keep these free of branches (a max against 0 they do not)
        const double u = std::max(ys[k], y_min), d = y_max - std::min(u, y_max);
        column[k] += 0.5 * sign * d * std::min(d * run, width) + weight * (u - ys[k]);
      }
      if (last) break;
      xa = xb;
      ya = yb;
    }
  }
  for (int c = 0; c < n_i; ++c) {
    double* column = area + static_cast<std::size_t>(c) * static_cast<std::size_t>(rows);
    for (int j = 0; j + 1 < rows; ++j) column[j] -= column[j + 1];
  }
}

/// Areas of the convex polygon p inside every cell [xs[i], xs[i+1]] x [ys[j], ys[j+1]] of a rectangular
/// grid whose ascending lines xs (n_i + 1) and ys (n_j + 1) cover p's bounds; area[i * n_j + j] receives
/// the cell's area. By Green's theorem the area in column i and row j is -(contour integral of
/// clamp(y - ys[j], 0, ys[j+1] - ys[j]) dx) along p's boundary inside column i, so one pass over the
/// edges, each split at the column lines, gives every overlap at once (instead of clipping p against each
/// cell). Cells p only touches get zero or round-off crumbs of either sign; the areas sum to area(p).
/// `area` holds n_i * n_j values and is overwritten. Up to 3 rows, the count an old cell meets on a lattice
/// of about its own spacing, the loops over the rows have fixed lengths.
inline void grid_overlaps(const ConvexPolygon& p, const double* xs, int n_i, const double* ys, int n_j, double* area) {
  switch (n_j) {
    case 1:
      return grid_overlaps_in_rows<1>(p, xs, n_i, ys, n_j, area);
    case 2:
      return grid_overlaps_in_rows<2>(p, xs, n_i, ys, n_j, area);
    case 3:
      return grid_overlaps_in_rows<3>(p, xs, n_i, ys, n_j, area);
    default:
      return grid_overlaps_in_rows(p, xs, n_i, ys, n_j, area);
  }
}

/// grid_overlaps into a vector, sized n_i * n_j.
inline void grid_overlaps(const ConvexPolygon& p, const double* xs, int n_i, const double* ys, int n_j,
                          std::vector<double>& area) {
  area.resize(static_cast<std::size_t>(n_i) * static_cast<std::size_t>(n_j));
  grid_overlaps(p, xs, n_i, ys, n_j, area.data());
}

/// Whether a side of the convex polygon `window` (counter-clockwise) has all of p beyond it or within `width`
/// of it: then whatever p and the window share lies in a strip of that width along the side, inside the
/// window, so its area is at most width times the window's diameter.
inline bool apart(const ConvexPolygon& p, const ConvexPolygon& window, double width) {
  for (int i = 0, j = window.n - 1; i < window.n; j = i++) {
    const Point e = window[i] - window[j];
    const Point normal(e.y(), -e.x());  // outward, of length |e|
    const double inside = normal.dot(window[j]) - width * e.norm();
    int v = 0;
    while (v < p.n && normal.dot(p[v]) >= inside) ++v;  // stops at the first vertex well inside this side
    if (v == p.n) return true;
  }
  return false;
}

/// p intersected with a convex polygon `window` (counter-clockwise) into `out`, `scratch` the other buffer of
/// the ping-pong: a side of the window that no vertex lies beyond costs its dot products and no copy.
inline void clip_convex(const ConvexPolygon& p, const ConvexPolygon& window, ConvexPolygon& out,
                        ConvexPolygon& scratch) {
  const ConvexPolygon* cur = &p;
  ConvexPolygon* next = &out;
  for (int i = 0, j = window.n - 1; i < window.n && cur->n >= 3; j = i++) {
    const Point e = window[i] - window[j];
    const Point normal(e.y(), -e.x());  // outward for a counter-clockwise window
    if (detail::cut_halfplane(*cur, normal, normal.dot(window[j]), *next)) {
      cur = next;
      next = next == &out ? &scratch : &out;
    }
  }
  if (cur->n < 3)
    out.clear();
  else if (cur != &out)
    out = *cur;
}

/// p intersected with a convex polygon `window` (counter-clockwise).
inline ConvexPolygon clip_convex(const ConvexPolygon& p, const ConvexPolygon& window) {
  ConvexPolygon out, scratch;
  clip_convex(p, window, out, scratch);
  return out;
}

/// The sides of a convex polygon of at most 32 sides (counter-clockwise) as outward normals and offsets: x is
/// inside when normal[k] . x <= offset[k] for every k. Polygons that are moved or scaled keep the normals
/// and take their offsets anew (with_part_within_sides), so the normals are computed once.
struct Sides {
  static constexpr int capacity = 32;  ///< sides are picked by the bits of a 32-bit mask
  std::array<Point, capacity> normal;
  std::array<double, capacity> offset;
  int n = 0;
};
inline Sides sides_of(const ConvexPolygon& shape) {
  if (shape.n > Sides::capacity) throw NumericalError("sides_of: more than 32 sides");
  Sides s;
  s.n = shape.n;
  for (int i = 0, j = shape.n - 1; i < shape.n; j = i++) {
    const Point e = shape[i] - shape[j];
    const auto k = static_cast<std::size_t>(i);
    s.normal[k] = Point(e.y(), -e.x());
    s.offset[k] = s.normal[k].dot(shape[j]);
  }
  return s;
}

/// f(the part of p inside the sides k of `sides` whose bit is set in `cutting`, side k at offset_of(k)), cut
/// in increasing k; the other sides must not cut p. A side that no vertex of the part left so far lies
/// beyond is passed over without a copy.
template <class OffsetOf, class F>
auto with_part_within_sides(const ConvexPolygon& p, const Sides& sides, std::uint32_t cutting, OffsetOf&& offset_of,
                            F&& f) {
  ConvexPolygon buffers[2];
  const ConvexPolygon* cut = &p;
  int next = 0;
  for (; cutting != 0 && cut->n >= 3; cutting &= cutting - 1) {
    const auto k = static_cast<std::size_t>(std::countr_zero(cutting));
    if (detail::cut_halfplane(*cut, sides.normal[k], offset_of(k), buffers[next])) {
      cut = &buffers[next];
      next ^= 1;
    }
  }
  return f(*cut);
}

/// Area of the part of p inside the sides set in `cutting`, the polygon of `sides` moved by `shift`.
inline double area_within_sides(const ConvexPolygon& p, const Sides& sides, const Point& shift, std::uint32_t cutting) {
  return with_part_within_sides(
      p, sides, cutting, [&](std::size_t k) { return sides.offset[k] + sides.normal[k].dot(shift); },
      [](const ConvexPolygon& part) { return area(part); });
}

/// Area of p inside the convex polygon `window` (counter-clockwise): area(clip_convex(p, window)) to the bit,
/// without a copy for the sides no vertex of p lies beyond.
inline double intersection_area(const ConvexPolygon& p, const ConvexPolygon& window) {
  if (window.n > Sides::capacity) return area(clip_convex(p, window));
  const std::uint32_t all = window.n == Sides::capacity ? ~std::uint32_t{0} : (std::uint32_t{1} << window.n) - 1;
  return area_within_sides(p, sides_of(window), Point::Zero(), all);
}

}  // namespace rsph::geometry
