#pragma once
// Variable resolution in factors of two, as in adaptive mesh refinement: space is tiled by blocks of
// block_cells^D level-0 cells; each block carries one level l, with spacing Delta_l = Delta_0 / 2^l and
// h_l = (h/Delta) Delta_l; neighbouring blocks (diagonals and periodic images included) differ by at
// most one level. The remap of eqs. (6)-(9) onto it stays exactly conservative: overlaps are taken on
// the finest lattice and summed into each coarser cell, which is a union of finest cells.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/level_faces.hpp"
#include "rsph/regularize/level_owners.hpp"
#include "rsph/regularize/level_windows.hpp"
#include "rsph/regularize/multilevel_lattice.hpp"
#include "rsph/regularize/refinement.hpp"
#include "rsph/regularize/remap.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::regularize {
namespace detail {

/// Every closed axis of the box must hold a whole number of blocks.
template <int D, class Criterion>
void check_whole_blocks(const Box<D>& box, const lattice::MultiLevel<D, Criterion>& ml) {
  for (int k = 0; k < D; ++k)
    if (box.edge[k] != Edge::open) {
      const double blocks = (box.hi[k] - box.lo[k]) / (ml.spacing * ml.block_cells);
      require(std::abs(blocks - std::round(blocks)) < 1e-9 * std::max(1.0, blocks) && std::round(blocks) >= 1,
              "multi-level lattice: the box length along axis " + std::to_string(k) +
                  " must be a whole number of blocks (block size " + std::to_string(ml.spacing * ml.block_cells) + ")");
    }
}

/// The level-0 layout of the blocks of `window`, a block-aligned part of the whole set's grid `whole` (mass and
/// volume zero); block0 receives the absolute index of its first block.
template <int D, class Criterion>
refine::BlockField<D> level0_layout(const lattice::MultiLevel<D, Criterion>& ml, const Box<D>& box,
                                    const CellGrid<D>& whole, const CellGrid<D>& window, BlockIndex<D>& block0) {
  const std::int64_t ratio = std::int64_t{1} << ml.max_level;  // finest cells per level-0 cell and axis
  const std::int64_t align = ratio * ml.block_cells;           // finest cells per block and axis
  refine::BlockField<D> field;
  field.spacing = ml.spacing;
  field.cells_per_block = ml.block_cells;
  std::size_t n_level0 = 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    field.blocks[k] = window.count[k] / align;
    block0[k] = window.range.lo[k] / align;  // aligned: exact
    field.first_block[k] = (window.range.lo[k] - whole.range.lo[k]) / align;
    field.periods[k] = whole.periods[k] > 0 ? field.blocks[k] : 0;  // (a window spans a periodic axis whole)
    field.origin[static_cast<int>(k)] =
        box.lo[static_cast<int>(k)] + static_cast<double>(whole.range.lo[k]) * ml.finest().spacing;
    n_level0 *= static_cast<std::size_t>(window.count[k] / ratio);
  }
  field.mass.assign(n_level0, 0.0);
  field.volume.assign(n_level0, 0.0);
  return field;
}

/// Adds to `field` (laid out on `whole`, a window) the finest cells' mass and volume of `grid`, a block-aligned part
/// of `whole` (`finest(f)` gives the pair of cell f), in the order of grid's cells.
template <int D, class Criterion, class Finest>
void add_finest_cells(refine::BlockField<D>& field, const lattice::MultiLevel<D, Criterion>& ml,
                      const CellGrid<D>& whole, const CellGrid<D>& grid, Finest&& finest) {
  const std::int64_t ratio = std::int64_t{1} << ml.max_level;
  for (std::size_t f = 0; f < grid.n_cells; ++f) {
    const auto [m, volume] = finest(f);
    if (volume == 0.0) continue;
    const auto idx = grid.unflat(f);
    std::size_t c = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      c = c * static_cast<std::size_t>(whole.count[kk] / ratio) +
          static_cast<std::size_t>((idx[kk] - whole.range.lo[kk]) / ratio);
    }
    field.mass[c] += m;
    field.volume[c] += volume;
  }
}

