#pragma once
// An orbit-following polar lattice for disks: rings r_i = r_in + (i + 1/2) Delta, ring i holding
// N_i = round(2 pi r_i / Delta) sites, so that its cells are nearly squares of side Delta. At every remap
// each ring is turned by the angle its gas has moved since the last one, so that gas on circular orbits
// lands on its new site exactly and the remap sees only the deviation from the mean flow (as FARGO's
// orbital advection does for a grid, Masset 2000). The new cells are the Voronoi cells of the new sites:
// polygons, no two alike, that change from remap to remap as the rings turn against each other.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/neighbors/cell_list.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace rsph::lattice {

/// The sites of a Rings lattice at one remap: the rings in use, each turned by its phase, and once
/// build_cells has run, the Voronoi cells of the sites held and what the candidate lookup needs of each ring.
/// Sites are numbered ring by ring from the innermost, each ring counter-clockwise. Every site's position is
/// known from its ring; the sites held (every one, or on many ranks an arc of each ring around a rank's gas,
/// hold()) also keep their position and cell, in slots of their own, so that a rank's memory follows its gas.
struct RingSites {
  double spacing = 0.0;
  std::int64_t first_ring = 0;         ///< the lattice's index of the innermost ring here
  std::vector<double> radius, phase;   ///< per ring: r_i, and the angle site 0 lies half a step past
  std::vector<std::size_t> offset{0};  ///< per ring and one past the last: its first site's number
  /// Per ring: the first site held (its index on the ring), how many follow it (wrapping), and the first slot.
  std::vector<std::int64_t> held_first, held_count;
  std::vector<std::size_t> held_offset{0};
  std::vector<Vec<2>> xy;                ///< every site held, by slot (place() sets them from the phases)
  std::vector<std::size_t> cell_start;   ///< per slot and one past the last: its first vertex (none: not built)
  std::vector<Vec<2>> vertices;          ///< every cell's vertices, relative to its site, counter-clockwise
  std::vector<geometry::Bounds> bounds;  ///< every held cell's bounding box, relative to its site
  /// Per ring: the least and largest distance of its cells from the origin, and the most any cell reaches
  /// in angle (seen from the origin) from its site's angle; pi where a cell holds the origin.
  std::vector<double> reach_lo, reach_hi, reach_angle;
  std::size_t n_cells = 0;

