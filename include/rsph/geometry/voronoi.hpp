#pragma once
// Voronoi cells of 2D particles, closed against the domain, handed one by one to a visitor (cells are
// consumed at once by the remap; storing a million polygons would cost gigabytes).
//
// Domain edges: periodic axes get periodic images of the particles near the faces; reflecting axes clip
// the cell to the box (the bisector of a particle and its mirror image is the wall itself); open axes
// close each cell with a disc of radius `closing_radius[a]` (a regular 32-gon circumscribing it), so no
// cell is ever unbounded.
//
// Two interchangeable builders:
//  - LocalVoronoi cuts each cell out of its initial polygon by the bisectors of neighbours gathered from a
//    cell list in discs of growing radius, until the security radius (twice the farthest vertex
//    distance) lies inside the discs gathered; once no vertex is farther than the disc's radius, the last
//    sites come only from the discs through the particle centred on the vertices that reach out (the
//    only places a site can still cut). The first disc's cut is taken at once as the polar dual of the convex
//    hull of the candidates (clipping is kept for the rest and for cells at walls or near-coincident sites).
//    Exact in double precision; per particle, so it runs in parallel.
//  - BoostVoronoi takes the Voronoi neighbours from Boost.Polygon's construct_voronoi on positions
//    quantized to 31-bit integers (scale 2^30 over the extent of the points: quantization error at most
//    extent / 2^31 per coordinate), then cuts the cell by those neighbours' bisectors in double precision
//    from the unquantized positions. Quantization can only miss edges shorter than about that error, so
//    the two agree to round-off on any set whose points are farther apart than the quantum.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <boost/polygon/voronoi.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace rsph::geometry {

/// The points a cell builder sees: the real particles, then periodic images (with their sources).
struct SitesWithImages {
  std::vector<Point> x;
  std::vector<std::uint32_t> source;
  std::size_t n_real = 0;
  double margin = 0.0;  ///< images cover this distance beyond each periodic face
};

namespace detail {

/// Throws for the first particle (lowest index) that is not finite or lies outside a closed axis.
inline void check_sites(const std::vector<Point>& x, const Box<2>& box) {
  // 0: fine, 1: not finite, 2 + k: outside along axis k
  auto problem = [&](std::size_t a) {
    if (!x[a].allFinite()) return 1;
    for (int k = 0; k < 2; ++k)
      if (box.edge[k] != Edge::open && (x[a][k] < box.lo[k] || x[a][k] > box.hi[k])) return 2 + k;
    return 0;
  };
  std::vector<std::size_t> first_bad(static_cast<std::size_t>(max_threads()), x.size());
  run_parallel(x.size(), [&](int t, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a)
      if (problem(a) != 0) {
        first_bad[static_cast<std::size_t>(t)] = a;
        return;
      }
  });
  const std::size_t a = *std::min_element(first_bad.begin(), first_bad.end());
  if (a == x.size()) return;
  const int what = problem(a);
  if (what == 1) throw InputError("Voronoi cells: particle " + std::to_string(a) + " has a non-finite position");
  throw InputError("Voronoi cells: particle " + std::to_string(a) + " lies outside the domain along axis " +
                   std::to_string(what - 2));
}

/// Fills `s` with the particles and their periodic images (reusing its storage from call to call). Both
/// are written in parallel; the images come in the order of a serial pass (by particle, then by shift),
/// each thread writing its particles' images from the count of those before them on.
inline void add_periodic_images(const std::vector<Point>& x, const Box<2>& box, double margin, SitesWithImages& s) {
  const std::size_t n_real = x.size();
  s.n_real = n_real;
  s.margin = margin;
  s.x.resize(n_real);
  s.source.resize(n_real);
  run_parallel(n_real, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      s.x[a] = x[a];
      s.source[a] = static_cast<std::uint32_t>(a);
    }
  });
  for (int k = 0; k < 2; ++k) {
    if (!box.periodic(k)) continue;
    const double L = box.hi[k] - box.lo[k], lo = box.lo[k] - margin, hi = box.hi[k] + margin;
    const auto reach = static_cast<int>(std::ceil(margin / L));  // a wide margin needs several periods
    // calls f(shifted point) for each image of point i that lies within the margin, shifts ascending
    auto for_each_image = [&](std::size_t i, auto&& f) {
      const double c = s.x[i][k];
      if (c - L >= lo || c + L <= hi || reach > 1)  // almost every point has no image at all
        for (int shift = -reach; shift <= reach; ++shift) {
          const double shifted = c + shift * L;
          if (shift == 0 || shifted < lo || shifted > hi) continue;
          Point p = s.x[i];
          p[k] = shifted;
          f(p);
        }
    };
    const std::size_t n = s.x.size();
    run_parallel_packed(
        n,
        [&](std::size_t begin, std::size_t end) {
          std::size_t count = 0;
          for (std::size_t i = begin; i < end; ++i) for_each_image(i, [&](const Point&) { ++count; });
          return count;
        },
        [&](std::size_t n_images) {
          s.x.resize(n + n_images);
          s.source.resize(n + n_images);
        },
        [&](int, std::size_t begin, std::size_t end, std::size_t first) {
          std::size_t at = n + first;
          for (std::size_t i = begin; i < end; ++i)
            for_each_image(i, [&](const Point& p) {
              s.x[at] = p;
              s.source[at++] = s.source[i];
            });
        });
  }
}

