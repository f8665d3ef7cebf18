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
  /// Voronoi cells have about 15 faces and 27 vertices; pieces and degenerate cells a few more.
  static constexpr int max_vertices = 256, max_faces = 128, max_corners = 768;
  std::array<Point3, max_vertices> v;
  std::array<std::uint16_t, max_corners> corner;        ///< every face's vertex indices, face after face
  std::array<std::uint16_t, max_faces + 1> face_start;  ///< face f: corner[face_start[f] .. face_start[f + 1])
  int nv = 0, nf = 0;

  ConvexPolyhedron() { face_start[0] = 0; }
  // Copies only what is in use: polyhedra are copied inside the cutting loops.
  ConvexPolyhedron(const ConvexPolyhedron& o) { *this = o; }
  ConvexPolyhedron& operator=(const ConvexPolyhedron& o) {
    nv = o.nv;
    nf = o.nf;
    std::copy_n(o.v.begin(), o.nv, v.begin());
    std::copy_n(o.face_start.begin(), o.nf + 1, face_start.begin());
    std::copy_n(o.corner.begin(), o.face_start[static_cast<std::size_t>(o.nf)], corner.begin());
    return *this;
  }

  bool empty() const { return nf == 0; }
  void clear() {
    nv = nf = 0;
    face_start[0] = 0;
  }
  int n_corners() const { return face_start[static_cast<std::size_t>(nf)]; }
  const Point3& operator[](int i) const { return v[static_cast<std::size_t>(i)]; }

  int add_vertex(const Point3& p) {
    if (nv == max_vertices) throw NumericalError("convex polyhedron: more than 256 vertices (degenerate cell)");
    v[static_cast<std::size_t>(nv)] = p;
    return nv++;
  }
  void add_corner(int i) {
    const int at = face_start[static_cast<std::size_t>(nf) + 1];
    if (at == max_corners) throw NumericalError("convex polyhedron: more than 768 face corners (degenerate cell)");
    corner[static_cast<std::size_t>(at)] = static_cast<std::uint16_t>(i);
    ++face_start[static_cast<std::size_t>(nf) + 1];
  }
  /// Faces are written corner by corner between open_face and close_face; a face of fewer than three
  /// corners is dropped.
  void open_face() {
    if (nf == max_faces) throw NumericalError("convex polyhedron: more than 128 faces (degenerate cell)");
    face_start[static_cast<std::size_t>(nf) + 1] = face_start[static_cast<std::size_t>(nf)];
  }
  void close_face() {
    if (face_start[static_cast<std::size_t>(nf) + 1] - face_start[static_cast<std::size_t>(nf)] >= 3) ++nf;
  }

  void translate(const Point3& d) {
    for (int i = 0; i < nv; ++i) v[static_cast<std::size_t>(i)] += d;
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

/// A plane n . x = c, cutting by s = n . x - c.
struct Plane {
  Point3 n;
  double c;
  double distance(const Point3& x) const { return n.dot(x) - c; }
  /// Where the edge from a (s_a <= 0) to b (s_b > 0) meets the plane.
  Point3 meet(const Point3& a, const Point3& b, double s_a, double s_b) const {
    return a + (s_a / (s_a - s_b)) * (b - a);
  }
};

/// A lattice plane x_axis = c: the new vertices are set on it exactly, so neighbouring pieces share them.
struct AxisPlane {
  int axis;
  double c;
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

/// The edges a plane crosses, each with its new vertex in both pieces and the cap's chains.
struct Crossings {
  static constexpr int capacity = ConvexPolyhedron::max_corners / 2;
  std::array<std::uint16_t, capacity> from, to;               ///< the edge: its end below, its end above
  std::array<std::uint16_t, capacity> in_below, in_above;     ///< the new vertex's index in each piece
  std::array<std::int16_t, capacity> next_below, next_above;  ///< the next crossing along each piece's cap
  int n = 0;

  /// The crossing of edge (b below, a above), created on first sight.
  template <class P>
  int find_or_add(const ConvexPolyhedron& in, const double* s, int b, int a, const P& plane, ConvexPolyhedron* below,
                  ConvexPolyhedron* above) {
    for (int c = 0; c < n; ++c)
      if (from[static_cast<std::size_t>(c)] == b && to[static_cast<std::size_t>(c)] == a) return c;
    if (n == capacity) throw NumericalError("convex polyhedron: too many edges cross a plane");
    const auto c = static_cast<std::size_t>(n);
    from[c] = static_cast<std::uint16_t>(b);
    to[c] = static_cast<std::uint16_t>(a);
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
                     const std::array<std::uint16_t, Crossings::capacity>& index) {
  std::array<bool, Crossings::capacity> done{};
  for (int start = 0; start < x.n; ++start) {
    if (done[static_cast<std::size_t>(start)]) continue;
    piece.open_face();
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

}  // namespace detail

/// Splits `in` by `plane` into the part below (s <= 0) and the part above (s > 0). Returns Side::below or
/// Side::above, writing nothing, when no vertex lies strictly on the other side; otherwise fills the pieces
/// asked for (a null pointer: not wanted) and returns Side::both.
template <class P>
Side split(const ConvexPolyhedron& in, const P& plane, ConvexPolyhedron* below, ConvexPolyhedron* above) {
  std::array<double, ConvexPolyhedron::max_vertices> s;
  bool any_below = false, any_above = false;
  for (int i = 0; i < in.nv; ++i) {
    const double d = plane.distance(in[i]);
    s[static_cast<std::size_t>(i)] = d;
    any_below |= d < 0.0;
    any_above |= d > 0.0;
  }
  if (!any_above) return Side::below;
  if (!any_below) return Side::above;
  if (below) below->clear();
  if (above) above->clear();
  // every vertex goes to its side's piece
  std::array<std::uint16_t, ConvexPolyhedron::max_vertices> at;
  for (int i = 0; i < in.nv; ++i) {
    ConvexPolyhedron* piece = s[static_cast<std::size_t>(i)] > 0.0 ? above : below;
    at[static_cast<std::size_t>(i)] = piece ? static_cast<std::uint16_t>(piece->add_vertex(in[i])) : 0;
  }
  detail::Crossings x;
  // Each face in turn: its corners on each side, a crossing's vertex wherever the side changes. Going up at X
  // and down at Y, the piece below holds the edge X -> Y and the piece above Y -> X, so their caps, which
  // run the other way, continue with Y -> X below and X -> Y above.
  for (int f = 0; f < in.nf; ++f) {
    const int begin = in.face_start[static_cast<std::size_t>(f)], end = in.face_start[static_cast<std::size_t>(f) + 1];
    if (below) below->open_face();
    if (above) above->open_face();
    int pending_up = -1, first_down = -1;
    auto link = [&](int up, int down) {
      x.next_below[static_cast<std::size_t>(down)] = static_cast<std::int16_t>(up);
      x.next_above[static_cast<std::size_t>(up)] = static_cast<std::int16_t>(down);
    };
    for (int k = begin; k < end; ++k) {
      const int i = in.corner[static_cast<std::size_t>(k)];
      const int j = in.corner[static_cast<std::size_t>(k == begin ? end - 1 : k - 1)];
      const bool up_i = s[static_cast<std::size_t>(i)] > 0.0, up_j = s[static_cast<std::size_t>(j)] > 0.0;
      if (up_i != up_j) {
        const int c = up_i ? x.find_or_add(in, s.data(), j, i, plane, below, above)
                           : x.find_or_add(in, s.data(), i, j, plane, below, above);
        if (below) below->add_corner(x.in_below[static_cast<std::size_t>(c)]);
        if (above) above->add_corner(x.in_above[static_cast<std::size_t>(c)]);
        if (up_i) {
          pending_up = c;
        } else if (pending_up >= 0) {
          link(pending_up, c);
          pending_up = -1;
        } else {
          first_down = c;
        }
      }
      ConvexPolyhedron* piece = up_i ? above : below;
      if (piece) piece->add_corner(at[static_cast<std::size_t>(i)]);
    }
    if (pending_up >= 0 && first_down >= 0) link(pending_up, first_down);
    if (below) below->close_face();
    if (above) above->close_face();
  }
  if (below) detail::add_caps(*below, x, x.next_below, x.in_below);
  if (above) detail::add_caps(*above, x, x.next_above, x.in_above);
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
template <int Axis, class F>
void split_along(const ConvexPolyhedron& p, const std::array<const double*, 3>& planes, const std::array<int, 3>& n,
                 std::array<int, 3>& index, GridPieceScratch& scratch, F& f) {
  auto& buffer = scratch.buffer[Axis];
  auto descend = [&](const ConvexPolyhedron& piece, int c) {
    index[Axis] = c;
    if constexpr (Axis == 2)
      f(index, piece);
    else
      split_along<Axis + 1>(piece, planes, n, index, scratch, f);
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
  detail::split_along<0>(cell, planes, n, index, scratch, f);
}

}  // namespace rsph::geometry
