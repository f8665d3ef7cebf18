#pragma once
// What a remap sums into every new cell, per thread, and the scratch it keeps from one remap to the next.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/slot_map.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <vector>

namespace rsph::regularize {

namespace detail {

using rsph::SlotMap;

/// Per-thread sums over old particles for the new cells of a grid. Dense: one entry per cell of the grid,
/// indexed by its flat index. Sparse (a grid of many cells per particle: a disk in a box, a particle far out
/// on an open axis): one entry per cell that received something, found by flat index through a SlotMap, and,
/// once reduced, in the order of the flat indices. Either way `size()` entries, entry c being grid cell
/// flat(c), and every cell adds the same shares in the same order.
template <int D>
struct alignas(64) Sums {  // one per thread: aligned so that no two threads write to one cache line
  std::vector<Conserved<D>> cell;
  std::vector<std::size_t> flat_of;  ///< sparse: each entry's grid cell
  SlotMap slot;                      ///< sparse: grid cell -> entry
  bool sparse = false;
  double max_mismatch = 0.0;

  std::size_t size() const { return cell.size(); }
  /// Dense over n grid cells, or sparse and empty.
  void reset(std::size_t n, bool sparse_cells) {
    sparse = sparse_cells;
    cell.assign(sparse ? 0 : n, Conserved<D>{});
    flat_of.clear();
    slot.clear();
    max_mismatch = 0.0;
  }
  /// The entry of grid cell `flat` (a new, empty one where a sparse sum has none yet).
  Conserved<D>& at(std::size_t flat) {
    if (!sparse) return cell[flat];
    const std::uint32_t s = slot.find_or_insert(flat, static_cast<std::uint32_t>(cell.size()));
    if (s == cell.size()) {
      cell.emplace_back();
      flat_of.push_back(flat);
    }
    return cell[s];
  }
  /// Entry c's grid cell, and grid cell f's entry (-1 where a sparse sum has none).
  std::size_t flat(std::size_t c) const { return sparse ? flat_of[c] : c; }
  std::int64_t find(std::size_t f) const { return sparse ? slot.find(f) : static_cast<std::int64_t>(f); }
  /// Makes the entries sparse over the grid cells `flats` (ascending): entry c is cell flats[c].
  void index_by(std::vector<std::size_t> flats) {
    sparse = true;
    flat_of = std::move(flats);
    slot.clear();
    for (std::size_t c = 0; c < flat_of.size(); ++c) slot.find_or_insert(flat_of[c], static_cast<std::uint32_t>(c));
  }
  /// Sorts sparse entries by grid cell, so that they come in lattice order.
  void sort_by_cell() {
    std::vector<std::uint32_t> order(cell.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return flat_of[a] < flat_of[b]; });
    std::vector<Conserved<D>> sorted(cell.size());
    std::vector<std::size_t> flats(cell.size());
    for (std::size_t c = 0; c < order.size(); ++c) {
      sorted[c] = cell[order[c]];
      flats[c] = flat_of[order[c]];
    }
    cell = std::move(sorted);
    index_by(std::move(flats));
  }
  /// Adds old particle (m_o, v_o, e_o) to the cells `idx` with overlaps `omega`; V_o, the sum of the omega
  /// (eq. 7), hands its mass m_o out exactly. `exact_volume` is the cell's own volume, for the log.
  void add(std::span<const Overlap> overlaps, double V_o, double m_o, const Vec<D>& v_o, double e_o,
           double exact_volume) {
    if (!(V_o > 0.0)) throw NumericalError("regularization: an old cell overlaps no new cell");
    max_mismatch = std::max(max_mismatch, std::abs(V_o - exact_volume) / exact_volume);
    const double density = m_o / V_o;
    const double specific_energy = e_o + 0.5 * v_o.squaredNorm();
    auto share = [&](double omega) {
      const double dm = density * omega;                                       // eq. (6)
      return Conserved<D>{dm, Vec<D>(dm * v_o), dm * specific_energy, omega};  // eqs. (8), (9)
    };
    if (sparse)  // decided once per cell, not per overlap: the dense loop stays as tight as before
      for (const auto& [n, omega] : overlaps) at(n) += share(omega);
    else
      for (const auto& [n, omega] : overlaps) cell[n] += share(omega);
  }
  /// Adds o's dense sums of the cells [begin, end); the mismatch is merged by the caller.
  void merge(const Sums& o, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) cell[i] += o.cell[i];
  }
};

