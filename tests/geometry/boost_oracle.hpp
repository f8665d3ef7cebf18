#pragma once
// Boost.Geometry as the oracle for the clipping code, in plain double precision (its default rescaling to
// integers moves results by ~1e-10).
#define BOOST_GEOMETRY_NO_ROBUSTNESS
// Debian 12's Boost.Geometry still includes a header Boost itself has deprecated; without this the build
// prints its pragma message.
#define BOOST_ALLOW_DEPRECATED_HEADERS
#include "rsph/geometry/polygon.hpp"

#include <boost/geometry.hpp>

#include <vector>

namespace rsph::test {

namespace bg = boost::geometry;
using BgPoint = bg::model::d2::point_xy<double>;
using BgPolygon = bg::model::polygon<BgPoint, false>;  // counter-clockwise

inline BgPolygon to_bg(const geometry::ConvexPolygon& p) {
  BgPolygon out;
  for (int i = 0; i < p.n; ++i) bg::append(out.outer(), BgPoint(p[i].x(), p[i].y()));
  bg::append(out.outer(), BgPoint(p[0].x(), p[0].y()));
  return out;
}

inline double oracle_intersection_area(const geometry::ConvexPolygon& a, const geometry::ConvexPolygon& b) {
  std::vector<BgPolygon> result;
  bg::intersection(to_bg(a), to_bg(b), result);
  double s = 0.0;
  for (const auto& r : result) s += bg::area(r);
  return s;
}

}  // namespace rsph::test
