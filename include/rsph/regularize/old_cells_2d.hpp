#pragma once
// The old cells of a 2D remap: each particle's Voronoi polygon, closed by the region, and its overlaps on the
// lattice's cells (rectangles in one pass over the cell's edges, other shapes clipped by each candidate; a
// part beyond a wall shared among the sites inside).
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/voronoi.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/region.hpp"

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace rsph::regularize::detail {

/// Cells that are not rectangles do not tile a box with walls: `part`, an old cell's overlap with the
/// lattice cell idx beyond a wall (relative to xo), goes to the nearest sites inside among idx's
/// neighbours, each taking the piece nearer to it than to the others, just as the old cells, clipped to
/// the box, are the Voronoi cells of the sites inside. A lattice set then maps onto itself at walls too.
/// Calls f(index inside, piece) for each; a box one row wide (no site inside next to it) gives the whole
/// part to idx, whose flat index is clamped.
template <class Lattice, class F>
void share_beyond_wall(const Lattice& lattice, const CellGrid<2>& grid, const Box<2>& box,
                       std::array<std::int64_t, 2> idx, const geometry::ConvexPolygon& part, const Vec<2>& xo, F&& f) {
  std::array<std::array<std::int64_t, 2>, 8> nbs;
  std::array<Vec<2>, 8> at;
  std::size_t n = 0;
  for (std::int64_t dj = -1; dj <= 1; ++dj)
    for (std::int64_t di = -1; di <= 1; ++di) {
      const std::array<std::int64_t, 2> nb{idx[0] + di, idx[1] + dj};
      if ((di == 0 && dj == 0) || beyond_wall(grid, box, nb)) continue;
      nbs[n] = nb;
      at[n++] = lattice.site(box, nb) - xo;
    }
  if (n == 0) {
    f(idx, part);
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    geometry::ConvexPolygon piece = part;
    for (std::size_t m = 0; m < n && piece.n >= 3; ++m)
      if (m != k)  // nearer to at[k] than to at[m]
        geometry::clip_halfplane(piece, at[m] - at[k], 0.5 * (at[m].squaredNorm() - at[k].squaredNorm()));
    f(nbs[k], piece);
  }
}

/// What the overlaps need of a lattice's cells beyond their sites: nothing for rectangles (the grid lines),
/// the sides of the cell shape for the others.
struct NoSides {};
template <class Lattice>
using CellSides = std::conditional_t<Lattice::rectangular_cells, NoSides, geometry::Sides>;

template <class Lattice>
CellSides<Lattice> cell_sides(const Lattice& lattice) {
  if constexpr (Lattice::rectangular_cells) {
    return {};
  } else {
    static_assert(
        requires { lattice.cell_shape(); },
        "a lattice whose cells are not rectangles needs `geometry::ConvexPolygon cell_shape() const`: the "
        "cell around its site, every cell being that shape moved to its site");
    const geometry::ConvexPolygon shape = lattice.cell_shape();
    require(shape.n >= 3 && shape.n <= geometry::Sides::capacity,
            "regularization: a lattice's cell shape needs 3 to 32 sides");
    return geometry::sides_of(shape);
  }
}

/// The builder's visitor behind for_each_old_cell: each old cell's overlaps on the lattice cells of `grid`,
/// listed in per-thread scratch and handed to the action.
template <class Lattice, bool E, class Region, class Action>
struct OldCellVisitor {
  const ParticleSet<2, E>* p;
  const Lattice* lattice;
  const Box<2>* box;
  const CellGrid<2>* grid;
  const Region* region;
  Action* action;
  struct alignas(64) Scratch {  // per thread, a cache line apart
    std::vector<Overlap> overlaps;
    std::vector<double> lines, omegas;
    std::vector<std::int64_t> parts;
  };
  std::vector<Scratch> scratch;
  [[no_unique_address]] CellSides<Lattice> sides;

  std::int64_t axis_part(int k, std::int64_t i) const { return detail::axis_part(*grid, *box, k, i); }
  bool beyond_wall(std::array<std::int64_t, 2> idx) const { return detail::beyond_wall(*grid, *box, idx); }
  /// share_beyond_wall's pieces as (index inside, area); returns how many.
  using Share = std::pair<std::array<std::int64_t, 2>, double>;
  std::size_t share_beyond_wall(std::array<std::int64_t, 2> idx, const geometry::ConvexPolygon& part, const Vec<2>& xo,
                                std::array<Share, 8>& shares) const {
    std::size_t n = 0;
    detail::share_beyond_wall(*lattice, *grid, *box, idx, part, xo,
                              [&](std::array<std::int64_t, 2> nb, const geometry::ConvexPolygon& piece) {
                                shares[n++] = {nb, geometry::area(piece)};
                              });
    return n;
  }
  void restart() { action->restart(); }
  void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
    rsph::region::with_closed(*region, p->x[a], cell,
                              [&](const geometry::ConvexPolygon& closed) { add_cell(thread, a, closed); });
  }

  /// The overlaps listed so far for one cell: how many, and V_o their sum in their order.
  struct Listed {
    std::size_t n = 0;
    double V_o = 0.0;
  };

  void add_cell(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
    auto& own = scratch[static_cast<std::size_t>(thread)];
    const Vec<2> xo = p->x[a];
    geometry::Bounds cb;
    const double cell_area = geometry::area_and_bounds(cell, cb);
    const auto r = lattice->cells_touching(*box, Vec<2>(cb.lo + xo), Vec<2>(cb.hi + xo));
    Listed listed;  // own.overlaps is scratch that keeps its size
    if constexpr (Lattice::rectangular_cells)
      list_on_rectangles(own, a, cell, cell_area, r, xo, listed);
    else
      list_on_shapes(own, a, cell, cell_area, r, xo, listed);
    (*action)(thread, a, cell, std::span<const Overlap>(own.overlaps.data(), listed.n), listed.V_o, cell_area);
  }

  static NumericalError beyond_grid(std::size_t a) {
    return NumericalError("regularization: an old cell reaches beyond the lattice grid (particle " + std::to_string(a) +
                          ")");
  }

  [[gnu::always_inline]] inline void add_overlap(Scratch& own, Listed& l, std::size_t a, std::int64_t col_part,
                                                 std::int64_t row_part, double omega) const {
    if ((col_part | row_part) < 0) throw beyond_grid(a);
    grown(own.overlaps, l.n + 1)[l.n] = {static_cast<std::size_t>(col_part + row_part), omega};
    ++l.n;
    l.V_o += omega;
  }

  /// Rectangular lattice cells: all overlaps in one pass over the cell's edges; round-off crumbs in cells
  /// the old cell only touches (|omega| ~ 1e-16 of its area) are dropped, and V_o = sum omega keeps mass
  /// exact.
  [[gnu::always_inline]] inline void list_on_rectangles(Scratch& own, std::size_t a,
                                                        const geometry::ConvexPolygon& cell, double cell_area,
                                                        const IndexRange<2>& r, const Vec<2>& xo, Listed& l) const {
    const auto n_i = static_cast<int>(r.hi[0] - r.lo[0] + 1), n_j = static_cast<int>(r.hi[1] - r.lo[1] + 1);
    double* xs = grown(own.lines, static_cast<std::size_t>(n_i + n_j + 2));
    for (int c = 0; c <= n_i; ++c) xs[c] = lattice->line(*box, 0, r.lo[0] + c, xo[0]);
    double* ys = xs + n_i + 1;
    for (int c = 0; c <= n_j; ++c) ys[c] = lattice->line(*box, 1, r.lo[1] + c, xo[1]);
    double* omegas = grown(own.omegas, static_cast<std::size_t>(n_i) * static_cast<std::size_t>(n_j));
    geometry::grid_overlaps(cell, xs, n_i, ys, n_j, omegas);
    // The flat index is a column part plus a row part: each is wrapped (periodic) or clamped (walls)
    // once per cell instead of once per overlap.
    std::int64_t* cols = grown(own.parts, static_cast<std::size_t>(n_i + n_j));
    std::int64_t* rows = cols + n_i;
    for (int i = 0; i < n_i; ++i) cols[i] = axis_part(0, r.lo[0] + i);
    for (int j = 0; j < n_j; ++j) rows[j] = axis_part(1, r.lo[1] + j);
    // Each overlap is written and kept by advancing the count, without a branch (whether a cell of the grid
    // holds more than a crumb is a coin toss); so is the check that a kept one lies inside the grid.
    const double crumb = 1e-13 * cell_area;
    auto* out = grown(own.overlaps, static_cast<std::size_t>(n_i) * static_cast<std::size_t>(n_j));
    std::int64_t outside = 0;
    std::size_t n_ov = l.n;
    double V_o = l.V_o;
    for (int i = 0; i < n_i; ++i)
      for (int j = 0; j < n_j; ++j) {
        const double omega = omegas[i * n_j + j];
        const bool kept = omega > crumb;
        out[n_ov] = {static_cast<std::size_t>(cols[i] + rows[j]), omega};
        outside |= kept ? cols[i] | rows[j] : 0;
        V_o += kept ? omega : 0.0;
        n_ov += kept;
      }
    if (outside < 0) throw beyond_grid(a);
    l.n = n_ov;
    l.V_o = V_o;
  }

  /// Cells of another shape: every lattice cell is the lattice's shape moved to its site, so all have the
  /// same side normals; the old cell's extent along each, taken once, tells for each candidate which sides
  /// cut the old cell and whether one keeps them apart, before any clipping (many in the rectangular index
  /// range are).
  [[gnu::always_inline]] inline void list_on_shapes(Scratch& own, std::size_t a, const geometry::ConvexPolygon& cell,
                                                    double cell_area, const IndexRange<2>& r, const Vec<2>& xo,
                                                    Listed& l) const {
    std::array<double, geometry::Sides::capacity> reach_lo, reach_hi;
    for (int k = 0; k < sides.n; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      reach_lo[kk] = std::numeric_limits<double>::max();
      reach_hi[kk] = std::numeric_limits<double>::lowest();
      for (int v = 0; v < cell.n; ++v) {
        const double d = sides.normal[kk].dot(cell[v]);
        reach_lo[kk] = std::min(reach_lo[kk], d);
        reach_hi[kk] = std::max(reach_hi[kk], d);
      }
    }
    for (std::int64_t j = r.lo[1]; j <= r.hi[1]; ++j)
      for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i) {
        const Vec<2> site = lattice->site(*box, {i, j}) - xo;
        std::uint32_t cutting = 0;
        bool apart = false;
        for (int k = 0; k < sides.n; ++k) {
          const auto kk = static_cast<std::size_t>(k);
          const double offset = sides.offset[kk] + sides.normal[kk].dot(site);
          apart |= reach_lo[kk] >= offset;
          cutting |= static_cast<std::uint32_t>(reach_hi[kk] > offset) << k;
        }
        if (apart) continue;
        if (beyond_wall({i, j})) {
          std::array<Share, 8> shares;
          const std::size_t n_shares = share_beyond_wall(
              {i, j},
              geometry::with_part_within_sides(
                  cell, sides, cutting, [&](std::size_t k) { return sides.offset[k] + sides.normal[k].dot(site); },
                  [](const geometry::ConvexPolygon& part) { return part; }),
              xo, shares);
          for (std::size_t k = 0; k < n_shares; ++k)
            if (shares[k].second > 0.0)
              add_overlap(own, l, a, axis_part(0, shares[k].first[0]), axis_part(1, shares[k].first[1]),
                          shares[k].second);
          continue;
        }
        const double omega = cutting == 0 ? cell_area : geometry::area_within_sides(cell, sides, site, cutting);
        if (omega > 0.0) add_overlap(own, l, a, axis_part(0, i), axis_part(1, j), omega);
      }
  }
};

/// The visitor for_each_old_cell (remap.hpp) hands the builder in 2D.
template <class Lattice, bool E, class Region, class Action>
OldCellVisitor<Lattice, E, Region, Action> old_cell_visitor(const ParticleSet<2, E>& p, const Box<2>& box,
                                                            const Lattice& lattice, const CellGrid<2>& grid,
                                                            const Region& region, Action& action) {
  using Visitor = OldCellVisitor<Lattice, E, Region, Action>;
  return Visitor{&p,
                 &lattice,
                 &box,
                 &grid,
                 &region,
                 &action,
                 std::vector<typename Visitor::Scratch>(static_cast<std::size_t>(geometry::builder_threads())),
                 cell_sides(lattice)};
}

}  // namespace rsph::regularize::detail