/// The polygon a cell is cut from, in coordinates relative to the particle: the box (walls), the box
/// widened by the image margin (periodic), and the square circumscribing the closing disc (open axes;
/// the disc itself is applied by close_with_disc once the neighbours have cut the cell).
inline ConvexPolygon initial_cell(const Point& xa, const Box<2>& box, double margin, double closing_radius) {
  double lo[2], hi[2];
  for (int k = 0; k < 2; ++k) {
    if (box.edge[k] == Edge::open) {
      lo[k] = -closing_radius;
      hi[k] = closing_radius;
    } else {
      const double widen = box.periodic(k) ? margin : 0.0;
      lo[k] = box.lo[k] - widen - xa[k];
      hi[k] = box.hi[k] + widen - xa[k];
    }
  }
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

/// Mean spacing of n points in the box (open axes: their bounding box).
inline double mean_spacing(const std::vector<Point>& x, const Box<2>& box) {
  Point lo = box.lo, hi = box.hi;
  for (int k = 0; k < 2; ++k)
    if (box.edge[k] == Edge::open) {
      lo[k] = std::numeric_limits<double>::max();
      hi[k] = std::numeric_limits<double>::lowest();
      for (const auto& p : x) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
    }
  const double n = static_cast<double>(std::max<std::size_t>(x.size(), 1));
  // A set thinner than its spacing (collinear on an open axis) has the spacing along its length: the area's
  // would be tiny, and every cell's search would start from nothing.
  const double along = (hi - lo).maxCoeff() / n;
  return std::max(std::sqrt(std::max((hi - lo).prod(), 0.0) / n), std::max(along, 1e-300));
}

/// Squared distance of the farthest vertex from the particle (cells are given relative to it).
inline double max_radius2_origin(const ConvexPolygon& p) {
  double r2 = 0.0;
  for (int i = 0; i < p.n; ++i) r2 = std::max(r2, p[i].squaredNorm());
  return r2;
}

/// Whether a cell may be missing a periodic image: its security disc (twice its farthest vertex
/// distance, whose square is r2_max) reaches beyond the band the images cover. Then the margin is widened
/// and cells rebuilt.
inline bool needs_more_images(double r2_max, const Point& xa, const Box<2>& box, double margin) {
  const double security = 2.0 * std::sqrt(r2_max);
  for (int k = 0; k < 2; ++k)
    if (box.periodic(k) && (xa[k] - security < box.lo[k] - margin || xa[k] + security > box.hi[k] + margin))
      return true;
  return false;
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

/// Runs try_build(margin) with periodic images over a margin of 4 mean spacings, doubling it (and
/// calling visit.restart()) until every cell's security disc is covered.
template <class Visitor, class TryBuild>
void build_widening_images(const std::vector<Point>& x, const Box<2>& box, Visitor& visit, TryBuild&& try_build) {
  check_sites(x, box);
  double margin = 4.0 * mean_spacing(x, box);
  for (int attempt = 0;; ++attempt) {
    if (attempt > 0) visit.restart();
    if (try_build(margin)) return;
    margin *= 2.0;
    bool fits = true;  // cells wider than twice the box: the set is too sparse to mean anything periodic
    for (int k = 0; k < 2; ++k) fits &= !box.periodic(k) || margin < 4.0 * (box.hi[k] - box.lo[k]);
    if (!fits || attempt > 12)
      throw NumericalError("Voronoi cells: periodic cells wider than the box; too few particles for a periodic domain");
  }
}

/// The public face of both builders: build(x, box, closing_radius, visit, only) runs the builder's
/// try_build(x, box, closing_radius, margin, visit, only) with images widened until they suffice. Every
/// particle is a site; `only` (ascending, empty for all) names the particles whose cells are visited.
template <class Builder>
class WideningBuilder {
 public:
  template <class Visitor>
  void build(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing_radius, Visitor&& visit,
             std::span<const std::uint32_t> only = {}) {
    auto& self = static_cast<Builder&>(*this);
    build_widening_images(x, box, visit,
                          [&](double margin) { return self.try_build(x, box, closing_radius, margin, visit, only); });
  }
};

/// How many cells a build visits, and the particle of the k-th: `only` or, when empty, all n.
inline std::size_t chosen_count(std::size_t n, std::span<const std::uint32_t> only) {
  return only.empty() ? n : only.size();
}
inline std::size_t chosen(std::span<const std::uint32_t> only, std::size_t k) {
  return only.empty() ? k : static_cast<std::size_t>(only[k]);
}
}  // namespace detail

/// Number of threads the builders use (visitors keep per-thread state).
inline int builder_threads() { return max_threads(); }

/// Local half-plane builder. visit(thread, a, cell) receives each chosen particle's cell in coordinates
/// relative to x[a]; particles of one thread arrive in increasing order. When periodic images turn out
/// too few (a cell reaches past them), the builder widens them and starts again, calling
/// visit.restart() first: a visitor must then forget what it was given.
class BoostVoronoi;

class LocalVoronoi : public detail::WideningBuilder<LocalVoronoi> {
 public:
  /// How many cells of the last build took their first cut from the dual hull rather than from clips.
  std::size_t cells_from_hull() const { return cells_from_hull_; }

  /// The build; a set whose cells would make it scan more than scan_budget_per_cell points per cell on average
  /// goes to BoostVoronoi instead (visit.restart() first). Nearly collinear sets in walled boxes do: their long
  /// thin cells reach every particle of the line, O(N^2) here (17 s at N = 11 572) against O(N log N) there.
  template <class Visitor>
  void build(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing_radius, Visitor&& visit,
             std::span<const std::uint32_t> only = {});
  /// Whether the last build went to BoostVoronoi.
  bool handed_to_boost() const { return handed_to_boost_; }
  static constexpr double scan_budget_per_cell = 2000.0;
  /// Points a thread scans before it adds them to the shared count the budget is checked against.
  static constexpr std::size_t scan_flush = 4096;

 private:
  friend class detail::WideningBuilder<LocalVoronoi>;
  struct Candidate {
    double d2;  ///< squared distance
    Point d;    ///< position relative to the cell's particle
  };
  /// Radius of the first disc of candidates, in mean spacings: it holds the security disc of a regular
  /// lattice's cell (2 x 0.71 spacings), so one gather settles a near-regular cell; each further disc is
  /// `disc_growth` times wider (measured on jittered and sheared lattices against 1.8 / 2.0 and doubling).
  /// Since the dual hull cuts by a whole disc at about one test per candidate, a slightly wider first disc
  /// pays: fewer cells need the vertex discs (jittered cells, N = 1e5: 33.5 ms at 1.5, 30.2 at 1.65, 30.5 at
  /// 1.7, 31.6 at 1.8; sheared within 1 ms).
  static constexpr double first_radius_spacings = 1.65;
  static constexpr double disc_growth = 1.4;

  /// Cuts the cell by the bisectors of the candidates. Returns false when one coincides with the particle.
  /// r2_max, the squared farthest vertex distance, is refreshed once at the end: cuts only shrink the cell,
  /// so a stale value still bounds it and skips only what cannot cut.
  static bool cut_by(std::span<const Candidate> candidates, ConvexPolygon*& cell, ConvexPolygon*& scratch,
                     double& r2_max) {
    bool cut = false;
    for (const auto& [d2, d] : candidates) {
      if (d2 == 0.0) {
        cell->clear();
        return false;
      }
      // a bisector farther than the farthest vertex cuts nothing (slack for the rounding of r2_max)
      if (d2 > 4.0 * r2_max * (1.0 + 1e-9)) continue;
      if (detail::cut_by_bisector(*cell, d, *scratch)) {
        std::swap(cell, scratch);
        cut = true;
      }
    }
    if (cut) r2_max = detail::max_radius2_origin(*cell);
    return true;
  }

  /// The cell cut by the first disc's candidates, as the polar dual of a convex hull: the half-planes
  /// d . y <= |d|^2 / 2 are q . y <= 1 with q = 2 d / |d|^2, and the region they bound has one side per vertex of
  /// the convex hull of the points q and one vertex per hull edge. Sorting the handful of q by angle and one
  /// Graham scan find the hull with about one orientation test per candidate, where clipping copies the polygon
  /// once per cutting candidate (cells jittered 43 -> 35 ms, sheared 30 -> 19 ms at N = 1e5, one thread).
  /// Returns false, leaving the cell to the clips, when the region is not bounded strictly inside the initial
  /// rectangle [lo, hi] (the candidates do not surround the particle, or the cell reaches a wall), when two
  /// sides are nearly parallel (near-coincident sites: an ill-conditioned vertex), or when a candidate coincides
  /// with the particle. On success r2_max receives the squared distance of the cell's farthest vertex.
  static bool cell_from_dual_hull(std::span<const Candidate> candidates, const Point& lo, const Point& hi,
                                  ConvexPolygon& cell, double& r2_max) {
    const std::size_t k = candidates.size();
    if (k < 3 || k > ConvexPolygon::capacity) return false;
    std::array<double, ConvexPolygon::capacity> qx, qy;
    std::size_t start = 0;
    for (std::size_t c = 0; c < k; ++c) {
      const auto& [d2, d] = candidates[c];
      if (d2 == 0.0) return false;
      const double scale = 2.0 / d2;
      qx[c] = scale * d.x();
      qy[c] = scale * d.y();
      if (d2 < candidates[start].d2) start = c;  // the nearest site has the farthest q
    }
    // Graham's scan about the origin, which lies inside the hull when the candidates surround the particle
    // (the vertex test below rejects the rest): the q in order of angle (the angle of d), started at the
    // farthest (a hull vertex); a point that does not turn left of the last two drops the last. Within round-off
    // of a line counts as on it, so the middle of collinear q (co-circular sites, as on a regular lattice) is
    // dropped: its line passes through the vertex and adds no side.
    std::array<double, ConvexPolygon::capacity> angle;
    std::array<std::uint8_t, ConvexPolygon::capacity> order;
    for (std::size_t c = 0; c < k; ++c) {
      // monotone in the angle counted from -x, [0, 4): the order the first disc's gather nearly delivers
      const double t = -qx[c] / (std::abs(qx[c]) + std::abs(qy[c]));
      angle[c] = qy[c] <= 0.0 ? 1.0 - t : 3.0 + t;
      std::size_t j = c;
      for (; j > 0 && angle[order[j - 1]] > angle[c]; --j) order[j] = order[j - 1];
      order[j] = static_cast<std::uint8_t>(c);
    }
    std::size_t first = 0;
    while (order[first] != start) ++first;
    std::array<std::uint8_t, ConvexPolygon::capacity + 1> hull;
    std::size_t n_hull = 0;
    // The vertex of sides a and b by Cramer's rule, in d rather than q (a near site's huge q would swamp the
    // other side's digits); false where the sides are nearly parallel (sin < 1e-4: an ill-conditioned vertex,
    // as near-coincident sites make) or meet on the wrong side (the hull does not go round the origin).
    auto vertex = [&](std::size_t a, std::size_t b, Point& v) {
      const auto& [a2, da] = candidates[a];
      const auto& [b2, db] = candidates[b];
      const double det = da.x() * db.y() - da.y() * db.x();
      if (!(det > 0.0) || det * det < 1e-8 * a2 * b2) return false;
      const double inv = 0.5 / det;
      v = Point((a2 * db.y() - b2 * da.y()) * inv, (b2 * da.x() - a2 * db.x()) * inv);
      return true;
    };
    // Whether b is a hull vertex between a and c. Where round-off leaves the turn in q undecided, b's own side
    // decides: it is needed when it cuts off the vertex of a and c, and within round-off of that vertex (co-
    // circular sites, as on a regular lattice, put three sides through one vertex) it adds no side. An
    // undecidable case leaves the cell to the clips.
    bool undecided = false;
    auto turns_left = [&](std::size_t a, std::size_t b, std::size_t c) {
      const double ex = qx[b] - qx[a], ey = qy[b] - qy[a], rx = qx[c] - qx[a], ry = qy[c] - qy[a];
      const double cross = ex * ry - ey * rx, tolerance = 1e-13 * (std::abs(ex * ry) + std::abs(ey * rx));
      if (cross > tolerance) return true;
      if (cross < -tolerance) return false;
      Point v;
      if (!vertex(a, c, v)) {
        undecided = true;
        return false;
      }
      const auto& [b2, db] = candidates[b];
      const double reach = db.dot(v);
      return reach - 0.5 * b2 > 1e-13 * (std::abs(reach) + 0.5 * b2);
    };
    for (std::size_t m = 0; m <= k; ++m) {  // the start again at the end closes the hull
      const std::size_t at = first + m;
      const std::size_t c = order[at - k * static_cast<std::size_t>(at >= k)];  // wrapped without a branch
      while (n_hull >= 2 && !turns_left(hull[n_hull - 2], hull[n_hull - 1], c)) --n_hull;
      hull[n_hull++] = static_cast<std::uint8_t>(c);
    }
    --n_hull;  // the start, taken twice
    if (n_hull < 3 || undecided) return false;
    double r2 = 0.0;
    for (std::size_t i = 0, j = n_hull - 1; i < n_hull; j = i++) {  // vertex of the sides of hull[j] and hull[i]
      const std::size_t a = hull[j], b = hull[i];
      // det > 0 for every edge: the hull goes round the origin, so the sides bound the cell
      Point v;
      if (!vertex(a, b, v)) return false;
      if (!(v.x() > lo.x() && v.y() > lo.y() && v.x() < hi.x() && v.y() < hi.y())) return false;
      cell.v[i] = v;
      r2 = std::max(r2, v.squaredNorm());
    }
    cell.n = static_cast<int>(n_hull);
    r2_max = r2;
    return true;
  }

  /// The sites that can still cut a cell lie in the discs centred on its vertices v that pass through the
  /// particle (nearer to v than |v|): the bisector of such a site cuts v off, and no other site's bisector
  /// reaches a vertex. Those discs inside the gathered disc (radius^2 = outer2) were seen; this gathers the sites in
  /// the others from the box around them and cuts by them all, leaving the cell exact. Far cheaper than a
  /// wider concentric disc when one or two vertices reach out. Returns false as cut_by does.
  static bool cut_by_vertex_discs(const neighbors::CellList<2>& cells, std::size_t a, const Point& xa, double outer2,
                                  ConvexPolygon*& cell, ConvexPolygon*& scratch, double& r2_max,
                                  std::vector<Candidate>& found) {
    std::array<Point, ConvexPolygon::capacity> centre;
    std::array<double, ConvexPolygon::capacity> slack;
    int n_open = 0;
    Point lo = Point::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (int i = 0; i < cell->n; ++i) {
      const Point& v = (*cell)[i];
      const double v2 = v.squaredNorm();
      if (4.0 * v2 <= outer2) continue;
      const double r = std::sqrt(v2);
      lo = lo.cwiseMin(v - Point::Constant(r));
      hi = hi.cwiseMax(v + Point::Constant(r));
      centre[static_cast<std::size_t>(n_open)] = 2.0 * v;      // in d: |d - v|^2 < |v|^2  <=>  2 v . d > |d|^2
      slack[static_cast<std::size_t>(n_open++)] = -1e-9 * v2;  // rounding of the vertex
    }
    std::size_t n_found = 0;
    cells.for_each_run_in_box(xa + lo, xa + hi, [&](const std::uint32_t* index, const Point* at, std::size_t count) {
      grown(found, n_found + count);
      for (std::size_t s = 0; s < count; ++s) {
        const Point d = at[s] - xa;
        const double d2 = d.squaredNorm();
        bool in_disc = false;
        for (int k = 0; k < n_open; ++k)
          in_disc |= centre[static_cast<std::size_t>(k)].dot(d) - d2 > slack[static_cast<std::size_t>(k)];
        found[n_found] = {d2, d};
        n_found += static_cast<std::size_t>(in_disc & (d2 > outer2) & (index[s] != a));
      }
    });
    return cut_by({found.data(), n_found}, cell, scratch, r2_max);
  }

  /// Once the square of the gathered disc (radius) holds every point, the points outside the disc are all
  /// that is left: the cell is cut by each of them, nearest first, and is then exact. (Stopping there instead
  /// left sparse sets in walled or open boxes with cells too large: a neighbour just outside the disc never
  /// cut.) Returns false as cut_by does.
  static bool cut_by_rest(const neighbors::CellList<2>& cells, std::size_t a, const Point& xa, double radius,
                          ConvexPolygon*& cell, ConvexPolygon*& scratch, double& r2_max,
                          std::vector<Candidate>& found) {
    const double outer2 = radius * radius;
    std::size_t n_found = 0;
    cells.for_each_run_within(xa, radius, [&](const std::uint32_t* index, const Point* at, std::size_t count) {
      grown(found, n_found + count);
      for (std::size_t s = 0; s < count; ++s) {
        const Point d = at[s] - xa;
        const double d2 = d.squaredNorm();
        found[n_found] = {d2, d};
        n_found += static_cast<std::size_t>((d2 > outer2) & (index[s] != a));
      }
    });
    const std::span<Candidate> rest(found.data(), n_found);
    std::sort(rest.begin(), rest.end(), [](const Candidate& p, const Candidate& q) { return p.d2 < q.d2; });
    return cut_by(rest, cell, scratch, r2_max);
  }

  template <class Visitor>
  bool try_build(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing_radius,
                 double margin, Visitor& visit, std::span<const std::uint32_t> only) {
    SitesWithImages& sites = sites_;
    detail::add_periodic_images(x, box, margin, sites);
    neighbors::CellList<2>& cells = cells_;
    const double spacing = detail::mean_spacing(x, box);
    cells.build(sites.x, spacing);
    std::atomic<bool> ok{true}, too_costly{false};
    std::atomic<std::size_t> from_hull{0}, scanned{0};
    const double budget = scan_budget_per_cell * static_cast<double>(detail::chosen_count(sites.n_real, only)) + 1e5;
    rsph::run_parallel(detail::chosen_count(sites.n_real, only), [&](int thread, std::size_t begin, std::size_t end) {
      ConvexPolygon buffers[2];
      // Candidate buffers keep their size; n_found counts what the current disc wrote.
      std::vector<Candidate> found, extra;
      std::size_t n_found = 0, by_hull = 0;
      std::size_t scanned_here = 0;
      for (std::size_t k = begin; k < end && ok.load(std::memory_order_relaxed); ++k) {
        // The shared count is added to once per few thousand points scanned (a few dozen ordinary cells): added
        // to per cell, its cache line went back and forth between the cores. A thread overruns the budget by
        // at most scan_flush points and one cell's scan.
        if (scanned_here >= scan_flush) {
          if (static_cast<double>(scanned.fetch_add(scanned_here, std::memory_order_relaxed) + scanned_here) > budget) {
            too_costly.store(true, std::memory_order_relaxed);
            ok.store(false, std::memory_order_relaxed);
            break;
          }
          scanned_here = 0;
        }
        const std::size_t a = detail::chosen(only, k);
        const Point xa = sites.x[a];
        const double closing = closing_radius.empty() ? 0.0 : closing_radius[a];
        ConvexPolygon* cell = &buffers[0];  // cuts alternate between the buffers instead of copying
        ConvexPolygon* scratch = &buffers[1];
        *cell = detail::initial_cell(xa, box, margin, closing);
        double r2_max = detail::max_radius2_origin(*cell);
        // Candidates come disc by disc (each wider disc adding its annulus) until the security
        // disc, twice the farthest vertex distance, lies inside the discs seen: no point beyond can cut.
        // The first disc's cell comes from the dual hull; otherwise the candidates cut it nearest first, as
        // the nearest carve out most of the cell (the cell is an intersection of half-planes, so the order
        // cannot change it).
        double inner2 = -1.0;
        for (double radius = first_radius_spacings * spacing;; radius *= disc_growth) {
          const double outer2 = radius * radius;
          n_found = 0;
          cells.for_each_run_within(xa, radius, [&](const std::uint32_t* index, const Point* at, std::size_t count) {
            grown(found, n_found + count);
            scanned_here += count;
            // Each point is written and kept by advancing the count, without a branch: in or out is a coin
            // toss no predictor learns. Rows come bottom to top; those above the particle are read right to left,
            // so the candidates arrive nearly in the dual hull's order of angle (counted from -x: below the
            // particle rising left to right, above it right to left), and its insertion sort hardly moves them.
            const auto above = static_cast<std::ptrdiff_t>(at[0].y() > xa.y());
            const std::ptrdiff_t step = 1 - 2 * above;
            std::ptrdiff_t s = above * (static_cast<std::ptrdiff_t>(count) - 1);
            for (std::size_t m = 0; m < count; ++m, s += step) {
              const Point d = at[s] - xa;
              const double d2 = d.squaredNorm();
              found[n_found] = {d2, d};
              n_found += static_cast<std::size_t>((d2 > inner2) & (d2 <= outer2) & (index[s] != a));
            }
          });
          const std::span<Candidate> disc(found.data(), n_found);
          if (inner2 < 0.0 && cell_from_dual_hull(disc, (*cell)[0], (*cell)[2], *scratch, r2_max)) {
            std::swap(cell, scratch);
            ++by_hull;
          } else {
            std::sort(disc.begin(), disc.end(), [](const Candidate& p, const Candidate& q) { return p.d2 < q.d2; });
            if (!cut_by(disc, cell, scratch, r2_max)) break;
          }
          if (4.0 * r2_max <= outer2) break;
          if (cells.covers(xa, radius)) {  // the disc's square holds every point: cut by those outside the disc
            cut_by_rest(cells, a, xa, radius, cell, scratch, r2_max, extra);
            break;
          }
          if (r2_max <= outer2) {  // the vertex discs reach at most one radius beyond: gather only them
            cut_by_vertex_discs(cells, a, xa, outer2, cell, scratch, r2_max, extra);
            break;
          }
          inner2 = outer2;
        }
        if (!detail::finish_cell(cell, scratch, a, xa, box, margin, closing, r2_max)) {
          ok.store(false, std::memory_order_relaxed);
          break;
        }
        visit(thread, a, *cell);
      }
      from_hull.fetch_add(by_hull, std::memory_order_relaxed);
    });
    cells_from_hull_ = from_hull.load();
    handed_to_boost_ = too_costly.load();
    return ok || handed_to_boost_;  // handed over: no wider images, BoostVoronoi takes the set
  }

  bool handed_to_boost_ = false;

  std::size_t cells_from_hull_ = 0;
  // Kept from build to build: a remap every few dozen steps would otherwise fault in fresh pages each time.
  SitesWithImages sites_;
  neighbors::CellList<2> cells_;
};

/// Boost.Polygon builder: Voronoi neighbours from construct_voronoi on quantized positions, cells cut
/// in double precision. Same visitor protocol as LocalVoronoi.
class BoostVoronoi : public detail::WideningBuilder<BoostVoronoi> {
 public:
  static constexpr double quantization_levels = 1073741824.0;  ///< 2^30 steps over the extent of the points

 private:
  friend class detail::WideningBuilder<BoostVoronoi>;

  /// The chosen particles (ascending) with a site of their own or an adjacent group closer than 1e4 quanta:
  /// there the quantized diagram's neighbours may not be the true ones (pairs 1e-9 of a spacing apart; far
  /// outliers that coarsen the quanta), so their cells are checked against every site that can cut them.
  static std::vector<std::uint32_t> doubtful_cells(const SitesWithImages& sites,
                                                   const std::vector<std::uint32_t>& group_of,
                                                   const std::vector<std::vector<std::uint32_t>>& members,
                                                   const std::vector<std::vector<std::uint32_t>>& adjacent,
                                                   double quantum, std::span<const std::uint32_t> only) {
    const double close2 = (1e4 * quantum) * (1e4 * quantum);
    std::vector<std::uint32_t> doubtful;
    for (std::size_t k = 0; k < detail::chosen_count(sites.n_real, only); ++k) {
      const std::size_t a = detail::chosen(only, k);
      bool close = false;
      auto near = [&](std::uint32_t group) {
        for (const std::uint32_t b : members[group])
          close = close || (b != a && (sites.x[b] - sites.x[a]).squaredNorm() < close2);
      };
      near(group_of[a]);
      for (const std::uint32_t nb : adjacent[group_of[a]]) near(nb);
      if (close) doubtful.push_back(static_cast<std::uint32_t>(a));
    }
    std::sort(doubtful.begin(), doubtful.end());
    return doubtful;
  }

  template <class Visitor>
  bool try_build(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing_radius,
                 double margin, Visitor& visit, std::span<const std::uint32_t> only) {
    SitesWithImages sites;
    detail::add_periodic_images(x, box, margin, sites);
    const std::size_t n_sites = sites.x.size();
    // Quantize; points that share integer coordinates form one group (Boost keeps one of them).
    Point lo = sites.x[0], hi = sites.x[0];
    for (const auto& p : sites.x) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
    const double scale = quantization_levels / extent;
    std::vector<boost::polygon::point_data<int>> unique;
    std::vector<std::uint32_t> group_of(n_sites);
    std::vector<std::vector<std::uint32_t>> members;
    std::unordered_map<std::uint64_t, std::uint32_t> index_of;
    index_of.reserve(n_sites);
    for (std::size_t i = 0; i < n_sites; ++i) {
      const auto qx = static_cast<int>(std::llround((sites.x[i].x() - lo.x()) * scale));
      const auto qy = static_cast<int>(std::llround((sites.x[i].y() - lo.y()) * scale));
      const std::uint64_t key = (static_cast<std::uint64_t>(qx) << 32) | static_cast<std::uint32_t>(qy);
      auto [it, fresh] = index_of.emplace(key, static_cast<std::uint32_t>(unique.size()));
      if (fresh) {
        unique.emplace_back(qx, qy);
        members.emplace_back();
      }
      group_of[i] = it->second;
      members[it->second].push_back(static_cast<std::uint32_t>(i));
    }
    boost::polygon::voronoi_diagram<double> vd;
    boost::polygon::construct_voronoi(unique.begin(), unique.end(), &vd);
    std::vector<std::vector<std::uint32_t>> adjacent(unique.size());
    for (const auto& c : vd.cells()) {
      const auto* e = c.incident_edge();
      if (!e) continue;
      auto& adj = adjacent[c.source_index()];
      do {
        adj.push_back(static_cast<std::uint32_t>(e->twin()->cell()->source_index()));
        e = e->next();
      } while (e != c.incident_edge());
    }
    const auto doubtful = doubtful_cells(sites, group_of, members, adjacent, extent / quantization_levels, only);
    neighbors::CellList<2> lookup;  // only where quantization may have hidden a neighbour
    if (!doubtful.empty()) lookup.build(sites.x, detail::mean_spacing(x, box));
    std::atomic<bool> ok{true};
    rsph::run_parallel(detail::chosen_count(sites.n_real, only), [&](int thread, std::size_t begin, std::size_t end) {
      ConvexPolygon buffers[2];
      for (std::size_t k = begin; k < end && ok.load(std::memory_order_relaxed); ++k) {
        const std::size_t a = detail::chosen(only, k);
        const Point xa = sites.x[a];
        const double closing = closing_radius.empty() ? 0.0 : closing_radius[a];
        ConvexPolygon* cell = &buffers[0];
        ConvexPolygon* scratch = &buffers[1];
        *cell = detail::initial_cell(xa, box, margin, closing);
        const std::uint32_t g = group_of[a];
        auto cut_group = [&](std::uint32_t group) {
          for (std::uint32_t b : members[group]) {
            if (b == a) continue;
            const Point d = sites.x[b] - xa;
            if (d.squaredNorm() == 0.0) {
              cell->clear();
              return;
            }
            if (detail::cut_by_bisector(*cell, d, *scratch)) std::swap(cell, scratch);
          }
        };
        cut_group(g);
        for (std::uint32_t nb : adjacent[g]) {
          if (cell->empty()) break;
          cut_group(nb);
        }
        if (!cell->empty() && std::binary_search(doubtful.begin(), doubtful.end(), static_cast<std::uint32_t>(a))) {
          // every site that can still cut the cell lies within twice its farthest vertex: cut by them all
          const double reach = 2.0 * std::sqrt(detail::max_radius2_origin(*cell));
          lookup.for_each_within(xa, reach, [&](std::uint32_t b) {
            const Point d = sites.x[b] - xa;
            if (b == a || cell->empty() || d.squaredNorm() >= reach * reach) return;
            if (d.squaredNorm() == 0.0) return cell->clear();
            if (detail::cut_by_bisector(*cell, d, *scratch)) std::swap(cell, scratch);
          });
        }
        if (!detail::finish_cell(cell, scratch, a, xa, box, margin, closing, detail::max_radius2_origin(*cell))) {
          ok.store(false, std::memory_order_relaxed);
          break;
        }
        visit(thread, a, *cell);
      }
    });
    return ok.load();
  }
};

template <class Visitor>
void LocalVoronoi::build(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing_radius,
                         Visitor&& visit, std::span<const std::uint32_t> only) {
  handed_to_boost_ = false;
  detail::WideningBuilder<LocalVoronoi>::build(x, box, closing_radius, visit, only);
  if (!handed_to_boost_) return;
  visit.restart();
  BoostVoronoi boost;
  boost.build(x, box, closing_radius, visit, only);
  cells_from_hull_ = 0;
}

/// Cell area of every particle, for tests and diagnostics: stores areas, not polygons.
template <class Builder>
std::vector<double> cell_areas(Builder& builder, const std::vector<Point>& x, const Box<2>& box,
                               const std::vector<double>& closing_radius = {}) {
  struct Collect {
    std::vector<double>* out;
    void restart() { std::fill(out->begin(), out->end(), 0.0); }
    void operator()(int, std::size_t a, const ConvexPolygon& cell) { (*out)[a] = area(cell); }
  };
  std::vector<double> areas(x.size(), 0.0);
  builder.build(x, box, closing_radius, Collect{&areas});
  return areas;
}

namespace detail {
/// A visitor of the builders' protocol, for the concept below.
struct CellProbe {
  void operator()(int, std::size_t, const ConvexPolygon&) {}
  void restart() {}
};
}  // namespace detail

/// A Voronoi cell builder: build(x, box, closing_radius, visit) hands visit(thread, a, cell) the cell of
/// each particle (relative to x[a]), closed against the box's walls and open edges.
template <class B>
concept CellBuilder = requires(B& b, const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& r,
                               detail::CellProbe visit) {
  b.build(x, box, r, visit);
};

template <class B>
constexpr bool check_cell_builder() {
  static_assert(CellBuilder<B>,
                "a Voronoi cell builder needs `void build(const std::vector<Point>& x, const Box<2>& box, const "
                "std::vector<double>& closing_radius, Visitor&& visit)` calling visit(thread, a, cell) per particle");
  return true;
}

}  // namespace rsph::geometry
