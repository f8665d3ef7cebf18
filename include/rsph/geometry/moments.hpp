#pragma once
// Area, first and second moments of convex polygons by Green's theorem, and the cut of a polygon by an
// axis-parallel line into its two sides: what a remap that carries gradients needs of every overlap. In 3D,
// the volume, first and second moments of convex polyhedra by the divergence theorem.
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/polyhedron.hpp"

namespace rsph::geometry {

/// The integrals of 1, x, y, x^2, x y, y^2 over a region (coordinates of the polygon's own frame).
struct Moments {
  double area = 0.0;
  Point first = Point::Zero();  ///< (int x dA, int y dA)
  double xx = 0.0, xy = 0.0, yy = 0.0;

  Moments& operator+=(const Moments& o) {
    area += o.area;
    first += o.first;
    xx += o.xx;
    xy += o.xy;
    yy += o.yy;
    return *this;
  }
  Point centroid() const { return first / area; }
};

/// Green's theorem over the edges (counter-clockwise): with c_i = x_i y_{i+1} - x_{i+1} y_i,
/// A = sum c/2, int x = sum (x_i + x_{i+1}) c/6, int x^2 = sum (x_i^2 + x_i x_{i+1} + x_{i+1}^2) c/12,
/// int x y = sum (2 x_i y_i + x_i y_{i+1} + x_{i+1} y_i + 2 x_{i+1} y_{i+1}) c/24.
inline Moments moments(const ConvexPolygon& p) {
  Moments m;
  if (p.n < 3) return m;
  double a = 0.0, mx = 0.0, my = 0.0, xx = 0.0, xy = 0.0, yy = 0.0;
  for (int i = 0, j = p.n - 1; i < p.n; j = i++) {
    const double x0 = p[j].x(), y0 = p[j].y(), x1 = p[i].x(), y1 = p[i].y();
    const double c = x0 * y1 - x1 * y0;
    a += c;
    mx += (x0 + x1) * c;
    my += (y0 + y1) * c;
    xx += (x0 * x0 + x0 * x1 + x1 * x1) * c;
    yy += (y0 * y0 + y0 * y1 + y1 * y1) * c;
    xy += (2.0 * x0 * y0 + x0 * y1 + x1 * y0 + 2.0 * x1 * y1) * c;
  }
  m.area = 0.5 * a;
  m.first = Point(mx / 6.0, my / 6.0);
  m.xx = xx / 12.0;
  m.xy = xy / 24.0;
  m.yy = yy / 12.0;
  return m;
}

/// Cuts `in` by the line x_axis = c into the part below (x_axis <= c) and the part above; either may come
/// out empty. The new vertices on the line are set to c exactly, so neighbouring pieces share them.
inline void split_at(const ConvexPolygon& in, int axis, double c, ConvexPolygon& below, ConvexPolygon& above) {
  below.clear();
  above.clear();
  for (int i = 0, j = in.n - 1; i < in.n; j = i++) {
    const double si = in[i][axis] - c, sj = in[j][axis] - c;
    if ((si > 0.0) != (sj > 0.0)) {
      Point x = in[j] + (sj / (sj - si)) * (in[i] - in[j]);
      x[axis] = c;
      below.push(x);
      above.push(x);
    }
    if (si <= 0.0)
      below.push(in[i]);
    else
      above.push(in[i]);
  }
  if (below.n < 3) below.clear();
  if (above.n < 3) above.clear();
}

/// The integrals of 1, x and x x^T over a 3D region (coordinates of the polyhedron's own frame).
struct Moments3 {
  double volume = 0.0;
  Point3 first = Point3::Zero();
  Mat<3> second = Mat<3>::Zero();

