#pragma once
// The block of lattice cells a remap sums into: its index ranges, flat indices with periodic wrapping and
// wall clamping, and the candidate cells a particle set can reach. The same in every dimension.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

namespace rsph::regularize::detail {

/// An old cell's overlap with one new cell: (flat index of the new cell, Omega_n^o).
using Overlap = std::pair<std::size_t, double>;

inline std::int64_t wrap_index(std::int64_t i, std::int64_t period) {
  if (i >= 0 && i < period) return i;  // almost always: spare the integer division
  if (i >= period && i < 2 * period) return i - period;
  if (i < 0 && i >= -period) return i + period;
  i %= period;
  return i < 0 ? i + period : i;
}

/// The dense block of candidate new cells a remap accumulates into: an index range per axis, wrapped
/// on periodic axes.
template <int D>
struct CellGrid {
  IndexRange<D> range;
  std::array<std::int64_t, D> count{}, periods{};
  std::size_t n_cells = 0;

  /// Flat index of a cell, wrapping periodic axes; -1 outside the grid.
  std::int64_t flat(std::array<std::int64_t, D> idx) const {
    std::int64_t f = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      std::int64_t i = idx[kk];
      if (periods[kk] > 0) i = wrap_index(i, periods[kk]);
      i -= range.lo[kk];
      if (i < 0 || i >= count[kk]) return -1;
      f = f * count[kk] + i;
    }
    return f;
  }
  /// One integer division per axis but the last (f lies in the grid): the new set asks this of every cell.
  std::array<std::int64_t, D> unflat(std::size_t f) const {
    std::array<std::int64_t, D> idx;
    for (int k = 0; k + 1 < D; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      const std::size_t rest = f / static_cast<std::size_t>(count[kk]);
      idx[kk] = range.lo[kk] + static_cast<std::int64_t>(f - rest * static_cast<std::size_t>(count[kk]));
      f = rest;
    }
    idx[D - 1] = range.lo[D - 1] + static_cast<std::int64_t>(f);
    return idx;
  }
};

/// Calls f(g) for every cell of `grid` within `layers` index steps of cell c on each axis, c left out.
template <int D, class F>
void for_each_cell_within(const CellGrid<D>& grid, std::size_t c, int layers, F&& f) {
  const auto idx = grid.unflat(c);
  std::array<std::int64_t, D> off;
  off.fill(-layers);
  for (;;) {
    std::array<std::int64_t, D> nb;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) nb[k] = idx[k] + off[k];
    const std::int64_t g = grid.flat(nb);
    if (g >= 0 && static_cast<std::size_t>(g) != c) f(static_cast<std::size_t>(g));
    std::size_t k = 0;
    for (; k < static_cast<std::size_t>(D); ++k) {
      if (++off[k] <= layers) break;
      off[k] = -layers;
    }
    if (k == static_cast<std::size_t>(D)) break;
  }
}

/// The largest smoothing length of the real particles: old cells reach at most the closing radius in h of it.
template <int D, bool E>
double max_smoothing_length(const ParticleSet<D, E>& p) {
  double max_h = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) max_h = std::max(max_h, p.h[a]);
  return max_h;
}

/// The candidate cells: the whole box on closed axes, the particles' extent plus the closing radius on
/// open ones, there rounded out to whole multiples of `align` cells (counted from box.lo). Only an index
/// range: a remap sums into it densely or, where it holds many cells per particle, sparsely (sums.hpp).
/// `whole`: on many ranks, the extent is every rank's particles', so that every rank lays out the same grid.
template <class Lattice, int D, bool E>
CellGrid<D> candidate_grid(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice,
                           const RemapParams& params, std::int64_t align = 1, const RankPart& whole = {}) {
  CellGrid<D> g;
  g.periods = lattice.periods(box);
  const std::size_t n_old = p.n_real;
  Vec<D> lo, hi;
  const double max_h = whole.max(max_smoothing_length(p));
  for (int k = 0; k < D; ++k) {
    if (box.edge[k] == Edge::open) {
      lo[k] = std::numeric_limits<double>::max();
      hi[k] = std::numeric_limits<double>::lowest();
      for (std::size_t a = 0; a < n_old; ++a) {
        lo[k] = std::min(lo[k], p.x[a][k]);
        hi[k] = std::max(hi[k], p.x[a][k]);
      }
      lo[k] = whole.min(lo[k]);
      hi[k] = whole.max(hi[k]);
      lo[k] -= params.closing_radius_in_h * max_h * 1.1;
      hi[k] += params.closing_radius_in_h * max_h * 1.1;
    } else {
      lo[k] = box.lo[k];
      hi[k] = box.hi[k];
    }
  }
  g.range = lattice.cells_touching(box, lo, hi);
  double cells = 1.0;  // as a double first: an extent of many cells cannot overflow the count
  for (int k = 0; k < D; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (g.periods[kk] > 0) {
      g.range.lo[kk] = 0;
      g.range.hi[kk] = g.periods[kk] - 1;
    } else if (box.edge[k] == Edge::reflecting) {
      // rows whose sites lie inside the walls
      while (lattice.site(box, g.range.lo)[k] < box.lo[k]) ++g.range.lo[kk];
      auto top = g.range.lo;
      top[kk] = g.range.hi[kk];
      while (lattice.site(box, top)[k] > box.hi[k]) top[kk] = --g.range.hi[kk];
    } else if (align > 1) {
      auto floor_div = [](std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
      g.range.lo[kk] = floor_div(g.range.lo[kk], align) * align;
      g.range.hi[kk] = (floor_div(g.range.hi[kk], align) + 1) * align - 1;
    }
    g.count[kk] = g.range.hi[kk] - g.range.lo[kk] + 1;
    cells *= static_cast<double>(g.count[kk]);
  }
  require(cells < 0x1p62, "regularization: the particles span " + std::to_string(cells) + " lattice cells (" +
                              std::to_string(n_old) + " particles), more than flat indices can number");
  g.n_cells = static_cast<std::size_t>(cells);
  return g;
}

/// Axis k's part of the flat index of lattice index i in `grid`: wrapped on periodic axes, clamped at
/// walls (a round-off sliver beyond a wall); -1 outside the grid.
template <int D>
std::int64_t axis_part(const CellGrid<D>& grid, const Box<D>& box, int k, std::int64_t i) {
  const auto kk = static_cast<std::size_t>(k);
  if (grid.periods[kk] > 0) i = wrap_index(i, grid.periods[kk]);
  i -= grid.range.lo[kk];
  if (box.edge[k] == Edge::reflecting) i = std::clamp<std::int64_t>(i, 0, grid.count[kk] - 1);
  if (i < 0 || i >= grid.count[kk]) return -1;
  for (int m = 0; m < k; ++m) i *= grid.count[static_cast<std::size_t>(m)];
  return i;
}
/// Whether lattice index idx lies beyond a wall (outside the grid along a reflecting axis).
template <int D>
bool beyond_wall(const CellGrid<D>& grid, const Box<D>& box, std::type_identity_t<std::array<std::int64_t, D>> idx) {
  for (int k = 0; k < D; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (box.edge[k] == Edge::reflecting &&
        (idx[kk] < grid.range.lo[kk] || idx[kk] >= grid.range.lo[kk] + grid.count[kk]))
      return true;
  }
  return false;
}

}  // namespace rsph::regularize::detail
