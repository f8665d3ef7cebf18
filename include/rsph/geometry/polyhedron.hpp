#pragma once
// Convex polyhedra in double precision with a fixed capacity (no allocation in the hot loops): the 3D
// Voronoi cells and their pieces in lattice cells. Faces are cycles of vertex indices, counter-clockwise
// seen from outside, so a vertex may have any degree (a lattice node where eight cells meet is one vertex,
// not a cluster).
//
// A plane splits a polyhedron by the signs of its vertices alone, as r3d does (Powell & Abel 2015, J.
// Comput. Phys. 297, 340): a vertex with s <= 0 goes below, one with s > 0 above, each edge whose ends differ
// gets one new vertex that both pieces share, and the caps are chained from the faces' crossings. Topology
// never depends on an intersection's rounding, so faces lying in the plane, vertices on it and vertices of
// any degree need no special case: a piece with no vertex strictly on its side is the whole polyhedron on
// the other. Moments of any piece come from the divergence theorem over its faces (moments.hpp's 3D part).
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

namespace rsph::geometry {

using Point3 = Vec<3>;

/// A convex polyhedron: vertices, and faces as cycles of vertex indices (counter-clockwise from outside).
struct ConvexPolyhedron {
  /// Voronoi cells have about 15 faces and 27 vertices on average; the sparse cells between clusters of
  /// points have well over 100 faces.
  static constexpr int max_vertices = 512, max_faces = 256, max_corners = 1536;
  std::array<Point3, max_vertices> v;
  std::array<std::uint16_t, max_corners> corner;        ///< every face's vertex indices, face after face
  std::array<std::uint16_t, max_faces + 1> face_start;  ///< face f: corner[face_start[f] .. face_start[f + 1])
  /// What made each face: the label of the plane that cut it (a Voronoi neighbour's index), -1 for none.
  std::array<std::int32_t, max_faces> label;
  int nv = 0, nf = 0;

  ConvexPolyhedron() { face_start[0] = 0; }
  // Copies only what is in use: polyhedra are copied inside the cutting loops.
  ConvexPolyhedron(const ConvexPolyhedron& o) { *this = o; }
  ConvexPolyhedron& operator=(const ConvexPolyhedron& o) {
    nv = o.nv;
    nf = o.nf;
    std::copy_n(o.v.begin(), o.nv, v.begin());
    std::copy_n(o.face_start.begin(), o.nf + 1, face_start.begin());
    std::copy_n(o.label.begin(), o.nf, label.begin());
    std::copy_n(o.corner.begin(), o.face_start[static_cast<std::size_t>(o.nf)], corner.begin());
    return *this;
  }

  bool empty() const { return nf == 0; }
  void clear() {
    nv = nf = 0;
    face_start[0] = 0;
  }
  const Point3& operator[](int i) const { return v[static_cast<std::size_t>(i)]; }

  int add_vertex(const Point3& p) {
    if (nv == max_vertices) throw NumericalError("convex polyhedron: more than 512 vertices (degenerate cell)");
    v[static_cast<std::size_t>(nv)] = p;
    return nv++;
  }
  void add_corner(int i) {
    const int at = face_start[static_cast<std::size_t>(nf) + 1];
    if (at == max_corners) throw NumericalError("convex polyhedron: more than 1536 face corners (degenerate cell)");
    corner[static_cast<std::size_t>(at)] = static_cast<std::uint16_t>(i);
    ++face_start[static_cast<std::size_t>(nf) + 1];
  }
  /// Faces are written corner by corner between open_face and close_face; a face of fewer than three
  /// corners is dropped.
  void open_face(std::int32_t face_label = -1) {
    if (nf == max_faces) throw NumericalError("convex polyhedron: more than 256 faces (degenerate cell)");
    face_start[static_cast<std::size_t>(nf) + 1] = face_start[static_cast<std::size_t>(nf)];
    label[static_cast<std::size_t>(nf)] = face_label;
  }
  void close_face() {
    if (face_start[static_cast<std::size_t>(nf) + 1] - face_start[static_cast<std::size_t>(nf)] >= 3) ++nf;
  }