  Moments3& operator+=(const Moments3& o) {
    volume += o.volume;
    first += o.first;
    second += o.second;
    return *this;
  }
  Point3 centroid() const { return first / volume; }
};

/// The divergence theorem over the faces, each fanned from its first corner: the tetrahedron of the origin
/// and a triangle (a, b, c), with det = a . (b x c), has volume det/6, first moment det/24 (a + b + c) and
/// second moment det/120 (a a^T + b b^T + c c^T + s s^T), s = a + b + c.
inline Moments3 moments(const ConvexPolyhedron& p) {
  double six_v = 0.0;
  Point3 first = Point3::Zero();
  Mat<3> second = Mat<3>::Zero();
  for (int f = 0; f < p.nf; ++f) {
    const int begin = p.face_start[static_cast<std::size_t>(f)], end = p.face_start[static_cast<std::size_t>(f) + 1];
    const Point3& a = p[p.corner[static_cast<std::size_t>(begin)]];
    for (int k = begin + 1; k + 1 < end; ++k) {
      const Point3& b = p[p.corner[static_cast<std::size_t>(k)]];
      const Point3& c = p[p.corner[static_cast<std::size_t>(k) + 1]];
      const double det = triple(a, b, c);
      const Point3 sum = a + b + c;
      six_v += det;
      first += det * sum;
      second += det * (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose());
    }
  }
  Moments3 m;
  m.volume = six_v / 6.0;
  m.first = first / 24.0;
  m.second = second / 120.0;
  return m;
}

namespace detail {
/// Streams the part of every face of p with x_axis <= c, in the frame of the point O on the plane (O_axis = c,
/// 0 elsewhere), as fan triangles: add(a, b, c) for each. The caps that close these parts lie in the plane through
/// O, so their tetrahedra with O have no volume: the triangles alone give the measures of the part below.
template <class Add>
void for_each_triangle_below(const ConvexPolyhedron& p, int axis, double c, Add&& add) {
  Point3 origin = Point3::Zero();
  origin[axis] = c;
  for (int f = 0; f < p.nf; ++f) {
    const int begin = p.face_start[static_cast<std::size_t>(f)], end = p.face_start[static_cast<std::size_t>(f) + 1];
    Point3 first, previous;
    int emitted = 0;
    auto emit = [&](const Point3& x) {
      if (emitted >= 2) add(first, previous, x);
      if (emitted == 0) first = x;
      previous = x;
      ++emitted;
    };
    const Point3* vj = &p[p.corner[static_cast<std::size_t>(end - 1)]];
    double sj = (*vj)[axis] - c;
    for (int k = begin; k < end; ++k) {
      const Point3& vi = p[p.corner[static_cast<std::size_t>(k)]];
      const double si = vi[axis] - c;
      if ((si > 0.0) != (sj > 0.0)) {  // the crossing, on the plane exactly
        Point3 x = *vj + (sj / (sj - si)) * (vi - *vj) - origin;
        x[axis] = 0.0;
        emit(x);
      }
      if (si <= 0.0) emit(vi - origin);
      vj = &vi;
      sj = si;
    }
  }
}
}  // namespace detail

/// What a first-order 3D remap measures of a piece: its volume, whole or below an axis plane.
struct VolumeMeasure {
  using type = double;
  static double of(const ConvexPolyhedron& p) { return volume(p); }
  static double below(const ConvexPolyhedron& p, int axis, double c) {
    double six_v = 0.0;
    detail::for_each_triangle_below(
        p, axis, c, [&](const Point3& a, const Point3& b, const Point3& d) { six_v += triple(a, b, d); });
    return six_v / 6.0;
  }
  static double difference(double a, double b) { return a - b; }
};

/// What a second-order 3D remap measures of a piece: its volume, first and second moments (cell frame).
struct MomentMeasure {
  using type = Moments3;
  static Moments3 of(const ConvexPolyhedron& p) { return moments(p); }
  static Moments3 below(const ConvexPolyhedron& p, int axis, double c) {
    double six_v = 0.0;
    Point3 first = Point3::Zero();
    Mat<3> second = Mat<3>::Zero();
    detail::for_each_triangle_below(p, axis, c, [&](const Point3& a, const Point3& b, const Point3& d) {
      const double det = triple(a, b, d);
      const Point3 sum = a + b + d;
      six_v += det;
      first += det * sum;
      second += det * (a * a.transpose() + b * b.transpose() + d * d.transpose() + sum * sum.transpose());
    });
    // back from the frame of O on the plane to the cell's: x = y + O
    Point3 origin = Point3::Zero();
    origin[axis] = c;
    Moments3 m;
    m.volume = six_v / 6.0;
    const Point3 first_y = first / 24.0;
    m.first = first_y + m.volume * origin;
    m.second = second / 120.0 + first_y * origin.transpose() + origin * first_y.transpose() +
               m.volume * origin * origin.transpose();
    return m;
  }
  static Moments3 difference(const Moments3& a, const Moments3& b) {
    Moments3 d;
    d.volume = a.volume - b.volume;
    d.first = a.first - b.first;
    d.second = a.second - b.second;
    return d;
  }
};

}  // namespace rsph::geometry
