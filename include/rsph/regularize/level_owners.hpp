#pragma once
// The multi-level remap by owners (multilevel.hpp on many ranks): each rank builds the old cells of its own
// particles only, so its sums on the finest cells, and on the new cells made of them, are its part of the whole
// set's. The parts add up: the level-0 field takes them as they are (level_windows.hpp adds them over the ranks),
// and each new cell's parts travel to the rank that keeps it (owner_sums.hpp). What is particular to the levels is
// how the ranks name a new cell (by its first finest cell on the whole set's grid) and who its neighbours are (the
// cells in the one-cell ring of finest cells around its footprint).
#include "rsph/core/errors.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/multilevel_lattice.hpp"
#include "rsph/regularize/owner_sums.hpp"
#include "rsph/regularize/remap_params.hpp"
#include "rsph/regularize/sums.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace rsph::regularize::detail {

/// f(o) for the owners o of the finest cells in the one-cell ring around c's footprint (repeats possible).
template <int D, class F>
void for_each_ring_neighbour(const CellGrid<D>& grid, const Footprint<D>& fp, std::size_t c, F&& f) {
  const std::int64_t s = fp.span[c];
  std::array<std::int64_t, D> off;
  off.fill(-1);
  std::uint32_t last = static_cast<std::uint32_t>(c);
  do {
    bool ring = false;
    std::array<std::int64_t, D> g;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      ring = ring || off[k] < 0 || off[k] >= s;
      g[k] = grid.range.lo[k] + fp.first_fine[c][k] + off[k];
    }
    if (ring) {
      const std::int64_t fl = grid.flat(g);
      if (fl >= 0) {
        const std::uint32_t o = fp.owner[static_cast<std::size_t>(fl)];
        if (o != c && o != last) f(static_cast<std::size_t>(o));  // repeats only cost a comparison
        last = o;
      }
    }
  } while (next_index<D>(off, -1, s + 1));
}

/// Level-0 cells a rank lays its footprint out beyond the reach of its own old cells in the remap by owners: the
/// new cells within two rings of those it keeps (the hand-on reads them) and, for the face cells among them, the
/// sites within two spans that cut their Voronoi cells (level_faces.hpp). A span is at most one level-0 cell.
inline constexpr int level0_cells_beyond_own = 4;

/// The new cells of a multi-level lattice as the ranks name them: by the flat index of their first finest cell on
/// the whole set's grid `whole`, which every rank lays out alike. `grid`: the part of it this rank's footprint `fp`
/// covers. The interface of GridCells (owner_sums.hpp), for complete_on_owners.
template <int D>
struct LevelCells {
  const CellGrid<D>* whole;
  const CellGrid<D>* grid;
  const Footprint<D>* fp;

  std::size_t size() const { return whole->n_cells; }
  /// The name of footprint cell c.
  std::int64_t whole_flat(std::size_t c) const {
    std::array<std::int64_t, D> g;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) g[k] = grid->range.lo[k] + fp->first_fine[c][k];
    return whole->flat(g);
  }
  /// The footprint cell named f; a rank asks only of cells near its own gas, which its footprint covers.
  std::size_t cell(std::size_t f) const {
    const std::int64_t fl = grid->flat(whole->unflat(f));
    require(fl >= 0, "multi-level remap: a new cell near this rank's gas lies beyond its footprint");
    return fp->owner[static_cast<std::size_t>(fl)];
  }
  Vec<D> site(std::size_t f) const { return fp->site(cell(f)); }
  /// g(name) for the cells within `layers` rings of the cell named f, f left out: the ring neighbours, then theirs.
  template <class G>
  void for_each_within(std::size_t f, int layers, G&& g) const {
    std::vector<std::size_t> seen{cell(f)}, front = seen, next;
    for (int layer = 0; layer < layers; ++layer) {
      next.clear();
      for (const std::size_t c : front)
        for_each_ring_neighbour(*grid, *fp, c, [&](std::size_t o) {
          if (std::find(seen.begin(), seen.end(), o) != seen.end()) return;
          seen.push_back(o);
          next.push_back(o);
          g(static_cast<std::size_t>(whole_flat(o)));
        });
      std::swap(front, next);
    }
  }
};

/// The remap by owners' end on levels: `cells`, this rank's parts of the sums of its footprint's new cells (in
/// footprint order), replaced by the complete sums of the cells it keeps and of those within two rings that other
/// ranks keep (flagged in `elsewhere`, with every cell it has no sums for, which stay empty). The hand-on then reads
/// what one process reads around a kept cell, in the same order. `complete`: whether this rank's old cells are
/// (cells_complete); raises HaloTooNarrow on every rank where a rank's cells or keepers lie beyond what it gathered.
template <int D>
void complete_level_cells(Sums<D>& cells, const LevelCells<D>& named, const RankPart& part, bool complete,
                          std::vector<std::uint8_t>& elsewhere) {
  std::vector<std::uint8_t> kept_elsewhere;
  const Sums<D> kept = complete_on_owners(numbered_for_ranks(cells, named), named, part, complete, kept_elsewhere);
  const double mismatch = cells.max_mismatch;
  cells.reset(cells.size(), false);
  cells.max_mismatch = mismatch;
  elsewhere.assign(cells.size(), 1);
  for (std::size_t e = 0; e < kept.size(); ++e) {
    const std::size_t c = named.cell(kept.flat(e));
    cells.cell[c] = kept.cell[e];
    elsewhere[c] = kept_elsewhere[e];
  }
}

}  // namespace rsph::regularize::detail