  std::size_t rings() const { return radius.size(); }
  std::int64_t sites_on(std::size_t k) const { return static_cast<std::int64_t>(offset[k + 1] - offset[k]); }
  double step(std::size_t k) const { return 2.0 * std::numbers::pi / static_cast<double>(sites_on(k)); }
  double angle(std::size_t k, std::int64_t j) const { return phase[k] + (static_cast<double>(j) + 0.5) * step(k); }
  std::size_t ring_of(std::size_t c) const {
    return static_cast<std::size_t>(std::upper_bound(offset.begin(), offset.end(), c) - offset.begin()) - 1;
  }
  /// Holds every site (the serial remap, and a scene's start).
  void hold_all() {
    std::vector<std::int64_t> count(rings());
    for (std::size_t k = 0; k < rings(); ++k) count[k] = sites_on(k);
    hold(std::vector<std::int64_t>(rings(), 0), std::move(count));
  }
  /// Holds on each ring k the held_count[k] sites from held_first[k] on (wrapping round the ring).
  void hold(std::vector<std::int64_t> first, std::vector<std::int64_t> count) {
    held_first = std::move(first);
    held_count = std::move(count);
    held_offset.assign(1, 0);
    all_held = true;
    for (std::size_t k = 0; k < rings(); ++k) {
      held_offset.push_back(held_offset.back() + static_cast<std::size_t>(held_count[k]));
      all_held = all_held && held_first[k] == 0 && held_count[k] == sites_on(k);
    }
  }
  std::size_t n_held() const { return held_offset.back(); }
  /// Site c's slot among the held sites; -1 where it is not held.
  std::int64_t slot(std::size_t c) const {
    if (all_held) return static_cast<std::int64_t>(c);
    const std::size_t k = ring_of(c);
    std::int64_t d = static_cast<std::int64_t>(c - offset[k]) - held_first[k];  // in (-N_k, N_k)
    if (d < 0) d += sites_on(k);
    return d < held_count[k] ? static_cast<std::int64_t>(held_offset[k]) + d : -1;
  }
  /// The site held in slot i.
  std::size_t site_in(std::size_t i) const {
    if (all_held) return i;
    const std::size_t k =
        static_cast<std::size_t>(std::upper_bound(held_offset.begin(), held_offset.end(), i) - held_offset.begin()) - 1;
    const auto n = sites_on(k);
    return offset[k] + static_cast<std::size_t>((held_first[k] + static_cast<std::int64_t>(i - held_offset[k])) % n);
  }
  /// Site c's position: its ring's radius at its angle (the same bits whether held or not).
  Vec<2> site(std::size_t c) const {
    if (const std::int64_t i = slot(c); i >= 0) return xy[static_cast<std::size_t>(i)];
    return place_site(c);
  }
  Vec<2> place_site(std::size_t c) const {
    const std::size_t k = ring_of(c);
    const double a = angle(k, static_cast<std::int64_t>(c - offset[k]));
    return radius[k] * Vec<2>(std::cos(a), std::sin(a));
  }
  /// Sets every site held from its ring's radius and phase.
  void place() {
    xy.resize(n_held());
    for (std::size_t i = 0; i < xy.size(); ++i) xy[i] = place_site(site_in(i));
  }
  /// The site of ring k nearest in angle to phi (wrapped into the ring).
  std::int64_t nearest(std::size_t k, double phi) const {
    const auto n = sites_on(k);
    const auto j = static_cast<std::int64_t>(std::floor((phi - phase[k]) / step(k)));
    return ((j % n) + n) % n;
  }
  /// The site nearest in angle to x on the ring nearest to |x| (clamped to the rings): the site whose cell most
  /// likely holds x.
  std::size_t nearest_site(const Vec<2>& x) const {
    const std::size_t k = ring_nearest(x.norm());
    return offset[k] + static_cast<std::size_t>(nearest(k, std::atan2(x.y(), x.x())));
  }
  /// The ring whose radius lies nearest to r (clamped to the rings).
  std::size_t ring_nearest(double r) const {
    const auto i = static_cast<std::int64_t>(std::floor((r - radius[0]) / spacing + 0.5));
    return static_cast<std::size_t>(std::clamp<std::int64_t>(i, 0, static_cast<std::int64_t>(rings()) - 1));
  }
  /// The area of the ring's band a cell stands for, 2 pi r_i Delta / N_i: what a full cell holds (the cells of
  /// the outermost and innermost rings reach beyond their band to take in any gas out there).
  double nominal_area(std::size_t c) const {
    const std::size_t k = ring_of(c);
    return step(k) * radius[k] * spacing;
  }
  /// Whether cell c's bounding box meets the box b (both relative to `origin`); a cell not held or not built
  /// meets none.
  bool box_meets(std::size_t c, const Vec<2>& origin, const geometry::Bounds& b) const {
    const std::int64_t slot_c = slot(c);
    if (slot_c < 0) return false;
    const auto i = static_cast<std::size_t>(slot_c);
    const Vec<2> shift = xy[i] - origin;
    return bounds[i].lo.x() + shift.x() < b.hi.x() && bounds[i].hi.x() + shift.x() > b.lo.x() &&
           bounds[i].lo.y() + shift.y() < b.hi.y() && bounds[i].hi.y() + shift.y() > b.lo.y();
  }
  /// At least cell c's diameter: its bounding box's diagonal (a cell that box_meets).
  double diameter(std::size_t c) const {
    const auto i = static_cast<std::size_t>(slot(c));
    return (bounds[i].hi - bounds[i].lo).norm();
  }
  /// Cell c relative to `origin` (a cell that box_meets).
  geometry::ConvexPolygon cell(std::size_t c, const Vec<2>& origin) const {
    const auto i = static_cast<std::size_t>(slot(c));
    geometry::ConvexPolygon out;
    const Vec<2> shift = xy[i] - origin;
    for (std::size_t v = cell_start[i]; v < cell_start[i + 1]; ++v) out.push(vertices[v] + shift);
    return out;
  }
  /// f(g) for the sites next to c: its two neighbours on its ring and the three nearest on each ring beside.
  template <class F>
  void for_each_neighbour(std::size_t c, F&& f) const {
    const std::size_t k = ring_of(c);
    const auto j = static_cast<std::int64_t>(c - offset[k]), n = sites_on(k);
    f(offset[k] + static_cast<std::size_t>((j + 1) % n));
    f(offset[k] + static_cast<std::size_t>((j + n - 1) % n));
    const double phi = angle(k, j);
    for (const std::size_t m : {k - 1, k + 1}) {
      if (m >= rings()) continue;  // k - 1 wraps past zero for the innermost ring
      const auto near = nearest(m, phi), nm = sites_on(m);
      for (std::int64_t d = -1; d <= 1; ++d) f(offset[m] + static_cast<std::size_t>(((near + d) % nm + nm) % nm));
    }
  }
  /// f(c) for every site whose cell may overlap the polygon `p` (relative to xo): the rings whose radial
  /// reach meets p's, and on each the sites whose angular reach meets p's. A lookup by ring and angle.
  template <class F>
  void for_each_candidate(const geometry::ConvexPolygon& p, const Vec<2>& xo, F&& f) const;
  /// Every site's Voronoi cell among the sites (see the definition below), or, where `wanted` is not empty, the
  /// cells of the sites it marks and of the innermost and outermost rings; the others have no vertices and
  /// meet no box, so no lookup names them.
  void build_cells(double edge_extent, const std::vector<std::uint8_t>& wanted = {});

