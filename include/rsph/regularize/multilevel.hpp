#pragma once
// Variable resolution in factors of two, as in adaptive mesh refinement: space is tiled by blocks of
// block_cells^D level-0 cells; each block carries one level l, with spacing Delta_l = Delta_0 / 2^l and
// h_l = (h/Delta) Delta_l; neighbouring blocks (diagonals and periodic images included) differ by at
// most one level. The remap of eqs. (6)-(9) onto it stays exactly conservative: overlaps are taken on
// the finest lattice and summed into each coarser cell, which is a union of finest cells.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/refinement.hpp"
#include "rsph/regularize/remap.hpp"

#include <map>
#include <numeric>
#include <string>
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

  /// Levels of the blocks at the last regularization, by block index (hysteresis reads them).
  const std::map<std::array<std::int64_t, D>, int>& levels() const { return levels_; }
  int previous_level(const std::array<std::int64_t, D>& block) const {
    const auto it = levels_.find(block);
    return it == levels_.end() ? refine::no_previous_level : it->second;
  }
  void store_levels(std::map<std::array<std::int64_t, D>, int> levels) { levels_ = std::move(levels); }

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

}  // namespace detail

/// Remaps `p` onto a multi-level lattice: sets every block's level from the criterion (capped at the
/// finest level, 2:1 balanced), then builds one particle per kept cell, block by block and in lattice
/// order within a block, with h = h_over_dx * Delta_l. Mass, momentum and total energy are conserved
/// exactly as on a uniform lattice.
template <int D, class Criterion, class Builder, bool E, class Region = region::Unbounded>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                              Builder& builder, const RemapParams& params, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr) {
  ml.validate();
  RemapWorkspace<D> local;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  const auto fine = ml.finest();
  detail::check_remap_input(p, fine, params);
  const std::int64_t ratio = std::int64_t{1} << ml.max_level;  // finest cells per level-0 cell and axis
  const std::int64_t align = ratio * ml.block_cells;           // finest cells per block and axis
  for (int k = 0; k < D; ++k)
    if (box.edge[k] != Edge::open) {
      const double blocks = (box.hi[k] - box.lo[k]) / (ml.spacing * ml.block_cells);
      require(std::abs(blocks - std::round(blocks)) < 1e-9 * std::max(1.0, blocks) && std::round(blocks) >= 1,
              "multi-level lattice: the box length along axis " + std::to_string(k) +
                  " must be a whole number of blocks (block size " + std::to_string(ml.spacing * ml.block_cells) + ")");
    }
  const auto grid = detail::candidate_grid(p, box, fine, params, align);
  auto& S = detail::accumulate_overlaps(p, box, fine, builder, params, grid, region, ws);
  RemapStats stats;
  stats.max_volume_mismatch = S.max_mismatch;

  // Level-0 sums for the criteria.
  refine::BlockField<D> field;
  field.spacing = ml.spacing;
  field.cells_per_block = ml.block_cells;
  std::array<std::int64_t, D> n0{}, block0{};
  std::size_t n_level0 = 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    n0[k] = grid.count[k] / ratio;
    field.blocks[k] = grid.count[k] / align;
    block0[k] = grid.range.lo[k] / align;  // aligned: exact
    field.periods[k] = grid.periods[k] > 0 ? field.blocks[k] : 0;
    field.origin[static_cast<int>(k)] =
        box.lo[static_cast<int>(k)] + static_cast<double>(grid.range.lo[k]) * fine.spacing;
    n_level0 *= static_cast<std::size_t>(n0[k]);
  }
  field.mass.assign(n_level0, 0.0);
  field.volume.assign(n_level0, 0.0);
  for (std::size_t f = 0; f < grid.n_cells; ++f) {
    if (S.fill[f] == 0.0) continue;
    const auto idx = grid.unflat(f);
    std::size_t c = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      c = c * static_cast<std::size_t>(n0[kk]) + static_cast<std::size_t>((idx[kk] - grid.range.lo[kk]) / ratio);
    }
    field.mass[c] += S.m[f];
    field.volume[c] += S.fill[f];
  }

  // Levels: criterion, cap, 2:1 balance.
  const std::size_t n_blocks = field.n_blocks();
  std::vector<int> level(n_blocks, 0);
  auto absolute = [&](std::size_t b) {
    auto bi = field.block_index(b);
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) bi[k] += block0[k];
    return bi;
  };
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const int want = static_cast<int>(ml.criterion.level(field, b, ml.previous_level(absolute(b))));
    stats.requested_level = std::max(stats.requested_level, want);
    if (want > ml.max_level) ++stats.capped_blocks;
    level[b] = std::clamp(want, 0, ml.max_level);
  }
  detail::balance_two_to_one(field, level);

  // Cells of every block at its level; owner maps each finest cell to its cell.
  detail::Sums<D> cells;
  std::vector<std::uint32_t> owner(grid.n_cells);
  std::vector<std::array<std::int64_t, D>> first_fine;  // lowest finest-cell index (grid-relative) per cell
  std::vector<std::int64_t> span;                       // finest cells per axis per cell
  std::vector<int> cell_level;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const auto bi = field.block_index(b);
    const std::int64_t s = std::int64_t{1} << (ml.max_level - level[b]);
    const std::int64_t per_axis = align / s;
    std::array<std::int64_t, D> ci;
    ci.fill(0);
    for (;;) {
      std::array<std::int64_t, D> f0;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) f0[k] = bi[k] * align + ci[k] * s;
      const auto id = static_cast<std::uint32_t>(first_fine.size());
      first_fine.push_back(f0);
      span.push_back(s);
      cell_level.push_back(level[b]);
      // every finest cell of the footprint
      std::array<std::int64_t, D> fi;
      fi.fill(0);
      for (;;) {
        std::array<std::int64_t, D> g;
        for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) g[k] = grid.range.lo[k] + f0[k] + fi[k];
        owner[static_cast<std::size_t>(grid.flat(g))] = id;
        std::size_t k = 0;
        for (; k < static_cast<std::size_t>(D); ++k) {
          if (++fi[k] < s) break;
          fi[k] = 0;
        }
        if (k == static_cast<std::size_t>(D)) break;
      }
      std::size_t k = 0;
      for (; k < static_cast<std::size_t>(D); ++k) {
        if (++ci[k] < per_axis) break;
        ci[k] = 0;
      }
      if (k == static_cast<std::size_t>(D)) break;
    }
  }
  const std::size_t n_cells = first_fine.size();
  cells.resize(n_cells);
  for (std::size_t f = 0; f < grid.n_cells; ++f) {
    const std::size_t c = owner[f];
    cells.m[c] += S.m[f];
    cells.mv[c] += S.mv[f];
    cells.E[c] += S.E[f];
    cells.fill[c] += S.fill[f];
  }

  auto volume = [&](std::size_t c) { return std::pow(ml.spacing_at(cell_level[c]), D); };
  auto for_each_neighbour = [&](std::size_t c, auto&& f) {
    // owners of the finest cells in the one-cell ring around c's footprint
    const std::int64_t s = span[c];
    std::array<std::int64_t, D> off;
    off.fill(-1);
    std::uint32_t last = static_cast<std::uint32_t>(c);
    for (;;) {
      bool ring = false;
      std::array<std::int64_t, D> g;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
        ring = ring || off[k] < 0 || off[k] >= s;
        g[k] = grid.range.lo[k] + first_fine[c][k] + off[k];
      }
      if (ring) {
        const std::int64_t fl = grid.flat(g);
        if (fl >= 0) {
          const std::uint32_t o = owner[static_cast<std::size_t>(fl)];
          if (o != c && o != last) f(static_cast<std::size_t>(o));  // repeats only cost a comparison
          last = o;
        }
      }
      std::size_t k = 0;
      for (; k < static_cast<std::size_t>(D); ++k) {
        if (++off[k] <= s) break;
        off[k] = -1;
      }
      if (k == static_cast<std::size_t>(D)) break;
    }
  };
  auto& keep = ws.keep;
  detail::hand_on_sparse_cells<D>(cells, params, volume, for_each_neighbour, stats.dropped_cells, keep);

  auto& order = ws.order;
  order.resize(n_cells);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<std::size_t> block_of(n_cells);
  {
    std::size_t c = 0;
    for (std::size_t b = 0; b < n_blocks; ++b) {
      const auto n = static_cast<std::size_t>(std::pow(static_cast<double>(align >> (ml.max_level - level[b])), D));
      for (std::size_t i = 0; i < n; ++i) block_of[c++] = b;
    }
  }
  auto place = [&](std::size_t c) {
    const double dx = fine.spacing;
    Vec<D> site;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k)
      site[static_cast<int>(k)] = field.origin[static_cast<int>(k)] +
                                  (static_cast<double>(first_fine[c][k]) + 0.5 * static_cast<double>(span[c])) * dx;
    const int l = cell_level[c];
    double h = params.h_over_dx * ml.spacing_at(l);
    if (ml.h_ramp > 0.0 && l > 0) {
      // distance to the nearest coarser neighbouring block (2:1 balance: one level coarser)
      const double ramp = ml.h_ramp * ml.spacing_at(l - 1);
      const double d = detail::distance_to_coarser_block(field, level, block_of[c], site, ramp);
      if (d < ramp) h += (params.h_over_dx * ml.spacing_at(l - 1) - h) * (1.0 - d / ramp);
    }
    return std::pair{site, h};
  };
  detail::emit_particles(p, cells, keep, order, place, stats);

  stats.per_level.assign(static_cast<std::size_t>(ml.max_level) + 1, 0);
  for (std::size_t c = 0; c < n_cells; ++c)
    if (keep[c] && cells.m[c] > 0.0) ++stats.per_level[static_cast<std::size_t>(cell_level[c])];
  std::map<std::array<std::int64_t, D>, int> levels;
  for (std::size_t b = 0; b < n_blocks; ++b) levels[absolute(b)] = level[b];
  ml.store_levels(std::move(levels));
  return stats;
}

}  // namespace regularize
}  // namespace rsph
