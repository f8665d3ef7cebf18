#pragma once
// The old cells of a 2D remap onto a lattice whose sites each own a cell of their own (lattice::Rings): each
// old Voronoi polygon clipped by the new cells the sites' lookup by ring and angle names, and the new
// particles on those sites. The sums, the hand-on and the emission are remap.hpp's.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/sites.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/region.hpp"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph::regularize::detail {

/// f(c, piece) for every piece of the old cell `cell` (relative to its particle at xo) in a new cell c of `sites`
/// whose area exceeds `crumb` (at most a small fraction of the cell's), in the order of the sites' lookup; the
/// pieces are relative to xo. The cell of the site nearest the particle is clipped first: once the pieces found
/// leave less than half a crumb of the old cell, no other cell can hold a crumb, so the lookup stops (or, where
/// that cell holds the whole old cell, as for gas on the circular orbits the rings follow, is not made). The
/// pieces and their order are those of the whole lookup, to the bit.
template <SiteCells Sites, class F>
void for_each_site_piece(const Sites& sites, const geometry::ConvexPolygon& cell, const Vec<2>& xo, double crumb,
                         F&& f) {
  const double cell_area = geometry::area(cell);
  const geometry::Bounds b = geometry::bounds(cell);
  geometry::ConvexPolygon piece, home_piece, scratch;
  // the piece in cell c into `out`, and its area; 0 (out empty) where they share no more than a crumb
  const auto piece_in = [&](std::size_t c, geometry::ConvexPolygon& out) {
    out.clear();
    if (!sites.box_meets(c, xo, b)) return 0.0;
    const geometry::ConvexPolygon window = sites.cell(c, xo);
    if (geometry::apart(cell, window, crumb / sites.diameter(c))) return 0.0;
    geometry::clip_convex(cell, window, out, scratch);
    if (const double a = out.n >= 3 ? geometry::area(out) : 0.0; a > crumb) return a;
    out.clear();
    return 0.0;
  };
  const std::size_t home = sites.nearest_site(xo);
  const double home_area = piece_in(home, home_piece);
  double left = cell_area - home_area;  // not yet found in a piece
  if (left < 0.5 * crumb) {
    if (home_area > 0.0) f(home, home_piece);
    return;
  }
  bool home_passed = false, done = false;
  sites.for_each_candidate(cell, xo, [&](std::size_t c) {
    if (done) return;
    if (c == home) {
      home_passed = true;
      if (home_area > 0.0) f(c, home_piece);
    } else if (left >= 0.5 * crumb) {
      if (const double a = piece_in(c, piece); a > 0.0) {
        left -= a;
        f(c, piece);
      }
    }
    done = home_passed && left < 0.5 * crumb;
  });
}

/// The builder's visitor for per-site cells: each old cell, closed by the region, with its overlaps listed in
/// per-thread scratch and handed to the action.
template <SiteCells Sites, bool E, class Region, class Action>
struct SiteCellVisitor {
  const ParticleSet<2, E>* p;
  const Sites* sites;
  const Region* region;
  Action* action;
  struct alignas(64) Scratch {
    std::vector<Overlap> overlaps;
  };
  std::vector<Scratch> scratch;

  void restart() { action->restart(); }
  void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
    rsph::region::with_closed(*region, p->x[a], cell,
                              [&](const geometry::ConvexPolygon& closed) { add_cell(thread, a, closed); });
  }
  void add_cell(int thread, std::size_t a, const geometry::ConvexPolygon& closed) {
    if (closed.n < 3) throw NumericalError("regularization: an old cell closed to nothing");
    auto& own = scratch[static_cast<std::size_t>(thread)].overlaps;
    own.clear();
    const double cell_area = geometry::area(closed);
    double V_o = 0.0;
    for_each_site_piece(*sites, closed, p->x[a], 1e-13 * cell_area,
                        [&](std::size_t c, const geometry::ConvexPolygon& piece) {
                          const double omega = geometry::area(piece);
                          own.emplace_back(c, omega);
                          V_o += omega;
                        });
    (*action)(thread, a, closed, std::span<const Overlap>(own), V_o, cell_area);
  }
};

/// The visitor for_each_old_cell (remap.hpp) hands the builder for per-site cells.
template <class Lattice, bool E, class Region, class Action, SiteCells Sites>
SiteCellVisitor<Sites, E, Region, Action> old_cell_visitor(const ParticleSet<2, E>& p, const Box<2>&, const Lattice&,
                                                           const Sites& sites, const Region& region, Action& action) {
  using Visitor = SiteCellVisitor<Sites, E, Region, Action>;
  return Visitor{&p, &sites, &region, &action,
                 std::vector<typename Visitor::Scratch>(static_cast<std::size_t>(geometry::builder_threads()))};
}

/// The new cells of a per-site lattice as the ranks name them (owner_sums.hpp): by their site's number, which
/// every rank gives alike (the sites are the whole set's on every rank).
template <SiteCells Sites>
struct SitesOnRanks {
  const Sites* sites;
  std::size_t size() const { return sites->n_cells; }
  Vec<2> site(std::size_t c) const { return sites->site(c); }
  /// f(g) for the sites within `layers` steps of neighbours of site c, each once, c left out.
  template <class F>
  void for_each_within(std::size_t c, int layers, F&& f) const {
    std::vector<std::size_t> seen{c};
    std::size_t from = 0;
    for (int layer = 0; layer < layers; ++layer) {
      const std::size_t to = seen.size();
      for (std::size_t i = from; i < to; ++i)
        sites->for_each_neighbour(seen[i], [&](std::size_t g) {
          if (std::find(seen.begin(), seen.end(), g) != seen.end()) return;
          seen.push_back(g);
          f(g);
        });
      from = to;
    }
  }
  std::int64_t whole_flat(std::size_t c) const { return static_cast<std::int64_t>(c); }
};

/// The new cells of a per-site lattice for the particles `p`: its sites placed for them (a rings lattice
/// follows their orbits) with the cells built out to where an old cell may reach; on many ranks (`part`), the
/// whole set's sites, with the cells this rank's old cells meet.
template <class Lattice, bool E>
auto site_cells(const ParticleSet<2, E>& p, const Box<2>& box, const Lattice& lattice, const RemapParams& params,
                const RankPart& part) {
  require(box.edge[0] == Edge::open && box.edge[1] == Edge::open,
          "regularization: a lattice of per-site cells (rings) needs a box open on both axes");
  const std::span<const Vec<2>> x(p.x.data(), p.n_real);
  const std::span<const double> m(p.m.data(), p.n_real);
  const double reach = params.closing_radius_in_h * part.max(max_smoothing_length(p)) * 1.1;
  if constexpr (requires { lattice.following(x, m, reach, part); })
    return lattice.following(x, m, reach, part);
  else
    return lattice.following(x, m, reach);
}

}  // namespace rsph::regularize::detail