 private:
  bool all_held = true;
};

namespace detail {
/// The extent of polygon p (relative to xo) seen from the origin: the least and largest distance, and the
/// angles of its vertices relative to the direction `towards` (in (-pi, pi]); pi both ways where p holds
/// the origin.
struct PolarExtent {
  double r_lo = 0.0, r_hi = 0.0, angle_lo = 0.0, angle_hi = 0.0;
};
inline PolarExtent polar_extent(const geometry::ConvexPolygon& p, const Vec<2>& xo, const Vec<2>& towards) {
  PolarExtent e;
  e.r_lo = std::numeric_limits<double>::max();
  bool inside = p.n >= 3, ahead = true;
  const double scale = towards.norm();
  double t_lo = 0.0, t_hi = 0.0;  // tangents of the angles while every vertex lies ahead (dot > 0)
  for (int i = 0, j = p.n - 1; i < p.n; j = i++) {
    const Vec<2> a = p[j] + xo, b = p[i] + xo, ab = b - a;
    inside &= ab.x() * (-a.y()) - ab.y() * (-a.x()) > 0.0;  // the origin left of every edge
    const double t = ab.squaredNorm() > 0.0 ? std::clamp(-a.dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    e.r_lo = std::min(e.r_lo, (a + t * ab).norm());
    const double r = b.norm();
    e.r_hi = std::max(e.r_hi, r);
    if (r <= 1e-12 * scale) continue;  // a vertex on the origin has no angle (a wedge's tip)
    const double cross = towards.x() * b.y() - towards.y() * b.x(), dot = towards.dot(b);
    if (dot > 0.0) {
      t_lo = std::min(t_lo, cross / dot);
      t_hi = std::max(t_hi, cross / dot);
    } else {
      ahead = false;
    }
    if (!ahead) {  // beyond a right angle somewhere: angles one by one
      const double ang = std::atan2(cross, dot);
      e.angle_lo = std::min(e.angle_lo, ang);
      e.angle_hi = std::max(e.angle_hi, ang);
    }
  }
  // the angle grows with its tangent below a right angle: two arctangents for the whole polygon
  e.angle_lo = std::min(e.angle_lo, std::atan(t_lo));
  e.angle_hi = std::max(e.angle_hi, std::atan(t_hi));
  if (inside) {
    e.r_lo = 0.0;
    e.angle_lo = -std::numbers::pi;
    e.angle_hi = std::numbers::pi;
  }
  return e;
}

/// Site c's Voronoi cell among the sites within `rings` rings and `reach` sites along each (relative to the
/// site), clipped from a square of half-width `half`: the sites on its own ring first, then the rings beside
/// from the nearest site outwards, so that the cell takes its shape from the first few and the rest mostly
/// cut nothing (a side that cuts nothing costs no copy).
inline geometry::ConvexPolygon voronoi_cell(const RingSites& s, std::size_t c, std::size_t k, double half,
                                            std::size_t rings, std::int64_t reach) {
  geometry::ConvexPolygon cell = geometry::ConvexPolygon::rectangle(-half, -half, half, half);
  const Vec<2> x = s.site(c);
  const double phi = s.angle(k, static_cast<std::int64_t>(c - s.offset[k]));
  auto cut_by = [&](std::size_t m, std::int64_t d) {
    const auto nm = s.sites_on(m);
    const std::size_t b = s.offset[m] + static_cast<std::size_t>(((s.nearest(m, phi) + d) % nm + nm) % nm);
    if (b == c) return;
    const Vec<2> dx = s.site(b) - x;
    geometry::clip_halfplane(cell, dx, 0.5 * dx.squaredNorm());
  };
  for (std::int64_t d = 0; d <= reach; ++d)
    for (std::size_t dm = 0; dm <= rings; ++dm)
      for (const int side : {-1, 1}) {
        if (dm == 0 && side == 1) continue;  // the own ring once
        if (dm > k && side == -1) continue;
        const std::size_t m = side < 0 ? k - dm : k + dm;
        if (m >= s.rings()) continue;
        cut_by(m, d);
        if (d > 0) cut_by(m, -d);
      }
  return cell;
}

/// The largest arc of ring sites 0..n-1 that none of the intervals [lo, hi] of site indices (lo in [0, n),
/// hi < lo + n, sorted by lo) covers, as its first site and length; length 0 where they cover the ring.
inline std::pair<std::int64_t, std::int64_t> largest_gap(const std::vector<std::pair<std::int64_t, std::int64_t>>& in,
                                                         std::int64_t n) {
  std::vector<std::pair<std::int64_t, std::int64_t>> gaps;
  std::int64_t end = in.front().second;
  for (std::size_t i = 1; i < in.size(); ++i) {
    if (in[i].first > end + 1) gaps.emplace_back(end + 1, in[i].first - 1);
    end = std::max(end, in[i].second);
  }
  gaps.emplace_back(end + 1, in.front().first + n - 1);  // round past site n - 1
  const std::int64_t tail = end - n;                     // the intervals reach round to site `tail`
  std::pair<std::int64_t, std::int64_t> best{0, 0};
  for (auto [a, b] : gaps) {
    if (b < n) a = std::max(a, tail + 1);
    if (b - a + 1 > best.second) best = {a, b - a + 1};
  }
  return best;
}

/// The arc of each ring (its first site and length) that holds every site within `w` of one of the points, and
/// the whole of the innermost and outermost rings. A site on ring k (radius r_k) at angle d from a point at
/// radius r lies at least 2 sqrt(r r_k) sin(d/2) from it, and |r - r_k| across. The points are taken in order of
/// angle, so that each ring's windows mostly join the one before and few are kept.
inline std::pair<std::vector<std::int64_t>, std::vector<std::int64_t>> arcs_near(const RingSites& s,
                                                                                 std::span<const Vec<2>> points,
                                                                                 double w) {
  using Arc = std::pair<std::int64_t, std::int64_t>;
  const std::size_t n_rings = s.rings();
  std::vector<std::pair<double, double>> polar(points.size());  // angle, radius
  for (std::size_t i = 0; i < points.size(); ++i)
    polar[i] = {std::atan2(points[i].y(), points[i].x()), points[i].norm()};
  std::sort(polar.begin(), polar.end());
  std::vector<std::vector<Arc>> near(n_rings);
  std::vector<Arc> open(n_rings, Arc{0, -1});  // per ring: the window growing now (empty: hi < lo)
  std::vector<std::uint8_t> whole(n_rings, 0);
  whole.front() = whole.back() = 1;
  for (const auto& [phi, r] : polar) {
    const auto k_lo = static_cast<std::int64_t>(std::floor((r - w - s.radius.front()) / s.spacing)) - 1;
    for (std::int64_t ki = std::max<std::int64_t>(k_lo, 1);
         ki < static_cast<std::int64_t>(n_rings) - 1 && s.radius[static_cast<std::size_t>(ki)] <= r + w; ++ki) {
      const auto k = static_cast<std::size_t>(ki);
      if (whole[k] || std::abs(r - s.radius[k]) > w) continue;
      const double sine = w / (2.0 * std::sqrt(r * s.radius[k]));
      if (!(sine < 1.0)) {
        whole[k] = 1;
        continue;
      }
      const double d = 2.0 * std::asin(sine) + 1e-9;
      const Arc arc{static_cast<std::int64_t>(std::ceil((phi - d - s.phase[k]) / s.step(k) - 0.5)) - 1,
                    static_cast<std::int64_t>(std::floor((phi + d - s.phase[k]) / s.step(k) - 0.5)) + 1};
      Arc& now = open[k];
      if (now.second >= now.first && arc.first <= now.second + 1 && arc.second >= now.first - 1) {
        now = {std::min(now.first, arc.first), std::max(now.second, arc.second)};  // joins the window
        continue;
      }
      if (now.second >= now.first) near[k].push_back(now);
      now = arc;
    }
  }
  std::vector<std::int64_t> first(n_rings, 0), count(n_rings, 0);
  for (std::size_t k = 0; k < n_rings; ++k) {
    const auto n = s.sites_on(k);
    if (open[k].second >= open[k].first) near[k].push_back(open[k]);
    for (auto& [lo, hi] : near[k]) {  // lo into [0, n); a window of a whole ring or more holds it all
      if (hi - lo + 1 >= n) whole[k] = 1;
      const std::int64_t shift = lo - ((lo % n) + n) % n;
      lo -= shift;
      hi -= shift;
    }
    if (whole[k]) {
      count[k] = n;
      continue;
    }
    if (near[k].empty()) continue;
    std::sort(near[k].begin(), near[k].end());
    const auto [gap_first, gap] = largest_gap(near[k], n);
    count[k] = n - gap;
    first[k] = gap == 0 ? 0 : (gap_first + gap) % n;
  }
  return {std::move(first), std::move(count)};
}

/// Whether each site lies within `w` of one of the points.
inline std::vector<std::uint8_t> sites_near(std::span<const Vec<2>> sites, const std::vector<Vec<2>>& points,
                                            double w) {
  std::vector<std::uint8_t> near(sites.size(), 0);
  if (points.empty()) return near;
  neighbors::CellList<2> lookup;
  lookup.build(points, w);
  run_parallel(sites.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c)
      lookup.for_each_within(sites[c], w, [&](std::uint32_t j) {
        if ((points[j] - sites[c]).squaredNorm() <= w * w) near[c] = 1;
      });
  });
  return near;
}
}  // namespace detail