/// The grids of a multi-level remap: `whole`, the whole set's (alike on every rank), on which blocks are numbered;
/// `local`, the block-aligned part of it that the old cells built here reach, on which this rank sums; `window`,
/// local grown by max_level + 1 blocks, over which it lays out the level-0 field and chooses levels (the 2:1
/// balance carries a level at most max_level blocks, so the blocks `kept`, local's grown by one, which the
/// footprint and the h ramp read, get the levels one process gives them); and `kept`, whose levels it stores for
/// the next remap. In one process all are the whole. A rank's memory then follows its particles, not the box; on
/// periodic axes it spans the period. A rank that builds no cell sums on one block.
template <int D>
struct LevelGrids {
  CellGrid<D> whole, local, window;
  BlockRange<D> kept;
};

/// The field the criteria read, over the blocks of `grids.window`: from this process's sums on it, or on many ranks
/// from each rank's part of the sums on its part of the finest grid (the remap by owners: every old cell was built
/// by its owner alone, so the parts add up to the whole set's sums). A rank adds its parts into its level-0 cells,
/// and the ranks whose windows meet trade them (trade_level_inputs), so that every rank holds the same bits in a
/// cell. What travels is one record a level-0 cell, not one a finest cell; with them the levels kept at the last
/// remap travel into `previous`.
template <int D, class Criterion>
refine::BlockField<D> level0_field(const lattice::MultiLevel<D, Criterion>& ml, const Box<D>& box,
                                   const LevelGrids<D>& grids, const Sums<D>& S, const RankPart& part,
                                   const RankWindows<D>& all, BlockIndex<D>& block0,
                                   std::map<BlockIndex<D>, int>& previous) {
  auto field = level0_layout(ml, box, grids.whole, grids.window, block0);
  add_finest_cells(field, ml, grids.window, grids.local, [&](std::size_t f) {
    return std::pair{S.cell[f].m, S.cell[f].volume};
  });
  if (!part.on_ranks()) return field;
  return trade_level_inputs(field, block0, ml.levels(), all, part, previous);
}

template <int D, class Criterion, bool E>
LevelGrids<D> level_grids(const ParticleSet<D, E>& p, const Box<D>& box, const lattice::MultiLevel<D, Criterion>& ml,
                          const RemapParams& params, const RankPart& part) {
  const auto fine = ml.finest();
  const std::int64_t align = (std::int64_t{1} << ml.max_level) * ml.block_cells;  // finest cells per block and axis
  LevelGrids<D> g{candidate_grid(p, box, fine, params, align, part), {}, {}, {}};
  g.local = g.window = g.whole;
  g.kept = blocks_of(g.whole, align);
  if (!part.on_ranks()) return g;
  Vec<D> lo = Vec<D>::Constant(std::numeric_limits<double>::max()), hi = -lo;
  double h_max = 0.0;
  for (const std::uint32_t a : part.cells) {
    lo = lo.cwiseMin(p.x[a]);
    hi = hi.cwiseMax(p.x[a]);
    h_max = std::max(h_max, p.h[a]);
  }
  // the old cells built here, and on many ranks the new cells near them that the hand-on and face cells read
  const double reach = params.closing_radius_in_h * h_max * 1.1 + level0_cells_beyond_own * ml.spacing;
  const auto touched = fine.cells_touching(box, (lo.array() - reach).matrix(), (hi.array() + reach).matrix());
  auto floor_div = [](std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
  double cells = 1.0;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    auto& r = g.local.range;
    if (part.cells.empty()) {
      r.hi[k] = r.lo[k] + align - 1;
    } else if (g.whole.periods[k] == 0) {
      r.lo[k] = std::max(g.whole.range.lo[k], floor_div(touched.lo[k], align) * align);
      r.hi[k] = std::min(g.whole.range.hi[k], (floor_div(touched.hi[k], align) + 1) * align - 1);
      if (r.hi[k] < r.lo[k]) {  // (no cell reaches the whole grid: its first block)
        r.lo[k] = g.whole.range.lo[k];
        r.hi[k] = r.lo[k] + align - 1;
      }
    }
    g.local.count[k] = r.hi[k] - r.lo[k] + 1;
    cells *= static_cast<double>(g.local.count[k]);
  }
  g.local.n_cells = static_cast<std::size_t>(cells);
  g.window = grown_by_blocks(g.local, g.whole, ml.max_level + 1, align);
  g.kept = blocks_of(grown_by_blocks(g.local, g.whole, 1, align), align);
  return g;
}

