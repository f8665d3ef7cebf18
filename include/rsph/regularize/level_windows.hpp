#pragma once
// The multi-level lattice on many ranks (multilevel.hpp) with memory that follows a rank's particles: each rank
// lays out blocks, level-0 field and levels over a window around the part of the finest grid its old cells reach,
// wide enough that the 2:1 balance gives every block it needs the level one process gives it, and keeps for the
// next remap the levels of those blocks only. What a window needs from the others (the level-0 sums of the cells
// another rank owns, the levels another rank kept) travels in one sparse exchange between ranks whose windows
// meet.
#include "rsph/core/errors.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/refinement.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <type_traits>
#include <vector>

namespace rsph::regularize::detail {

/// A block's (or a cell's) integer index per axis; not deduced from, so D comes from the other arguments.
template <int D>
using BlockIndex = std::type_identity_t<std::array<std::int64_t, static_cast<std::size_t>(D)>>;

/// Blocks by absolute index, both ends included on every axis.
template <int D>
struct BlockRange {
  std::array<std::int64_t, D> lo{}, hi{};
  bool contains(const BlockIndex<D>& b) const {
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k)
      if (b[k] < lo[k] || b[k] > hi[k]) return false;
    return true;
  }
  bool meets(const BlockRange& o) const {
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k)
      if (o.hi[k] < lo[k] || o.lo[k] > hi[k]) return false;
    return true;
  }
};

/// The blocks of a block-aligned grid (`align` finest cells per block and axis).
template <int D>
BlockRange<D> blocks_of(const CellGrid<D>& g, std::int64_t align) {
  BlockRange<D> r;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    r.lo[k] = g.range.lo[k] / align;  // aligned: exact, negative indices included
    r.hi[k] = (g.range.hi[k] + 1) / align - 1;
  }
  return r;
}

/// `part`, a block-aligned part of `whole`, grown by `blocks` blocks a side and clipped to `whole`.
template <int D>
CellGrid<D> grown_by_blocks(const CellGrid<D>& part, const CellGrid<D>& whole, std::int64_t blocks,
                            std::int64_t align) {
  CellGrid<D> g = part;
  std::size_t cells = 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    g.range.lo[k] = std::max(whole.range.lo[k], part.range.lo[k] - blocks * align);
    g.range.hi[k] = std::min(whole.range.hi[k], part.range.hi[k] + blocks * align);
    g.count[k] = g.range.hi[k] - g.range.lo[k] + 1;
    cells *= static_cast<std::size_t>(g.count[k]);
  }
  g.n_cells = cells;
  return g;
}

/// Every rank's window and kept blocks (what it lays out, and whose levels it keeps), on every rank: 4 D numbers a
/// rank, each filled by its rank and summed over the ranks (exact: integers below 2^53).
template <int D>
struct RankWindows {
  std::vector<BlockRange<D>> window, kept;
};

template <int D>
RankWindows<D> gather_windows(const BlockRange<D>& window, const BlockRange<D>& kept, const RankPart& part) {
  constexpr std::size_t w = 4 * D;
  const auto P = static_cast<std::size_t>(part.ranks);
  std::vector<double> v(w * P, 0.0);
  double* mine = v.data() + w * static_cast<std::size_t>(part.rank);
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    mine[k] = static_cast<double>(window.lo[k]);
    mine[D + k] = static_cast<double>(window.hi[k]);
    mine[2 * D + k] = static_cast<double>(kept.lo[k]);
    mine[3 * D + k] = static_cast<double>(kept.hi[k]);
  }
  part.sum_over_ranks(v);
  RankWindows<D> all;
  all.window.resize(P);
  all.kept.resize(P);
  for (std::size_t r = 0; r < P; ++r)
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      const double* x = v.data() + w * r;
      all.window[r].lo[k] = static_cast<std::int64_t>(x[k]);
      all.window[r].hi[k] = static_cast<std::int64_t>(x[D + k]);
      all.kept[r].lo[k] = static_cast<std::int64_t>(x[2 * D + k]);
      all.kept[r].hi[k] = static_cast<std::int64_t>(x[3 * D + k]);
    }
  return all;
}

/// Whether block b is this rank's to count (the figures summed over the ranks): it is among the blocks this rank
/// keeps and no lower rank keeps it.
template <int D>
bool counts_block_here(const RankWindows<D>& all, int rank, const BlockIndex<D>& b) {
  if (!all.kept[static_cast<std::size_t>(rank)].contains(b)) return false;
  for (int r = 0; r < rank; ++r)
    if (all.kept[static_cast<std::size_t>(r)].contains(b)) return false;
  return true;
}

