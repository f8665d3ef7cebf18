#pragma once
// Where the gas may be at an open edge: the region that closes the old cells of edge particles before
// their overlaps are taken (§2 of the paper leaves open edges to the scene). One policy axis: a type
// with `clips` and `clip(x_o, cell)` (2D: a polygon; 3D: a polyhedron cut between two buffers); Unbounded
// leaves the closing disc (sphere) of RemapParams alone. Each region cuts a cell by the tangent planes of its
// surface at the particle, exact for flat faces and within d^2 / (2 r) over a cell of size d for curved ones;
// a particle beyond the surface is cut at its own position instead, so its cell keeps the half towards the gas.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/polyhedron.hpp"

#include <algorithm>
#include <concepts>

namespace rsph::region {

/// No region: cells at open edges are closed by the disc of RemapParams::closing_radius_in_h only.
struct Unbounded {
  static constexpr bool clips = false;
  void clip(const Vec<2>&, geometry::ConvexPolygon&) const {}
  void clip(const Vec<3>&, geometry::ConvexPolyhedron*&, geometry::ConvexPolyhedron*&) const {}
};

/// The annulus r_in <= r <= r_out about the origin (a disk between fixed edges, §5). Each cell is cut
/// by the tangents of both circles at its particle's azimuth: exact at the tangent point and within
/// d^2 / (2 r) over a cell of size d. A particle beyond an edge is cut at its own radius instead, so
/// its cell keeps the half towards the disk.
struct Annulus {
  static constexpr bool clips = true;
  double r_in = 0.0, r_out = 1.0;

  void validate() const { require(r_in >= 0.0 && r_out > r_in, "annulus region: need 0 <= r_in < r_out"); }
  /// `cell` is relative to the particle at x_o.
  void clip(const Vec<2>& x_o, geometry::ConvexPolygon& cell) const {
    const double r_o = x_o.norm();
    if (r_o <= 0.0) return;
    const Vec<2> e_r = x_o / r_o;
    geometry::clip_halfplane(cell, e_r, std::max(r_out, r_o) - r_o);                  // r <= r_out
    if (r_in > 0.0) geometry::clip_halfplane(cell, -e_r, r_o - std::min(r_in, r_o));  // r >= r_in
  }
};

/// f(cell) with the 2D cell (relative to x_o) closed by the region: the cell itself, uncopied, where the region
/// does not clip.
template <class Region, class F>
void with_closed(const Region& region, const Vec<2>& x_o, const geometry::ConvexPolygon& cell, F&& f) {
  if constexpr (Region::clips) {
    geometry::ConvexPolygon closed = cell;
    region.clip(x_o, closed);
    f(closed);
  } else {
    f(cell);
  }
}

namespace detail {
/// Cuts a 3D cell (relative to x_o) to the side of the plane through the point at `reach` along the unit
/// normal `n` from x_o: n . y <= reach.
inline void keep_within(geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch, const Vec<3>& n,
                        double reach) {
  geometry::clip(cell, scratch, geometry::Plane{n, reach});
}
}  // namespace detail

/// The box lo <= x <= hi (3D): each cell cut by the box's six planes.
struct Cuboid {
  static constexpr bool clips = true;
  Vec<3> lo = Vec<3>::Zero(), hi = Vec<3>::Ones();

  void validate() const { require((hi - lo).minCoeff() > 0.0, "box region: need lo < hi on every axis"); }
  void clip(const Vec<3>& x_o, geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch) const {
    for (int k = 0; k < 3; ++k) {
      const Vec<3> e = Vec<3>::Unit(k);
      detail::keep_within(cell, scratch, e, std::max(hi[k], x_o[k]) - x_o[k]);   // x_k <= hi_k
      detail::keep_within(cell, scratch, -e, x_o[k] - std::min(lo[k], x_o[k]));  // x_k >= lo_k
    }
  }
};

/// The ball |x| <= radius about the origin (3D): each cell cut by the sphere's tangent plane at its particle.
struct Ball {
  static constexpr bool clips = true;
  double radius = 1.0;

