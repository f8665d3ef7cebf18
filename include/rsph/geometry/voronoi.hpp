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
#include "rsph/geometry/sites.hpp"
#include "rsph/geometry/voronoi_boost.hpp"
#include "rsph/geometry/voronoi_cells2d.hpp"
#include "rsph/neighbors/cell_list.hpp"

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
#include <vector>

namespace rsph::geometry {

/// Local half-plane builder. visit(thread, a, cell) receives each chosen particle's cell in coordinates
/// relative to x[a]; particles of one thread arrive in increasing order. When periodic images turn out
/// too few (a cell reaches past them), the builder widens them and starts again, calling
/// visit.restart() first: a visitor must then forget what it was given.
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

  /// What one thread keeps from cell to cell: the candidate buffers (they keep their size), the points it has
  /// scanned since it last added them to the shared count, and how many cells came from the dual hull.
  struct ThreadScratch {
    std::vector<Candidate> found, extra;
    std::size_t scanned = 0, by_hull = 0;
  };

  /// Gathers the candidates with inner2 < d^2 <= outer2 from the cells within `radius` of x_a into s.found;
  /// returns how many. Each point is written and kept by advancing the count, without a branch: in or out is a
  /// coin toss no predictor learns. Rows come bottom to top; those above the particle are read right to left,
  /// so the candidates arrive nearly in the dual hull's order of angle (counted from -x: below the particle
  /// rising left to right, above it right to left), and its insertion sort hardly moves them.
  static std::size_t gather_disc(const neighbors::CellList<2>& cells, std::size_t a, const Point& xa, double radius,
                                 double inner2, double outer2, ThreadScratch& s) {
    std::size_t n_found = 0;
    cells.for_each_run_within(xa, radius, [&](const std::uint32_t* index, const Point* at, std::size_t count) {
      grown(s.found, n_found + count);
      s.scanned += count;
      const auto above = static_cast<std::ptrdiff_t>(at[0].y() > xa.y());
      const std::ptrdiff_t step = 1 - 2 * above;
      std::ptrdiff_t k = above * (static_cast<std::ptrdiff_t>(count) - 1);
      for (std::size_t m = 0; m < count; ++m, k += step) {
        const Point d = at[k] - xa;
        const double d2 = d.squaredNorm();
        s.found[n_found] = {d2, d};
        n_found += static_cast<std::size_t>((d2 > inner2) & (d2 <= outer2) & (index[k] != a));
      }
    });
    return n_found;
  }

  /// Cuts particle a's cell out of its initial polygon. Candidates come disc by disc (each wider disc adding its
  /// annulus) until the security disc, twice the farthest vertex distance, lies inside the discs seen: no point
  /// beyond can cut. The first disc's cell comes from the dual hull; otherwise the candidates cut it nearest
  /// first, as the nearest carve out most of the cell (the cell is an intersection of half-planes, so the order
  /// cannot change it). A coincident site leaves the cell empty.
  static void cut_cell(const neighbors::CellList<2>& cells, std::size_t a, const Point& xa, double spacing,
                       ConvexPolygon*& cell, ConvexPolygon*& scratch, double& r2_max, ThreadScratch& s) {
    double inner2 = -1.0;
    for (double radius = first_radius_spacings * spacing;; radius *= disc_growth) {
      const double outer2 = radius * radius;
      const std::span<Candidate> disc(s.found.data(), gather_disc(cells, a, xa, radius, inner2, outer2, s));
      if (inner2 < 0.0 && cell_from_dual_hull(disc, (*cell)[0], (*cell)[2], *scratch, r2_max)) {
        std::swap(cell, scratch);
        ++s.by_hull;
      } else {
        std::sort(disc.begin(), disc.end(), [](const Candidate& p, const Candidate& q) { return p.d2 < q.d2; });
        if (!cut_by(disc, cell, scratch, r2_max)) return;
      }
      if (4.0 * r2_max <= outer2) return;
      if (cells.covers(xa, radius)) {  // the disc's square holds every point: cut by those outside the disc
        cut_by_rest(cells, a, xa, radius, cell, scratch, r2_max, s.extra);
        return;
      }
      if (r2_max <= outer2) {  // the vertex discs reach at most one radius beyond: gather only them
        cut_by_vertex_discs(cells, a, xa, outer2, cell, scratch, r2_max, s.extra);
        return;
      }
      inner2 = outer2;
    }
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
      ThreadScratch own;
      for (std::size_t k = begin; k < end && ok.load(std::memory_order_relaxed); ++k) {
        // The shared count is added to once per few thousand points scanned (a few dozen ordinary cells): added
        // to per cell, its cache line went back and forth between the cores. A thread overruns the budget by
        // at most scan_flush points and one cell's scan.
        if (own.scanned >= scan_flush) {
          if (static_cast<double>(scanned.fetch_add(own.scanned, std::memory_order_relaxed) + own.scanned) > budget) {
            too_costly.store(true, std::memory_order_relaxed);
            ok.store(false, std::memory_order_relaxed);
            break;
          }
          own.scanned = 0;
        }
        const std::size_t a = detail::chosen(only, k);
        const Point xa = sites.x[a];
        const double closing = closing_radius.empty() ? 0.0 : closing_radius[a];
        ConvexPolygon* cell = &buffers[0];  // cuts alternate between the buffers instead of copying
        ConvexPolygon* scratch = &buffers[1];
        *cell = detail::initial_cell(xa, box, margin, closing);
        double r2_max = detail::max_radius2_origin(*cell);
        cut_cell(cells, a, xa, spacing, cell, scratch, r2_max, own);
        if (!detail::finish_cell(cell, scratch, a, xa, box, margin, closing, r2_max)) {
          ok.store(false, std::memory_order_relaxed);
          break;
        }
        visit(thread, a, *cell);
      }
      from_hull.fetch_add(own.by_hull, std::memory_order_relaxed);
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

}  // namespace rsph::geometry
