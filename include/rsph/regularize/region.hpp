#pragma once
// Where the gas may be at an open edge: the region that closes the old cells of edge particles before
// their overlaps are taken (§2 of the paper leaves open edges to the scene). One policy axis: a type
// with `clips` and `clip(x_o, cell)`; Unbounded leaves the closing disc of RemapParams alone.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/geometry/polygon.hpp"

#include <algorithm>
#include <concepts>

namespace rsph::region {

/// No region: cells at open edges are closed by the disc of RemapParams::closing_radius_in_h only.
struct Unbounded {
  static constexpr bool clips = false;
  void clip(const Vec<2>&, geometry::ConvexPolygon&) const {}
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

}  // namespace rsph::region

namespace rsph {

template <class R>
concept ClosingRegion = requires(const R& r, const Vec<2>& x, geometry::ConvexPolygon& cell) {
  { R::clips } -> std::convertible_to<bool>;
  r.clip(x, cell);
};

template <class R>
constexpr bool check_closing_region() {
  static_assert(ClosingRegion<R>,
                "a closing region must provide `static constexpr bool clips` and "
                "`void clip(const Vec<2>& x_o, geometry::ConvexPolygon& cell) const` (cell relative to x_o)");
  return true;
}

}  // namespace rsph