/// Builds each cell by clipping a square of half-width 1.5 Delta (`edge_extent` on the innermost and outermost
/// rings, whose cells take in everything beyond them) with the bisectors of its two neighbours on its ring and
/// the three nearest on each ring beside. Any other site lies at least 1.8 Delta off (two along its own ring:
/// 2 Delta; two along a ring beside: 1.5 steps along and Delta across; two rings away: 2 Delta), so it cannot
/// cut a cell that reaches less than 0.9 Delta; a cell reaching further is built again among two rings and
/// three sites each way, and refused if it still reaches beyond 1.2 Delta. Only the sites held have cells;
/// `wanted`, where not empty, marks by slot those whose cells are built.
inline void RingSites::build_cells(double edge_extent, const std::vector<std::uint8_t>& wanted) {
  const std::size_t n_rings = rings(), n_slots = n_held();
  const auto n_threads = static_cast<std::size_t>(max_threads());
  std::vector<std::vector<Vec<2>>> verts(n_threads);  // per thread, its contiguous run of cells in order
  cell_start.assign(n_slots + 1, 0);
  bounds.resize(n_slots);
  run_parallel(n_slots, [&](int t, std::size_t begin, std::size_t end) {
    auto& own = verts[static_cast<std::size_t>(t)];
    own.clear();
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t c = site_in(i), k = ring_of(c);
      const bool edge = k == 0 || k + 1 == n_rings;
      if (!edge && !wanted.empty() && !wanted[i]) {
        cell_start[i + 1] = 0;
        bounds[i] = {Vec<2>::Constant(std::numeric_limits<double>::infinity()),
                     Vec<2>::Constant(-std::numeric_limits<double>::infinity())};
        continue;
      }
      const double half = edge ? std::max(edge_extent, 3.0 * spacing) : 1.5 * spacing;
      geometry::ConvexPolygon cell = detail::voronoi_cell(*this, c, k, half, 1, 1);
      if (!edge && geometry::max_radius(cell, Vec<2>::Zero()) >= 0.89 * spacing) {
        cell = detail::voronoi_cell(*this, c, k, 3.0 * spacing, 2, 3);
        if (geometry::max_radius(cell, Vec<2>::Zero()) > 1.2 * spacing)
          throw NumericalError("rings lattice: the cell of site " + std::to_string(c) + " on the ring at r = " +
                               std::to_string(radius[k]) + " reaches beyond 1.2 Delta; too few sites on the ring?");
      }
      cell_start[i + 1] = static_cast<std::size_t>(cell.n);
      bounds[i] = geometry::bounds(cell);
      for (int v = 0; v < cell.n; ++v) own.push_back(cell[v]);
    }
  });
  for (std::size_t i = 0; i < n_slots; ++i) cell_start[i + 1] += cell_start[i];
  vertices.clear();
  vertices.reserve(cell_start[n_slots]);
  for (const auto& own : verts) vertices.insert(vertices.end(), own.begin(), own.end());
  reach_lo.assign(n_rings, std::numeric_limits<double>::max());
  reach_hi.assign(n_rings, 0.0);
  reach_angle.assign(n_rings, 0.0);
  for (std::size_t i = 0; i < n_slots; ++i) {
    if (cell_start[i + 1] == cell_start[i]) continue;  // not built
    const std::size_t c = site_in(i), k = ring_of(c);
    const auto e = detail::polar_extent(cell(c, Vec<2>::Zero()), Vec<2>::Zero(), xy[i]);
    reach_lo[k] = std::min(reach_lo[k], e.r_lo);
    reach_hi[k] = std::max(reach_hi[k], e.r_hi);
    reach_angle[k] = std::max({reach_angle[k], -e.angle_lo, e.angle_hi});
  }
}

