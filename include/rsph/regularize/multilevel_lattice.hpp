#pragma once
// The multi-level lattice (multilevel.hpp): blocks in factors of two, their neighbours and 2:1 balance, and the
// footprint of every new cell on the finest grid.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/refinement.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph {
namespace lattice {

/// The uniform lattice of one level: square in 2D, uniform in 1D.
template <int D>
using LevelLattice = std::conditional_t<D == 1, Uniform1D, Square>;

/// A multi-level lattice of blocks; `criterion` sets each block's level at every regularization.
template <int D, class Criterion>
struct MultiLevel {
  static_assert(D == 1 || D == 2, "multi-level lattices are built in 1D and 2D");
  static_assert(refine::check_criterion<Criterion, D>());
  static constexpr int dim = D;
  static constexpr int deepest_supported = 10;
  /// Runs on many ranks: every rank chooses the levels of the blocks near its part from the field the ranks
  /// complete together, as one process would, and keeps those alone (multilevel.hpp, level_windows.hpp); it builds
  /// its own particles' old cells only, and each new cell's parts are added at the rank that keeps it
  /// (level_owners.hpp).
  static constexpr bool remaps_on_ranks = true;

  double spacing;   ///< Delta_0, the coarsest level's spacing
  int max_level;    ///< the finest level L
  int block_cells;  ///< level-0 cells per block and axis
  Criterion criterion;
  /// Width, in spacings of the coarser level, over which h of a finer block rises towards the coarser
  /// block's h next to it (0: h jumps at the block face).
  double h_ramp = 0.0;

  MultiLevel(double spacing_0, int finest_level, int cells_per_block, Criterion c)
      : spacing(spacing_0), max_level(finest_level), block_cells(cells_per_block), criterion(std::move(c)) {}

  void validate() const {
    require(spacing > 0.0, "multi-level lattice: the level-0 spacing must be positive");
    require(max_level >= 0 && max_level <= deepest_supported, "multi-level lattice: the finest level must lie in [0, " +
                                                                  std::to_string(deepest_supported) + "] (got " +
                                                                  std::to_string(max_level) + ")");
    require(block_cells >= 1, "multi-level lattice: a block needs at least one level-0 cell per axis");
    require(h_ramp >= 0.0 && h_ramp <= block_cells,
            "multi-level lattice: the h ramp must lie in [0, block_cells] coarser spacings");
    if constexpr (requires { criterion.validate(); }) criterion.validate();
  }
  double spacing_at(int level) const { return spacing / static_cast<double>(std::int64_t{1} << level); }
  LevelLattice<D> finest() const { return {spacing_at(max_level)}; }

  /// Levels of the blocks at the last regularization, by block index (hysteresis reads them): every block in one
  /// process, on many ranks those near a rank's part.
  const std::map<std::array<std::int64_t, D>, int>& levels() const { return levels_; }
  void store_levels(std::map<std::array<std::int64_t, D>, int> levels) { levels_ = std::move(levels); }

  /// Saves or restores the blocks' levels through a checkpoint archive (io/checkpoint.hpp): one row a block (its
  /// index per axis, its level), every rank's rows in a file written by many, a share of them restored on each
  /// (the next remap hands every rank the levels near its part, whichever rank holds them).
  template <class Archive>
  void checkpoint(Archive& ar) {
    std::array<std::vector<std::int64_t>, D> blocks;
    std::vector<int> levels;
    for (const auto& [block, level] : levels_) {
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) blocks[k].push_back(block[k]);
      levels.push_back(level);
    }
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k)
      ar.rows("lattice_block_" + std::to_string(k), blocks[k]);
    ar.rows("lattice_levels", levels);
    if (ar.saving()) return;
    for (const auto& axis : blocks)
      require(axis.size() == levels.size(), "checkpoint: the lattice's block levels are misshapen");
    levels_.clear();
    for (std::size_t i = 0; i < levels.size(); ++i) {
      std::array<std::int64_t, D> block;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) block[k] = blocks[k][i];
      levels_.emplace(block, levels[i]);
    }
  }

 private:
  std::map<std::array<std::int64_t, D>, int> levels_;
};

}  // namespace lattice