/// Block b's absolute index (the grid's blocks start at block0).
template <int D>
BlockIndex<D> absolute_block(const refine::BlockField<D>& field, const BlockIndex<D>& block0, std::size_t b) {
  auto bi = field.block_index(b);
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) bi[k] += block0[k];
  return bi;
}

/// Each block's level: the criterion's (given the level `previous` holds for it), capped at the finest level, then
/// 2:1 balanced. The blocks asked above the finest level are reported where `counted` (its absolute index).
template <int D, class Criterion, class Counted>
std::vector<int> choose_levels(const lattice::MultiLevel<D, Criterion>& ml, const refine::BlockField<D>& field,
                               const BlockIndex<D>& block0, const std::map<BlockIndex<D>, int>& previous,
                               Counted&& counted, RemapStats& stats) {
  std::vector<int> level(field.n_blocks(), 0);
  for (std::size_t b = 0; b < level.size(); ++b) {
    const auto block = absolute_block(field, block0, b);
    const auto before = previous.find(block);
    const int want = static_cast<int>(
        ml.criterion.level(field, b, before == previous.end() ? refine::no_previous_level : before->second));
    if (counted(block)) {
      stats.requested_level = std::max(stats.requested_level, want);
      if (want > ml.max_level) ++stats.capped_blocks;
    }
    level[b] = std::clamp(want, 0, ml.max_level);
  }
  balance_two_to_one(field, level);
  return level;
}

/// The new cells of the blocks that lie in `grid`, a block-aligned part of `window` (on which `field` and `level`
/// are laid out), each block at its level, in block order; their sites are placed from the whole set's grid.
template <int D>
Footprint<D> footprint(const refine::BlockField<D>& field, const std::vector<int>& level, const LevelGrids<D>& grids,
                       int max_level, std::int64_t align, double dx) {
  const CellGrid<D>& grid = grids.local;
  Footprint<D> fp;
  fp.owner.resize(grid.n_cells);
  fp.dx = dx;
  fp.origin = field.origin;
  std::array<std::int64_t, D> first{}, last{};  // the blocks of `grid`, in the window's blocks
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    fp.offset[k] = grid.range.lo[k] - grids.whole.range.lo[k];
    first[k] = (grid.range.lo[k] - grids.window.range.lo[k]) / align;
    last[k] = first[k] + grid.count[k] / align;
  }
  for (std::size_t b = 0; b < level.size(); ++b) {
    auto bi = field.block_index(b);
    bool inside = true;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      inside = inside && bi[k] >= first[k] && bi[k] < last[k];
      bi[k] -= first[k];
    }
    if (!inside) continue;
    const std::int64_t s = std::int64_t{1} << (max_level - level[b]);
    std::array<std::int64_t, D> ci;
    ci.fill(0);
    do {
      std::array<std::int64_t, D> f0;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) f0[k] = bi[k] * align + ci[k] * s;
      const auto id = static_cast<std::uint32_t>(fp.first_fine.size());
      fp.first_fine.push_back(f0);
      fp.span.push_back(s);
      fp.level.push_back(level[b]);
      fp.block.push_back(b);
      std::array<std::int64_t, D> fi;  // every finest cell of the footprint
      fi.fill(0);
      do {
        std::array<std::int64_t, D> g;
        for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) g[k] = grid.range.lo[k] + f0[k] + fi[k];
        fp.owner[static_cast<std::size_t>(grid.flat(g))] = id;
      } while (next_index<D>(fi, 0, s));
    } while (next_index<D>(ci, 0, align / s));
  }
  return fp;
}