  /// The box [lo, hi].
  static ConvexPolyhedron box(const Point3& lo, const Point3& hi) {
    ConvexPolyhedron b;
    for (int i = 0; i < 8; ++i)
      b.add_vertex(Point3((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z()));
    // vertex i has bit 0 for x, 1 for y, 2 for z; each face counter-clockwise seen from outside
    static constexpr std::uint16_t faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                                  {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (const auto& f : faces) {
      b.open_face();
      for (std::uint16_t i : f) b.add_corner(i);
      b.close_face();
    }
    return b;
  }
};

/// a . (b x c): six times the volume of the tetrahedron of the origin and a, b, c.
inline double triple(const Point3& a, const Point3& b, const Point3& c) {
  return a.x() * (b.y() * c.z() - b.z() * c.y()) + a.y() * (b.z() * c.x() - b.x() * c.z()) +
         a.z() * (b.x() * c.y() - b.y() * c.x());
}

/// A plane n . x = c, cutting by s = n . x - c. Vertices within `tolerance` of it (in units of s) count as
/// lying on it: the rounding of a bisector's s, about 1e-16 |c|, would otherwise shave slivers of no volume
/// off cells whose vertices it passes through (every cell of a regular lattice).
struct Plane {
  Point3 n;
  double c;
  double tolerance = 0.0;
  std::int32_t label = -1;  ///< given to the face the plane makes
  double distance(const Point3& x) const { return n.dot(x) - c; }
  /// Where the edge from a (s_a <= tolerance) to b (s_b > tolerance) meets the plane.
  Point3 meet(const Point3& a, const Point3& b, double s_a, double s_b) const {
    return a + std::max(0.0, s_a / (s_a - s_b)) * (b - a);
  }
};

/// A lattice plane x_axis = c: the new vertices are set on it exactly, so neighbouring pieces share them.
struct AxisPlane {
  int axis;
  double c;
  static constexpr double tolerance = 0.0;
  static constexpr std::int32_t label = -1;
  double distance(const Point3& x) const { return x[axis] - c; }
  Point3 meet(const Point3& a, const Point3& b, double s_a, double s_b) const {
    Point3 x = a + (s_a / (s_a - s_b)) * (b - a);
    x[axis] = c;
    return x;
  }
};

/// Where a split left the polyhedron.
enum class Side { below, above, both };

namespace detail {

/// The edges a plane crosses, each with its new vertex in both pieces and the cap's chains; found again by
/// the edge's end below (a list per vertex: a vertex has a few edges).
struct Crossings {
  static constexpr int capacity = ConvexPolyhedron::max_corners / 2;
  std::array<std::uint16_t, capacity> to;                         ///< the edge's end above
  std::array<std::int16_t, capacity> link;                        ///< the next crossing from the same end below
  std::array<std::uint16_t, capacity> in_below, in_above;         ///< the new vertex's index in each piece
  std::array<std::int16_t, capacity> next_below, next_above;      ///< the next crossing along each piece's cap
  std::array<std::int16_t, ConvexPolyhedron::max_vertices> head;  ///< per vertex below: its first crossing
  int n = 0;

  explicit Crossings(int n_vertices) { std::fill_n(head.begin(), n_vertices, std::int16_t{-1}); }

  /// The crossing of edge (b below, a above), created on first sight.
  template <class P>
  int find_or_add(const ConvexPolyhedron& in, const double* s, int b, int a, const P& plane, ConvexPolyhedron* below,
                  ConvexPolyhedron* above) {
    for (int c = head[static_cast<std::size_t>(b)]; c >= 0; c = link[static_cast<std::size_t>(c)])
      if (to[static_cast<std::size_t>(c)] == a) return c;
    if (n == capacity) throw NumericalError("convex polyhedron: too many edges cross a plane");
    const auto c = static_cast<std::size_t>(n);
    to[c] = static_cast<std::uint16_t>(a);
    link[c] = head[static_cast<std::size_t>(b)];
    head[static_cast<std::size_t>(b)] = static_cast<std::int16_t>(n);
    const Point3 x = plane.meet(in[b], in[a], s[b], s[a]);
    if (below) in_below[c] = static_cast<std::uint16_t>(below->add_vertex(x));
    if (above) in_above[c] = static_cast<std::uint16_t>(above->add_vertex(x));
    next_below[c] = next_above[c] = -1;
    return n++;
  }
};

/// Closes a piece with the cycles of `next` (one face each; one in all for a convex polyhedron).
inline void add_caps(ConvexPolyhedron& piece, const Crossings& x,
                     const std::array<std::int16_t, Crossings::capacity>& next,
                     const std::array<std::uint16_t, Crossings::capacity>& index, std::int32_t label) {
  std::array<bool, Crossings::capacity> done;
  std::fill_n(done.begin(), x.n, false);
  for (int start = 0; start < x.n; ++start) {
    if (done[static_cast<std::size_t>(start)]) continue;
    piece.open_face(label);
    int c = start, steps = 0;
    do {
      if (c < 0 || ++steps > x.n) throw NumericalError("convex polyhedron: a cut left an open surface");
      done[static_cast<std::size_t>(c)] = true;
      piece.add_corner(index[static_cast<std::size_t>(c)]);
      c = next[static_cast<std::size_t>(c)];
    } while (c != start);
    piece.close_face();
  }
}

/// Face f of `in`, all on one side, into that side's piece (corners renumbered by `at`).
inline void copy_face(const ConvexPolyhedron& in, int f, const std::uint16_t* at, ConvexPolyhedron& piece) {
  const int begin = in.face_start[static_cast<std::size_t>(f)], end = in.face_start[static_cast<std::size_t>(f) + 1];
  piece.open_face(in.label[static_cast<std::size_t>(f)]);
  for (int k = begin; k < end; ++k) piece.add_corner(at[in.corner[static_cast<std::size_t>(k)]]);
  piece.close_face();
}

/// Face f of `in`, which the plane crosses: its corners on each side, a crossing's vertex wherever the side
/// changes. The piece below holds the edge from each rise X to the next fall Y, X -> Y, and the piece above the
/// edge from each fall Y to the next rise X, Y -> X, so their caps, which run the other way, continue with Y -> X
/// below and X -> Y above. A face crossed twice pairs the same two crossings both ways; a face that rounding
/// has made cross four times or more (one lying in the plane, its corners a rounding either side) pairs them
/// differently below and above.
template <class P>
void split_face(const ConvexPolyhedron& in, int f, const double* s, const std::uint8_t* up, const std::uint16_t* at,
                const P& plane, Crossings& x, ConvexPolyhedron* below, ConvexPolyhedron* above) {
  const int begin = in.face_start[static_cast<std::size_t>(f)], end = in.face_start[static_cast<std::size_t>(f) + 1];
  if (below) below->open_face(in.label[static_cast<std::size_t>(f)]);
  if (above) above->open_face(in.label[static_cast<std::size_t>(f)]);
  int pending_up = -1, first_down = -1, pending_down = -1, first_up = -1;
  auto link_below = [&](int rise, int fall) {  // the edge rise -> fall below: its cap continues fall -> rise
    x.next_below[static_cast<std::size_t>(fall)] = static_cast<std::int16_t>(rise);
  };
  auto link_above = [&](int fall, int rise) {  // the edge fall -> rise above: its cap continues rise -> fall
    x.next_above[static_cast<std::size_t>(rise)] = static_cast<std::int16_t>(fall);
  };
  int j = in.corner[static_cast<std::size_t>(end - 1)];
  for (int k = begin; k < end; ++k) {
    const int i = in.corner[static_cast<std::size_t>(k)];
    const bool up_i = up[i] != 0;
    if (up_i != (up[j] != 0)) {
      const int c =
          up_i ? x.find_or_add(in, s, j, i, plane, below, above) : x.find_or_add(in, s, i, j, plane, below, above);
      if (below) below->add_corner(x.in_below[static_cast<std::size_t>(c)]);
      if (above) above->add_corner(x.in_above[static_cast<std::size_t>(c)]);
      if (up_i) {
        if (pending_down >= 0)
          link_above(pending_down, c);
        else
          first_up = c;
        pending_up = c;
        pending_down = -1;
      } else {
        if (pending_up >= 0)
          link_below(pending_up, c);
        else
          first_down = c;
        pending_down = c;
        pending_up = -1;
      }
    }
    ConvexPolyhedron* piece = up_i ? above : below;
    if (piece) piece->add_corner(at[i]);
    j = i;
  }
  if (pending_up >= 0 && first_down >= 0) link_below(pending_up, first_down);
  if (pending_down >= 0 && first_up >= 0) link_above(pending_down, first_up);
  if (below) below->close_face();
  if (above) above->close_face();
}

}  // namespace detail

/// Splits `in` by `plane` into the part below (s <= t, t the plane's tolerance) and the part above (s > t).
/// Returns Side::below or Side::above, writing nothing, when no vertex lies beyond the tolerance on the other
/// side; otherwise fills the pieces asked for (a null pointer: not wanted) and returns Side::both.
template <class P>
Side split(const ConvexPolyhedron& in, const P& plane, ConvexPolyhedron* below, ConvexPolyhedron* above) {
  std::array<double, ConvexPolyhedron::max_vertices> s;
  std::array<std::uint8_t, ConvexPolyhedron::max_vertices> up;
  bool any_below = false, any_above = false;
  for (int i = 0; i < in.nv; ++i) {
    const double d = plane.distance(in[i]);
    s[static_cast<std::size_t>(i)] = d;
    up[static_cast<std::size_t>(i)] = d > plane.tolerance;
    any_below |= d < -plane.tolerance;
    any_above |= d > plane.tolerance;
  }
  if (!any_above) return Side::below;
  if (!any_below) return Side::above;
  if (below) below->clear();
  if (above) above->clear();
  std::array<std::uint16_t, ConvexPolyhedron::max_vertices> at;  // every vertex's index in its side's piece
  for (int i = 0; i < in.nv; ++i) {
    ConvexPolyhedron* piece = up[static_cast<std::size_t>(i)] ? above : below;
    at[static_cast<std::size_t>(i)] = piece ? static_cast<std::uint16_t>(piece->add_vertex(in[i])) : 0;
  }
  detail::Crossings x(in.nv);
  for (int f = 0; f < in.nf; ++f) {
    // most faces lie on one side: copied whole
    const int begin = in.face_start[static_cast<std::size_t>(f)], end = in.face_start[static_cast<std::size_t>(f) + 1];
    unsigned any = 0, all = 1;
    for (int k = begin; k < end; ++k) {
      const unsigned u = up[in.corner[static_cast<std::size_t>(k)]];
      any |= u;
      all &= u;
    }
    if (any != all)
      detail::split_face(in, f, s.data(), up.data(), at.data(), plane, x, below, above);
    else if (ConvexPolyhedron* piece = all ? above : below)
      detail::copy_face(in, f, at.data(), *piece);
  }
  if (below) detail::add_caps(*below, x, x.next_below, x.in_below, plane.label);
  if (above) detail::add_caps(*above, x, x.next_above, x.in_above, plane.label);
  return Side::both;
}

/// Keeps the part of `cell` below `plane`, cutting into `scratch` and swapping: returns whether it cut.
/// A cell wholly above becomes empty.
template <class P>
bool clip(ConvexPolyhedron*& cell, ConvexPolyhedron*& scratch, const P& plane) {
  switch (split(*cell, plane, scratch, nullptr)) {
    case Side::below:
      return false;
    case Side::above:
      cell->clear();
      return true;
    case Side::both:
      std::swap(cell, scratch);
      return true;
  }
  return false;
}

/// Squared distance of the farthest vertex from the origin (cells are given relative to their particle).
inline double max_radius2_origin(const ConvexPolyhedron& p) {
  double r2 = 0.0;
  for (int i = 0; i < p.nv; ++i) r2 = std::max(r2, p[i].squaredNorm());
  return r2;
}

/// The vertices' extent along one axis.
inline std::pair<double, double> extent(const ConvexPolyhedron& p, int axis) {
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  for (int i = 0; i < p.nv; ++i) {
    lo = std::min(lo, p[i][axis]);
    hi = std::max(hi, p[i][axis]);
  }
  return {lo, hi};
}

/// Face f's area vector (its area times its outward unit normal): half the sum of its fan's cross products.
inline Point3 area_vector(const ConvexPolyhedron& p, int f) {
  const int begin = p.face_start[static_cast<std::size_t>(f)], end = p.face_start[static_cast<std::size_t>(f) + 1];
  const Point3& a = p[p.corner[static_cast<std::size_t>(begin)]];
  Point3 sum = Point3::Zero();
  for (int k = begin + 1; k + 1 < end; ++k) {
    const Point3 u = p[p.corner[static_cast<std::size_t>(k)]] - a, w = p[p.corner[static_cast<std::size_t>(k) + 1]] - a;
    sum += Point3(u.y() * w.z() - u.z() * w.y(), u.z() * w.x() - u.x() * w.z(), u.x() * w.y() - u.y() * w.x());
  }
  return 0.5 * sum;
}

/// Volume by the divergence theorem: each face fanned from its first corner, each triangle making a
/// tetrahedron with the origin.
inline double volume(const ConvexPolyhedron& p) {
  double six_v = 0.0;
  for (int f = 0; f < p.nf; ++f) {
    const int begin = p.face_start[static_cast<std::size_t>(f)], end = p.face_start[static_cast<std::size_t>(f) + 1];
    const Point3& a = p[p.corner[static_cast<std::size_t>(begin)]];
    for (int k = begin + 1; k + 1 < end; ++k)
      six_v += triple(a, p[p.corner[static_cast<std::size_t>(k)]], p[p.corner[static_cast<std::size_t>(k) + 1]]);
  }
  return six_v / 6.0;
}

/// Scratch of for_each_grid_piece: three polyhedra per axis (the piece below a plane and the rest, alternating).
struct GridPieceScratch {
  std::array<std::array<ConvexPolyhedron, 3>, 3> buffer;
};

namespace detail {
/// Splits p along axis Axis and recurses, down to axis Last, whose pieces go to f(index, piece).
template <int Axis, int Last, class F>
void split_along(const ConvexPolyhedron& p, const std::array<const double*, 3>& planes, const std::array<int, 3>& n,
                 std::array<int, 3>& index, GridPieceScratch& scratch, F& f) {
  auto& buffer = scratch.buffer[Axis];
  auto descend = [&](const ConvexPolyhedron& piece, int c) {
    index[Axis] = c;
    if constexpr (Axis == Last)
      f(index, piece);
    else
      split_along<Axis + 1, Last>(piece, planes, n, index, scratch, f);
  };
  const ConvexPolyhedron* rest = &p;
  std::size_t spare = 1;
  for (int c = 0; c + 1 < n[Axis]; ++c) {
    ConvexPolyhedron* above = &buffer[spare];
    const Side side = split(*rest, AxisPlane{Axis, planes[Axis][c + 1]}, &buffer[0], above);
    if (side == Side::below) {
      descend(*rest, c);
      return;
    }
    if (side == Side::both) {
      descend(buffer[0], c);
      rest = above;
      spare = 3 - spare;
    }
  }
  descend(*rest, n[Axis] - 1);
}
}  // namespace detail

/// Splits `cell` by the planes of a rectilinear grid, x first, then y, then z (r3d's voxelization): cell c
/// along axis k spans planes[k][c] to planes[k][c + 1], for c in [0, n[k]), and the cell lies within
/// planes[k][0] and planes[k][n[k]]. Calls f(index, piece) for every piece that holds a vertex strictly
/// inside its grid cell's slabs (index: the piece's cell along each axis).
template <class F>
void for_each_grid_piece(const ConvexPolyhedron& cell, const std::array<const double*, 3>& planes,
                         const std::array<int, 3>& n, GridPieceScratch& scratch, F&& f) {
  std::array<int, 3> index{};
  detail::split_along<0, 2>(cell, planes, n, index, scratch, f);
}

/// The same split, measured: f(index, m) with m = Measure::of(piece) for every piece, but the pieces of the last
/// axis are never built: each column's measure below every z plane (Measure::below, a pass over its faces) gives
/// them as differences. Measures are relative to the cell's frame, as the polyhedron's coordinates are.
template <class Measure, class F>
void for_each_grid_measure(const ConvexPolyhedron& cell, const std::array<const double*, 3>& planes,
                           const std::array<int, 3>& n, GridPieceScratch& scratch, F&& f) {
  std::array<int, 3> index{};
  auto column = [&](std::array<int, 3> idx, const ConvexPolyhedron& piece) {
    const auto [lo, hi] = extent(piece, 2);
    typename Measure::type below_previous{};
    for (int c = 0; c < n[2]; ++c) {
      if (c + 1 < n[2] && !(planes[2][c + 1] > lo)) continue;  // nothing of the column below this plane
      const bool last = c + 1 == n[2] || !(planes[2][c + 1] < hi);
      const typename Measure::type below = last ? Measure::of(piece) : Measure::below(piece, 2, planes[2][c + 1]);
      idx[2] = c;
      f(idx, Measure::difference(below, below_previous));
      if (last) return;
      below_previous = below;
    }
  };
  detail::split_along<0, 1>(cell, planes, n, index, scratch, column);
}

}  // namespace rsph::geometry