template <class F>
void RingSites::for_each_candidate(const geometry::ConvexPolygon& p, const Vec<2>& xo, F&& f) const {
  const Vec<2> towards = xo.squaredNorm() > 0.0 ? xo : Vec<2>(1.0, 0.0);
  const auto e = detail::polar_extent(p, xo, towards);
  const double phi_o = std::atan2(towards.y(), towards.x());
  const double margin = 1e-9 * spacing;
  const auto n_rings = static_cast<std::int64_t>(rings());
  const auto ring_at = [&](double r) { return static_cast<std::int64_t>(ring_nearest(r)); };
  for (std::int64_t ki = std::max<std::int64_t>(0, ring_at(e.r_lo) - 2);
       ki <= std::min(n_rings - 1, ring_at(e.r_hi) + 2); ++ki) {
    const auto k = static_cast<std::size_t>(ki);
    if (reach_lo[k] > e.r_hi + margin || reach_hi[k] < e.r_lo - margin) continue;
    const auto n = sites_on(k);
    const double wide = reach_angle[k] + 1e-9;
    const double lo = phi_o + e.angle_lo - wide, hi = phi_o + e.angle_hi + wide;
    if (hi - lo >= 2.0 * std::numbers::pi - step(k)) {
      for (std::int64_t j = 0; j < n; ++j) f(offset[k] + static_cast<std::size_t>(j));
      continue;
    }
    // sites whose angle phase + (j + 1/2) step lies in [lo, hi]
    const auto j_lo = static_cast<std::int64_t>(std::ceil((lo - phase[k]) / step(k) - 0.5));
    const auto j_hi = static_cast<std::int64_t>(std::floor((hi - phase[k]) / step(k) - 0.5));
    for (std::int64_t j = j_lo; j <= j_hi; ++j) f(offset[k] + static_cast<std::size_t>(((j % n) + n) % n));
  }
}