/// The end of the multi-level remap: nearly empty cells handed on, one particle per kept cell with h ramped
/// towards coarser blocks (on many ranks, per cell this rank keeps: ws.elsewhere flags the others, whose sums the
/// hand-on reads), and the levels of the blocks `kept` stored for the next remap.
template <int D, bool E, class Criterion, class Field, class Levels>
void emit_on_levels(ParticleSet<D, E>& p, lattice::MultiLevel<D, Criterion>& ml, const RemapParams& params,
                    const CellGrid<D>& grid, const BlockRange<D>& kept, const Footprint<D>& fp, const Field& field,
                    const Levels& level, const BlockIndex<D>& block0, Sums<D>& cells,
                    const std::vector<double>& cell_volume, RemapWorkspace<D>& ws, RemapStats& stats,
                    const RankPart& part) {
  auto& keep = ws.keep;
  hand_on_sparse_cells<D>(
      cells, params, [&](std::size_t c) { return cell_volume[c]; },
      [&](std::size_t c, auto&& f) { for_each_ring_neighbour(grid, fp, c, f); }, stats.dropped_cells, keep, part,
      ws.elsewhere);
  for (std::size_t c = 0; c < ws.elsewhere.size(); ++c)
    if (ws.elsewhere[c]) keep[c] = 0;
  const std::size_t n_cells = fp.size();
  auto& order = ws.order;
  order.resize(n_cells);
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto place = [&](std::size_t c) {
    const Vec<D> site = fp.site(c);
    const int l = fp.level[c];
    double h = params.h_over_dx * ml.spacing_at(l);
    if (ml.h_ramp > 0.0 && l > 0) {
      // distance to the nearest coarser neighbouring block (2:1 balance: one level coarser)
      const double ramp = ml.h_ramp * ml.spacing_at(l - 1);
      const double d = distance_to_coarser_block(field, level, fp.block[c], site, ramp);
      if (d < ramp) h += (params.h_over_dx * ml.spacing_at(l - 1) - h) * (1.0 - d / ramp);
    }
    return std::pair{site, h};
  };
  emit_particles(p, cells, keep, order, place, stats, part.own);
  stats.per_level.assign(static_cast<std::size_t>(ml.max_level) + 1, 0);
  for (std::size_t c = 0; c < n_cells; ++c)
    if (keep[c] && cells.cell[c].m > 0.0) ++stats.per_level[static_cast<std::size_t>(fp.level[c])];
  std::map<std::array<std::int64_t, D>, int> levels;
  for (std::size_t b = 0; b < level.size(); ++b) {
    const auto block = absolute_block(field, block0, b);
    if (kept.contains(block)) levels[block] = level[b];
  }
  ml.store_levels(std::move(levels));
}