/// Whether the remap sums into `n_cells` grid cells for n_old particles sparsely: past
/// `dense_cells_per_particle` cells per particle (counting at least 1 024 particles: small sets sum densely).
inline bool sum_sparsely(std::size_t n_cells, std::size_t n_old, double dense_cells_per_particle) {
  return static_cast<double>(n_cells) >
         dense_cells_per_particle * static_cast<double>(std::max<std::size_t>(n_old, 1024));
}

/// Dense sums over a grid must fit: (3 + D) doubles per cell and thread; refuse a grid that would not, rather
/// than ask for it (the multi-level remap sums on the finest grid densely).
template <int D>
void check_dense_sums_fit(std::size_t n_cells, std::size_t n_old) {
  const double gib = static_cast<double>(n_cells) * static_cast<double>((3 + D) * sizeof(double)) *
                     static_cast<double>(std::max(1, max_threads())) / double(1u << 30);
  require(n_cells < (std::size_t{1} << 31) && gib <= 4.0,
          "regularization: the particles span " + std::to_string(n_cells) + " lattice cells (" + std::to_string(n_old) +
              " particles; the remap's sums would take " + std::to_string(gib) +
              " GiB): a particle far from the rest on an open axis?");
}

/// Clears the per-thread sums, each thread its own (dense over n_cells, or sparse), and, once they are filled,
/// reduces them into the first. Dense: split by cells, each cell still adding the threads' sums in thread
/// order, so the result is the serial reduction's to the bit (on two threads the serial passes over the grid
/// had cost a tenth of the remap). Sparse: thread by thread, in the same order, then sorted by cell.
template <int D>
void clear_sums(std::vector<Sums<D>>& sums, std::size_t n_cells, bool sparse = false) {
  sums.resize(static_cast<std::size_t>(max_threads()));
  rsph::run_parallel(sums.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) sums[t].reset(n_cells, sparse);
  });
}
template <int D>
void reduce_sums(std::vector<Sums<D>>& sums) {
  if (sums[0].sparse) {
    for (std::size_t t = 1; t < sums.size(); ++t)
      for (std::size_t c = 0; c < sums[t].size(); ++c) sums[0].at(sums[t].flat_of[c]) += sums[t].cell[c];
    sums[0].sort_by_cell();
  } else if (sums.size() > 1) {
    rsph::run_parallel(sums[0].size(), [&](int, std::size_t begin, std::size_t end) {
      for (std::size_t t = 1; t < sums.size(); ++t) sums[0].merge(sums[t], begin, end);
    });
  }
  for (std::size_t t = 1; t < sums.size(); ++t)
    sums[0].max_mismatch = std::max(sums[0].max_mismatch, sums[t].max_mismatch);
}

}  // namespace detail

/// Scratch a remap fills and empties: kept by a regularizer from one remap to the next, so that a run
/// does not fault in fresh pages for every regularization (that cost as much as the overlaps).
template <int D>
struct RemapWorkspace {
  std::vector<detail::Sums<D>> sums;  ///< per thread
  std::vector<std::uint8_t> keep;
  /// On many ranks, the remap by owners: the cells another rank keeps, whose sums the hand-on reads.
  std::vector<std::uint8_t> elsewhere;
  std::vector<std::size_t> order;
  std::vector<double> closing;
  /// Distance from each old particle to its cell's farthest vertex, when the overlap pass is asked for it
  /// (the multi-level remap finds the few cells that meet a 2:1 face by it).
  std::vector<double> reach;
};

}  // namespace rsph::regularize