/// The orbit-following lattice: rings of width Delta from r_in outwards (to r_out, or without end).
struct Rings {
  static constexpr int dim = 2;
  /// Every site owns a cell of its own (no shape moved from site to site): the remap asks the sites for their
  /// cells and candidates (RingSites) instead of an index range.
  static constexpr bool per_site_cells = true;
  /// Runs on many ranks: every rank lays out the whole gas's rings, turned by phases summed over the ranks, and
  /// builds the cells its old cells meet (`following`).
  static constexpr bool remaps_on_ranks = true;
  double spacing = 0.0;
  double r_in = 0.0;                                       ///< the innermost ring's inner edge
  double r_out = std::numeric_limits<double>::infinity();  ///< the outermost ring's outer edge (infinite: none)

  void validate() const {
    require(spacing > 0.0, "rings lattice: the spacing Delta must be positive");
    require(r_in >= spacing, "rings lattice: the inner edge must lie at least Delta from the centre (got r_in = " +
                                 std::to_string(r_in) + ", Delta = " + std::to_string(spacing) + ")");
    require(r_out > r_in + spacing * (1.0 - 1e-9), "rings lattice: need at least one ring between r_in and r_out");
  }
  /// How many rings fit between r_in and r_out (rounded; the largest int64 without an outer edge).
  std::int64_t ring_count() const {
    if (!std::isfinite(r_out)) return std::numeric_limits<std::int64_t>::max() / 2;
    return std::max<std::int64_t>(1, std::llround((r_out - r_in) / spacing));
  }
  double radius(std::int64_t i) const { return r_in + (static_cast<double>(i) + 0.5) * spacing; }
  std::int64_t sites_on(std::int64_t i) const {
    return std::max<std::int64_t>(3, std::llround(2.0 * std::numbers::pi * radius(i) / spacing));
  }
  /// The ring whose band holds radius r (not clamped).
  std::int64_t ring_at(double r) const { return static_cast<std::int64_t>(std::floor((r - r_in) / spacing)); }