/// Level-0 cell c's index per axis within `field`'s cells (x fastest).
template <int D>
BlockIndex<D> level0_cell_index(const refine::BlockField<D>& field, std::size_t c) {
  BlockIndex<D> idx;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    const auto n = static_cast<std::size_t>(field.blocks[k] * field.cells_per_block);
    idx[k] = static_cast<std::int64_t>(c % n);
    c /= n;
  }
  return idx;
}

/// What travels: a kind (0: a level-0 cell's mass and volume; 1: a block's kept level), its absolute index per axis,
/// two numbers.
template <int D>
constexpr std::size_t level_record = D + 3;

/// The level-0 field over this rank's window and the blocks' previous levels, from `mine` (the mass and volume of
/// the finest cells whose site this rank owns, laid out over its window, whose first block is block0) and `stored`
/// (the levels this rank kept at the last remap): each rank sends the others whose window meets them its level-0
/// cells and its kept levels, and adds what every rank sent in rank order, its own in its place, so that a cell
/// has the same bits on every rank whose window holds it. `previous` receives the kept levels of the window's
/// blocks (the ranks that keep one agree on it).
template <int D>
refine::BlockField<D> trade_level_inputs(const refine::BlockField<D>& mine, const BlockIndex<D>& block0,
                                         const std::map<BlockIndex<D>, int>& stored, const RankWindows<D>& all,
                                         const RankPart& part, std::map<BlockIndex<D>, int>& previous) {
  constexpr std::size_t w = level_record<D>;
  const auto P = static_cast<std::size_t>(part.ranks);
  const auto me = static_cast<std::size_t>(part.rank);
  const std::int64_t cpb = mine.cells_per_block;
  std::vector<std::size_t> meeting;  // the other ranks whose window meets this one's
  for (std::size_t q = 0; q < P; ++q)
    if (q != me && all.window[q].meets(all.window[me])) meeting.push_back(q);
  std::vector<std::vector<double>> out(P);
  auto record = [&](std::size_t q, double kind, const BlockIndex<D>& idx, double a, double b) {
    auto& o = out[q];
    o.push_back(kind);
    for (const auto i : idx) o.push_back(static_cast<double>(i));  // exact: indices below 2^53
    o.push_back(a);
    o.push_back(b);
  };
  for (std::size_t c = 0; c < mine.mass.size(); ++c) {
    if (mine.volume[c] == 0.0) continue;
    auto idx = level0_cell_index(mine, c);
    BlockIndex<D> block;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      block[k] = block0[k] + idx[k] / cpb;
      idx[k] += block0[k] * cpb;
    }
    for (const std::size_t q : meeting)
      if (all.window[q].contains(block)) record(q, 0.0, idx, mine.mass[c], mine.volume[c]);
  }
  for (const auto& [block, level] : stored) {
    if (all.window[me].contains(block)) previous.emplace(block, level);
    for (const std::size_t q : meeting)
      if (all.window[q].contains(block)) record(q, 1.0, block, static_cast<double>(level), 0.0);
  }
  std::vector<int> counts;
  const auto in = part.exchange(out, &counts);
  auto field = mine;
  std::fill(field.mass.begin(), field.mass.end(), 0.0);
  std::fill(field.volume.begin(), field.volume.end(), 0.0);
  std::size_t at = 0;
  for (std::size_t r = 0; r < P; ++r) {
    const std::size_t end = at + static_cast<std::size_t>(counts[r]);
    if (r == me) {
      for (std::size_t c = 0; c < field.mass.size(); ++c) {
        field.mass[c] += mine.mass[c];
        field.volume[c] += mine.volume[c];
      }
      at = end;  // (the exchange hands a rank's own list back; it sent itself none)
      continue;
    }
    for (; at < end; at += w) {
      const double* x = in.data() + at;
      BlockIndex<D> idx;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) idx[k] = static_cast<std::int64_t>(x[1 + k]);
      if (x[0] == 1.0) {
        previous.emplace(idx, static_cast<int>(x[1 + D]));
        continue;
      }
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) idx[k] -= block0[k] * cpb;
      const auto c = static_cast<std::size_t>(field.cell(idx));
      field.mass[c] += x[1 + D];
      field.volume[c] += x[2 + D];
    }
  }
  return field;
}

}  // namespace rsph::regularize::detail
