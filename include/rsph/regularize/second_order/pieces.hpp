#pragma once
// The pieces of the old cells on the lattice, for the second-order remap (remap_second.hpp): listed per thread
// in 1D and 2D (3D cells list theirs as they are built, cells3d.hpp), renumbered compactly where the sums go
// sparse, and each new cell's bounds for the limiter.
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/regularize/remap.hpp"
#include "rsph/regularize/second_order/workspace.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace rsph::regularize::second_order {

/// Calls f(flat index, moments) for every piece of the 2D old cell `cell` (relative to its particle at xo)
/// on the lattice cells of `grid`. Rectangular cells: the cell is cut column by column, each column row by
/// row; other shapes: clipped by each candidate cell, and a part beyond a wall shared out as in the
/// first-order remap. Round-off crumbs below 1e-13 of the cell are dropped, as there.
template <class Lattice, class F>
void for_each_piece(const Lattice& lattice, const Box<2>& box, const detail::CellGrid<2>& grid, std::size_t a,
                    const geometry::ConvexPolygon& cell, const Vec<2>& xo, F&& f) {
  geometry::Bounds b;
  const double crumb = 1e-13 * geometry::area_and_bounds(cell, b);
  const auto r = lattice.cells_touching(box, Vec<2>(b.lo + xo), Vec<2>(b.hi + xo));
  auto emit = [&](std::array<std::int64_t, 2> idx, const geometry::ConvexPolygon& piece) {
    if (piece.n < 3) return;
    const auto m = geometry::moments(piece);
    if (!(m.area > crumb)) return;
    const std::int64_t col = detail::axis_part(grid, box, 0, idx[0]), row = detail::axis_part(grid, box, 1, idx[1]);
    if ((col | row) < 0)
      throw NumericalError("regularization: an old cell reaches beyond the lattice grid (particle " +
                           std::to_string(a) + ")");
    f(static_cast<std::size_t>(col + row), piece_moments(m));
  };
  if constexpr (Lattice::rectangular_cells) {
    // ping-pong buffers: the rest of the cell right of the column lines, the column, the rest of the column
    // above the row lines, the piece; nothing is copied
    std::array<geometry::ConvexPolygon, 6> buf;
    const geometry::ConvexPolygon* rest = &cell;
    for (std::int64_t i = r.lo[0], rb = 0; i <= r.hi[0] && rest->n >= 3; ++i) {
      const geometry::ConvexPolygon* column = rest;
      if (i < r.hi[0]) {
        geometry::split_at(*rest, 0, lattice.line(box, 0, i + 1, xo[0]), buf[2], buf[static_cast<std::size_t>(rb)]);
        column = &buf[2];
        rest = &buf[static_cast<std::size_t>(rb)];
        rb ^= 1;
      }
      const geometry::ConvexPolygon* row_rest = column;
      for (std::int64_t j = r.lo[1], cb = 4; j <= r.hi[1] && row_rest->n >= 3; ++j) {
        const geometry::ConvexPolygon* piece = row_rest;
        if (j < r.hi[1]) {
          geometry::split_at(*row_rest, 1, lattice.line(box, 1, j + 1, xo[1]), buf[3],
                             buf[static_cast<std::size_t>(cb)]);
          piece = &buf[3];
          row_rest = &buf[static_cast<std::size_t>(cb)];
          cb ^= 1;
        }
        emit({i, j}, *piece);
      }
    }
  } else {
    for (std::int64_t j = r.lo[1]; j <= r.hi[1]; ++j)
      for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i) {
        const geometry::ConvexPolygon part = geometry::clip_convex(cell, lattice.cell(box, {i, j}, xo));
        if (part.n < 3) continue;
        if (detail::beyond_wall(grid, box, {i, j}))
          detail::share_beyond_wall(lattice, grid, box, {i, j}, part, xo, emit);
        else
          emit({i, j}, part);
      }
  }
}

/// Per-site cells (lattice::Rings): f(site, moments) for every piece of the old cell in the cells the sites'
/// lookup names, crumbs dropped as above.
template <class Lattice, SiteCells Sites, class F>
void for_each_piece(const Lattice&, const Box<2>&, const Sites& sites, std::size_t, const geometry::ConvexPolygon& cell,
                    const Vec<2>& xo, F&& f) {
  detail::for_each_site_piece(
      sites, cell, xo, 1e-13 * geometry::area(cell),
      [&](std::size_t c, const geometry::ConvexPolygon& piece) { f(c, piece_moments(geometry::moments(piece))); });
}

