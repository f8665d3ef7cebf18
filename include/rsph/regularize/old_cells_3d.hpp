#pragma once
// The old cells of a 3D remap: each particle's Voronoi polyhedron split across the cells of a lattice of
// rectangular cells (lattice::Cubic), its overlaps Omega_n^o (flat index, volume) handed to the remap's
// action, as old_cells_2d.hpp hands the polygons' overlaps in 2D.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/polyhedron.hpp"
#include "rsph/geometry/sites.hpp"
#include "rsph/regularize/cell_grid.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <tuple>
#include <vector>

namespace rsph::regularize::detail {

/// Scratch of for_each_lattice_piece, one per thread.
struct LatticePieceScratch {
  std::array<std::vector<double>, 3> planes;
  std::array<std::vector<std::int64_t>, 3> parts;
  geometry::GridPieceScratch pieces;
};

/// Measures the pieces of the old cell of particle a (relative to its position xo) in the lattice cells it spans
/// (polyhedron.hpp's for_each_grid_measure: Measure is geometry::VolumeMeasure or geometry::MomentMeasure) and
/// calls f(flat, measure) for each: flat is the piece's lattice cell in `grid`, negative where that lies outside
/// the grid (a caller keeping the piece refuses it).
template <class Measure, class Lattice, class F>
void for_each_lattice_piece(const Lattice& lattice, const Box<3>& box, const CellGrid<3>& grid, const Vec<3>& xo,
                            const geometry::ConvexPolyhedron& cell, LatticePieceScratch& scratch, F&& f) {
  static_assert(Lattice::rectangular_cells,
                "a 3D remap needs a lattice of rectangular cells (`line(box, axis, index, origin)`, lattice::Cubic)");
  Vec<3> lo, hi;
  for (int k = 0; k < 3; ++k) std::tie(lo[k], hi[k]) = geometry::extent(cell, k);
  const auto r = lattice.cells_touching(box, Vec<3>(lo + xo), Vec<3>(hi + xo));
  std::array<const double*, 3> planes;
  std::array<const std::int64_t*, 3> parts;
  std::array<int, 3> n;
  for (int k = 0; k < 3; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    n[kk] = static_cast<int>(r.hi[kk] - r.lo[kk] + 1);
    double* at = grown(scratch.planes[kk], static_cast<std::size_t>(n[kk]) + 1);
    std::int64_t* part = grown(scratch.parts[kk], static_cast<std::size_t>(n[kk]));
    for (int c = 0; c <= n[kk]; ++c) at[c] = lattice.line(box, k, r.lo[kk] + c, xo[k]);
    for (int c = 0; c < n[kk]; ++c) part[c] = axis_part(grid, box, k, r.lo[kk] + c);
    planes[kk] = at;
    parts[kk] = part;
  }
  geometry::for_each_grid_measure<Measure>(
      cell, planes, n, scratch.pieces, [&](std::array<int, 3> idx, const typename Measure::type& piece) {
        const std::int64_t f0 = parts[0][idx[0]], f1 = parts[1][idx[1]], f2 = parts[2][idx[2]];
        f((f0 | f1 | f2) < 0 ? std::int64_t{-1} : f0 + f1 + f2, piece);
      });
}

inline NumericalError beyond_grid_3d(std::size_t a) {
  return NumericalError("regularization: an old cell reaches beyond the lattice grid (particle " + std::to_string(a) +
                        ")");
}

/// Closes each old cell with the region, splits it by the lattice planes it spans and calls action(thread, a,
/// cell, overlaps, V_o, cell_volume), the overlaps on the cells of `grid` with their volumes, V_o their sum in their
/// order (which hands the particle's mass out exactly) and cell_volume the cell's own. Crumbs of a cell that only
/// touches a lattice cell (volume below 1e-13 of the cell's) are dropped.
template <class Lattice, bool E, class Region, class Action>
struct OldCellVisitor3 {
  const ParticleSet<3, E>* p;
  const Lattice* lattice;
  const Box<3>* box;
  const CellGrid<3>* grid;
  const Region* region;
  Action* action;
  struct alignas(64) Scratch {  // per thread, a cache line apart
    std::vector<Overlap> overlaps;
    LatticePieceScratch pieces;
    std::array<geometry::ConvexPolyhedron, 2> closed;  ///< the cell cut by the region
  };
  std::vector<Scratch> scratch;

  void restart() { action->restart(); }

  void operator()(int thread, std::size_t a, const geometry::ConvexPolyhedron& cell) {
    auto& own = scratch[static_cast<std::size_t>(thread)];
    if constexpr (Region::clips) {
      geometry::ConvexPolyhedron* closed = &own.closed[0];
      geometry::ConvexPolyhedron* spare = &own.closed[1];
      *closed = cell;
      region->clip(p->x[a], closed, spare);
      add_cell(own, thread, a, *closed);
    } else {
      add_cell(own, thread, a, cell);
    }
  }

  void add_cell(Scratch& own, int thread, std::size_t a, const geometry::ConvexPolyhedron& cell) {
    const double cell_volume = geometry::volume(cell);
    const double crumb = 1e-13 * cell_volume;
    std::size_t n_ov = 0;
    double V_o = 0.0;
    for_each_lattice_piece<geometry::VolumeMeasure>(
        *lattice, *box, *grid, p->x[a], cell, own.pieces, [&](std::int64_t flat, double omega) {
          if (!(omega > crumb)) return;
          if (flat < 0) throw beyond_grid_3d(a);
          grown(own.overlaps, n_ov + 1)[n_ov] = {static_cast<std::size_t>(flat), omega};
          ++n_ov;
          V_o += omega;
        });
    (*action)(thread, a, cell, std::span<const Overlap>(own.overlaps.data(), n_ov), V_o, cell_volume);
  }
};

/// The visitor for_each_old_cell (remap.hpp) hands the builder in 3D.
template <class Lattice, bool E, class Region, class Action>
OldCellVisitor3<Lattice, E, Region, Action> old_cell_visitor(const ParticleSet<3, E>& p, const Box<3>& box,
                                                             const Lattice& lattice, const CellGrid<3>& grid,
                                                             const Region& region, Action& action) {
  using Visitor = OldCellVisitor3<Lattice, E, Region, Action>;
  return Visitor{&p,
                 &lattice,
                 &box,
                 &grid,
                 &region,
                 &action,
                 std::vector<typename Visitor::Scratch>(static_cast<std::size_t>(geometry::builder_threads()))};
}

}  // namespace rsph::regularize::detail