namespace regularize {
namespace detail {

/// Calls f(g, off) for every block g next to block b (diagonals and periodic images included; b itself
/// with off = 0), where off is g's offset from b in blocks.
template <int D, class F>
void for_each_neighbour_block(const refine::BlockField<D>& field, std::size_t b, F&& f) {
  const auto bi = field.block_index(b);
  std::array<std::int64_t, D> off;
  off.fill(-1);
  for (;;) {
    std::size_t g = 0;
    bool inside = true;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      std::int64_t i = bi[kk] + off[kk];
      if (field.periods[kk] > 0)
        i = ((i % field.blocks[kk]) + field.blocks[kk]) % field.blocks[kk];
      else if (i < 0 || i >= field.blocks[kk])
        inside = false;
      g = g * static_cast<std::size_t>(field.blocks[kk]) + static_cast<std::size_t>(std::max<std::int64_t>(i, 0));
    }
    if (inside) f(g, off);
    std::size_t k = 0;
    for (; k < static_cast<std::size_t>(D); ++k) {
      if (++off[k] <= 1) break;
      off[k] = -1;
    }
    if (k == static_cast<std::size_t>(D)) break;
  }
}

/// Raises levels until neighbouring blocks differ by at most one (refinement wins over coarsening).
template <int D>
void balance_two_to_one(const refine::BlockField<D>& field, std::vector<int>& level) {
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t b = 0; b < field.n_blocks(); ++b) {
      int need = level[b];
      for_each_neighbour_block(field, b, [&](std::size_t g, const auto&) { need = std::max(need, level[g] - 1); });
      if (need > level[b]) {
        level[b] = need;
        changed = true;
      }
    }
  }
}

/// Distance from x (in block b) to the nearest block next to b on a coarser level than b; `none` when
/// no neighbour is coarser.
template <int D>
double distance_to_coarser_block(const refine::BlockField<D>& field, const std::vector<int>& level, std::size_t b,
                                 const Vec<D>& x, double none) {
  double best = none;
  const Vec<D> lo = field.block_lo(b);
  for_each_neighbour_block(field, b, [&](std::size_t g, const std::array<std::int64_t, D>& off) {
    if (level[g] >= level[b]) return;
    // the neighbour's box, placed next to b (periodic images included)
    double d2 = 0.0;
    for (int k = 0; k < D; ++k) {
      const double a = lo[k] + static_cast<double>(off[static_cast<std::size_t>(k)]) * field.block_size();
      const double gap = std::max({a - x[k], 0.0, x[k] - (a + field.block_size())});
      d2 += gap * gap;
    }
    best = std::min(best, std::sqrt(d2));
  });
  return best;
}

/// The new cells of every block at its level, in block order and lattice order within a block: each
/// cell's footprint on the finest grid (its lowest finest index, grid-relative, and its span in finest
/// cells per axis), its level, and per finest cell its owner.
template <int D>
struct Footprint {
  std::vector<std::uint32_t> owner;
  std::vector<std::array<std::int64_t, D>> first_fine;
  std::vector<std::int64_t> span;
  std::vector<int> level;
  std::vector<std::size_t> block;        ///< the block each new cell lies in (of the level field's blocks)
  Vec<D> origin;                         ///< lower corner of the whole set's grid
  std::array<std::int64_t, D> offset{};  ///< the grid's first finest cell in the whole set's grid
  double dx = 0;                         ///< the finest spacing

  std::size_t size() const { return span.size(); }
  /// Placed from the whole set's grid, so that a site has the same bits whichever part of it a rank sums on.
  Vec<D> site(std::size_t c) const {
    Vec<D> x;
    for (int k = 0; k < D; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      x[k] =
          origin[k] + (static_cast<double>(first_fine[c][kk] + offset[kk]) + 0.5 * static_cast<double>(span[c])) * dx;
    }
    return x;
  }
};

/// Steps a D-dimensional counter through [lo, hi) per axis, axis 0 fastest; false once it has passed them all.
template <int D>
bool next_index(std::array<std::int64_t, D>& i, std::int64_t lo, std::int64_t hi) {
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    if (++i[k] < hi) return true;
    i[k] = lo;
  }
  return false;
}

}  // namespace detail
}  // namespace regularize
}  // namespace rsph