  /// Rings first..last (clamped to the lattice), unturned: the sites a scene starts on.
  RingSites sites(std::int64_t first, std::int64_t last) const {
    RingSites s = rings_between(first, last);
    s.hold_all();
    s.place();
    return s;
  }
  /// Rings first..last (clamped to the lattice), unturned, no site held yet.
  RingSites rings_between(std::int64_t first, std::int64_t last) const {
    validate();
    first = std::max<std::int64_t>(first, 0);
    last = std::min(last, ring_count() - 1);
    require(first <= last, "rings lattice: no ring in the range asked for");
    RingSites s;
    s.spacing = spacing;
    s.first_ring = first;
    for (std::int64_t i = first; i <= last; ++i) {
      s.radius.push_back(radius(i));
      s.phase.push_back(0.0);
      s.offset.push_back(s.offset.back() + static_cast<std::size_t>(sites_on(i)));
    }
    s.n_cells = s.offset.back();
    return s;
  }
  /// The sites gas at x (masses m) is remapped onto: the rings whose bands hold gas, from the innermost to the
  /// outermost (whose cells take in the gas beyond them), each
  /// turned to its gas's mass-weighted mean phase (the circular mean of N_i phi over the gas in its band,
  /// which is where the ring's sites have moved to modulo a site: Omega_i T for gas on circular orbits, with
  /// the integrator's phase error included); a ring without gas keeps phase 0. `reach`: how far an old cell
  /// may reach beyond its particle (the edge rings' cells take in everything that far out).
  /// On many ranks (`part`) the rings and phases are the whole gas's, alike on every rank: the extent is reduced
  /// over the ranks and each rank adds its own particles' phases. A rank holds only the sites near the old cells
  /// it builds (`part.cells`), an arc of each ring (and the edge rings whole), and builds the cells those old cells
  /// may meet, and the edge rings'.
  RingSites following(std::span<const Vec<2>> x, std::span<const double> m, double reach,
                      const regularize::RankPart& part = {}) const {
    require(!x.empty(), "rings lattice: no gas to follow");
    double g_lo = std::numeric_limits<double>::max(), g_hi = 0.0;
    for (const auto& xa : x) {
      g_lo = std::min(g_lo, xa.norm());
      g_hi = std::max(g_hi, xa.norm());
    }
    g_lo = part.min(g_lo);
    g_hi = part.max(g_hi);
    RingSites s = rings_between(ring_at(g_lo), ring_at(g_hi));
    turn_to_gas(s, x.first(std::min(part.own, x.size())), m, part);
    std::vector<std::uint8_t> wanted;
    if (part.on_ranks()) {
      std::vector<Vec<2>> near(part.cells.size());
      for (std::size_t i = 0; i < near.size(); ++i) near[i] = x[part.cells[i]];
      const double w = reach + 1.5 * spacing;  // an inner cell reaches at most 1.2 Delta
      auto [first, count] = detail::arcs_near(s, near, w);
      s.hold(std::move(first), std::move(count));
      s.place();
      wanted = detail::sites_near(s.xy, near, w);
    } else {
      s.hold_all();
      s.place();
    }
    const double beyond = std::max(0.0, s.radius.front() - g_lo) + std::max(0.0, g_hi - s.radius.back());
    s.build_cells(beyond + reach + 3.0 * spacing, wanted);
    return s;
  }