  void validate() const { require(radius > 0.0, "ball region: the radius must be positive"); }
  void clip(const Vec<3>& x_o, geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch) const {
    const double r_o = x_o.norm();
    if (r_o <= 0.0) return;
    detail::keep_within(cell, scratch, x_o / r_o, std::max(radius, r_o) - r_o);
  }
};

/// The cylindrical shell r_in <= sqrt(x^2 + y^2) <= r_out, z_lo <= z <= z_hi about the z axis (3D): a disk
/// between fixed edges, as Annulus in 2D, with a top and a bottom. Each cell is cut by the tangent planes of
/// both cylinders at its particle's azimuth and by the two planes.
struct CylindricalShell {
  static constexpr bool clips = true;
  double r_in = 0.0, r_out = 1.0, z_lo = -1.0, z_hi = 1.0;

  void validate() const {
    require(r_in >= 0.0 && r_out > r_in && z_hi > z_lo,
            "cylindrical shell region: need 0 <= r_in < r_out and z_lo < z_hi");
  }
  void clip(const Vec<3>& x_o, geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch) const {
    const double R_o = std::hypot(x_o.x(), x_o.y());
    if (R_o > 0.0) {
      const Vec<3> e_R(x_o.x() / R_o, x_o.y() / R_o, 0.0);
      detail::keep_within(cell, scratch, e_R, std::max(r_out, R_o) - R_o);
      if (r_in > 0.0) detail::keep_within(cell, scratch, -e_R, R_o - std::min(r_in, R_o));
    }
    const Vec<3> e_z = Vec<3>::UnitZ();
    detail::keep_within(cell, scratch, e_z, std::max(z_hi, x_o.z()) - x_o.z());
    detail::keep_within(cell, scratch, -e_z, x_o.z() - std::min(z_lo, x_o.z()));
  }
};

/// A flared disk (3D): r_in <= R <= r_out and |z| <= slope R, R = sqrt(x^2 + y^2), the gas of a disk whose
/// scale height grows as R (a vertically isothermal disk of fixed H / R, slope a few H / R). Each cell is cut
/// by the tangent planes of both cylinders at its particle's azimuth and by the planes of the two cones through
/// the particle's azimuth, which touch the cones along the whole line and are exact there.
struct FlaredDisk {
  static constexpr bool clips = true;
  double r_in = 0.0, r_out = 1.0, slope = 0.15;

  void validate() const {
    require(r_in >= 0.0 && r_out > r_in && slope > 0.0, "flared disk region: need 0 <= r_in < r_out and slope > 0");
  }
  void clip(const Vec<3>& x_o, geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch) const {
    const double R_o = std::hypot(x_o.x(), x_o.y());
    if (R_o <= 0.0) return;
    const Vec<3> e_R(x_o.x() / R_o, x_o.y() / R_o, 0.0);
    detail::keep_within(cell, scratch, e_R, std::max(r_out, R_o) - R_o);
    if (r_in > 0.0) detail::keep_within(cell, scratch, -e_R, R_o - std::min(r_in, R_o));
    // z <= slope R and -z <= slope R: the unit normals (-slope e_R +- e_z) / sqrt(1 + slope^2) through the axis
    const double norm = std::sqrt(1.0 + slope * slope);
    for (const double side : {1.0, -1.0}) {
      const Vec<3> n = (side * Vec<3>::UnitZ() - slope * e_R) / norm;
      detail::keep_within(cell, scratch, n, std::max(0.0, -n.dot(x_o)));
    }
  }
};

}  // namespace rsph::region

namespace rsph {

template <class R, int D>
concept ClosingRegion = requires(const R& r, const Vec<D>& x, geometry::ConvexPolygon& polygon,
                                 geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch) {
  { R::clips } -> std::convertible_to<bool>;
  requires D == 1 || (D == 2 && requires { r.clip(x, polygon); }) || (D == 3 && requires { r.clip(x, cell, scratch); });
};

template <class R, int D>
constexpr bool check_closing_region() {
  static_assert(ClosingRegion<R, D>,
                "a closing region must provide `static constexpr bool clips` and, for the lattice's dimension, "
                "`void clip(const Vec<2>& x_o, geometry::ConvexPolygon& cell) const` (2D) or `void clip(const "
                "Vec<3>& x_o, geometry::ConvexPolyhedron*& cell, geometry::ConvexPolyhedron*& scratch) const` (3D), "
                "the cell relative to x_o");
  return true;
}

}  // namespace rsph