/// The multi-level remap around the sums on the finest cells of grids.local: sums_on(grid, stats) gives them, and
/// once the level of every block is set, at_faces(fp, faces, stats) gives them again (a second-order remap
/// takes the old cells that reach a face cell to first order, as the face cells' hand-out is). Then every
/// block's level from the criterion (capped at the finest level, 2:1 balanced), one particle per kept cell,
/// block by block and in lattice order within a block, with h = h_over_dx * Delta_l.
/// `part`: on many ranks, each rank builds the old cells of its own particles only (the remap by owners), sums
/// their parts on its part of the finest grid and chooses the levels over a window around it from the level-0
/// field the ranks whose windows meet complete together (one record a level-0 cell), so that the blocks it needs get
/// the levels one process gives them; the face cells take the parts of its own old cells too, and each new cell's
/// parts are added at the rank that keeps it (level_owners.hpp). A rank's old cells or keepers beyond what it
/// gathered raise HaloTooNarrow on every rank, before any particle changed.
template <int D, class Criterion, class Builder, bool E, class Region, class SumsOn, class AtFaces>
RemapStats remap_onto_levels(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                             Builder& builder, const RemapParams& params, const Region& region, RemapWorkspace<D>& ws,
                             const LevelGrids<D>& grids, SumsOn&& sums_on, AtFaces&& at_faces, const RankPart& part) {
  const auto fine = ml.finest();
  const CellGrid<D>& grid = grids.local;
  const std::int64_t align = (std::int64_t{1} << ml.max_level) * ml.block_cells;  // finest cells per block and axis
  RemapStats stats;
  stats.summed_cells = grid.n_cells;
  const Sums<D>* S = &sums_on(grid, stats);
  stats.max_volume_mismatch = S->max_mismatch;
  std::array<std::int64_t, D> block0{};
  RankWindows<D> all;  // on many ranks, every rank's window and kept blocks
  if (part.on_ranks()) all = gather_windows(blocks_of(grids.window, align), grids.kept, part);
  std::map<std::array<std::int64_t, D>, int> traded;  // on many ranks, the previous levels of the window's blocks
  const auto field = level0_field(ml, box, grids, *S, part, all, block0, traded);
  const auto level = choose_levels(
      ml, field, block0, part.on_ranks() ? traded : ml.levels(),
      [&](const BlockIndex<D>& b) { return !part.on_ranks() || counts_block_here(all, part.rank, b); }, stats);
  const auto fp = footprint(field, level, grids, ml.max_level, align, fine.spacing);
  Faces faces;
  if (ml.max_level > 0) {
    faces = level_faces(grid, fp);
    S = &at_faces(fp, faces, stats);
  }
  const std::size_t n_cells = fp.size();
  Sums<D> cells;  // each new cell's sums: those of its finest cells
  cells.reset(n_cells, false);
  for (std::size_t f = 0; f < grid.n_cells; ++f) cells.cell[fp.owner[f]] += S->cell[f];
  std::vector<double> cell_volume(n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) cell_volume[c] = std::pow(ml.spacing_at(fp.level[c]), D);
  if (ml.max_level > 0) {
    if constexpr (D == 2)
      remap_face_cells(p, box, fine, builder, grid, region, ws, fp, faces, cells, cell_volume);
    else
      remap_face_cells(p, box, fine, params, grid, fp, faces, cells, cell_volume, part.cells);
  }
  ws.elsewhere.clear();
  if (part.by_owners()) {  // the parts of every rank added at the cells' keepers
    const auto own_reach = std::span<const double>(ws.reach).first(std::min(part.own, ws.reach.size()));
    complete_level_cells(cells, LevelCells<D>{&grids.whole, &grid, &fp}, part, cells_complete(p, own_reach, part),
                         ws.elsewhere);
  }
  emit_on_levels(p, ml, params, grid, grids.kept, fp, field, level, block0, cells, cell_volume, ws, stats, part);
  return stats;
}

}  // namespace detail

/// Remaps `p` onto a multi-level lattice (detail::remap_onto_levels), each old cell handing out its mean by
/// eqs. (6)-(9). Mass, momentum and total energy are conserved exactly as on a uniform lattice. `part`: on many
/// ranks, the old cells built and the reductions; every rank sums on the part of the finest grid its old cells reach
/// and lays out blocks and levels over a window around it (level_grids).
template <int D, class Criterion, class Builder, bool E, class Region = region::Unbounded>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                              Builder& builder, const RemapParams& params, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr, const RankPart& part = {}) {
  ml.validate();
  RemapWorkspace<D> local;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  const auto fine = ml.finest();
  detail::check_remap_input(p, fine, params, part);
  detail::check_whole_blocks(box, ml);
  return detail::remap_onto_levels(
      p, box, ml, builder, params, region, ws, detail::level_grids(p, box, ml, params, part),
      [&](const detail::CellGrid<D>& g, RemapStats&) -> detail::Sums<D>& {
        // remap_face_cells picks the old cells to build again by their reach
        // (and the remap by owners checks that the cells are complete by it)
        return detail::accumulate_overlaps(p, box, fine, builder, params, g, region, ws,
                                           ml.max_level > 0 || part.by_owners(), false, part.cells);
      },
      [&](const auto&, const detail::Faces&, RemapStats&) -> detail::Sums<D>& { return ws.sums[0]; }, part);
}

}  // namespace rsph::regularize