 private:
  /// Sets each ring's phase from the gas in its band: the circular mean of N_i phi, mass-weighted, over the
  /// particles x (masses m), summed over the ranks where `part` says so.
  void turn_to_gas(RingSites& s, std::span<const Vec<2>> x, std::span<const double> m,
                   const regularize::RankPart& part) const {
    std::vector<double> sum(2 * s.rings(), 0.0);  // per ring: the real and imaginary parts
    for (std::size_t a = 0; a < x.size(); ++a) {
      const std::int64_t k = ring_at(x[a].norm()) - s.first_ring;
      if (k < 0 || k >= static_cast<std::int64_t>(s.rings())) continue;
      const auto kk = static_cast<std::size_t>(k);
      const auto z = m[a] * std::polar(1.0, static_cast<double>(s.sites_on(kk)) * std::atan2(x[a].y(), x[a].x()));
      sum[2 * kk] += z.real();
      sum[2 * kk + 1] += z.imag();
    }
    if (part.sum_over_ranks) part.sum_over_ranks(sum);
    for (std::size_t k = 0; k < s.rings(); ++k) {
      const std::complex<double> z(sum[2 * k], sum[2 * k + 1]);
      if (std::abs(z) > 0.0) s.phase[k] = (std::arg(z) - std::numbers::pi) / static_cast<double>(s.sites_on(k));
    }
  }
};

}  // namespace rsph::lattice