/// Lists every old cell's pieces (kept per thread for the hand-outs) in 1D and 2D; 3D cells list theirs as
/// they are built (cells3d.hpp).
template <class Lattice, int D, bool E, class Grid>
void list_pieces(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, const RemapParams& params,
                 const Grid& grid, Workspace<D>& ws) {
  const auto n_threads = static_cast<std::size_t>(max_threads());
  ws.threads.resize(n_threads);
  ws.piece_thread.resize(p.n_real);
  ws.piece_first.resize(p.n_real);
  ws.piece_count.resize(p.n_real);
  auto listed = [&](int t, std::size_t a, std::size_t first) {
    const auto& own = ws.threads[static_cast<std::size_t>(t)].pieces;
    ws.piece_thread[a] = static_cast<std::uint32_t>(t);
    ws.piece_first[a] = static_cast<std::uint32_t>(first);
    ws.piece_count[a] = static_cast<std::uint32_t>(own.flat.size() - first);
  };
  for (auto& t : ws.threads) t.pieces.clear();
  if constexpr (D == 1) {
    auto& own = ws.threads[0].pieces;
    detail::for_each_old_interval(p, box, lattice, params, grid,
                                  [&](std::size_t a, double left, double, const auto& overlaps, double) {
                                    const std::size_t first = own.flat.size();
                                    double at = left - p.x[a][0];  // the overlaps come in order from the left end
                                    for (const auto& [c, omega] : overlaps) {
                                      own.flat.push_back(c);
                                      own.moments.push_back(interval_moments(at, at + omega));
                                      at += omega;
                                    }
                                    listed(0, a, first);
                                  });
  } else {
    run_parallel(p.n_real, [&](int t, std::size_t begin, std::size_t end) {
      auto& own = ws.threads[static_cast<std::size_t>(t)].pieces;
      for (std::size_t a = begin; a < end; ++a) {
        const std::size_t first = own.flat.size();
        if (ws.cells.built(a))
          for_each_piece(lattice, box, grid, a, ws.cells.polygon(a), p.x[a],
                         [&](std::size_t c, const PieceMoments<2>& pm) {
                           own.flat.push_back(c);
                           own.moments.push_back(pm);
                         });
        listed(t, a, first);
      }
    });
  }
}

/// Each new cell's bounds: the union of the ranges of the old cells with a piece in it, into ws.bounds[0] (a
/// union of ranges, the same in any order).
template <int D>
void gather_bounds(std::size_t n_old, std::size_t n_cells, Workspace<D>& ws) {
  const auto n_threads = static_cast<std::size_t>(max_threads());
  ws.bounds.resize(n_threads);
  run_parallel(n_threads, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) ws.bounds[t].assign(n_cells, FieldRanges<D>{});
  });
  run_parallel(n_old, [&](int t, std::size_t begin, std::size_t end) {
    auto& own = ws.bounds[static_cast<std::size_t>(t)];
    for (std::size_t a = begin; a < end; ++a) {
      const auto& listed = ws.threads[ws.piece_thread[a]].pieces;
      for (std::size_t k = ws.piece_first[a], last = k + ws.piece_count[a]; k < last; ++k)
        own[listed.flat[k]].add(ws.recon[a].range);
    }
  });
  run_parallel(n_cells, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = 1; t < ws.bounds.size(); ++t)
      for (std::size_t c = begin; c < end; ++c) ws.bounds[0][c].add(ws.bounds[t][c]);
  });
}

/// Renumbers the listed pieces' cells compactly: returns the grid cells that receive a piece, ascending, and
/// makes every piece's cell its place in that list (so that the hand-out sums densely over them alone).
template <int D>
std::vector<std::size_t> compact_piece_cells(Workspace<D>& ws) {
  std::vector<std::size_t> cells;
  for (const auto& t : ws.threads) cells.insert(cells.end(), t.pieces.flat.begin(), t.pieces.flat.end());
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  run_parallel(ws.threads.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t)
      for (auto& f : ws.threads[t].pieces.flat)
        f = static_cast<std::size_t>(std::lower_bound(cells.begin(), cells.end(), f) - cells.begin());
  });
  return cells;
}

}  // namespace rsph::regularize::second_order
