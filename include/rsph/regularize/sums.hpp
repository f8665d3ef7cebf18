#pragma once
// What a remap sums into every new cell, per thread, and the scratch it keeps from one remap to the next.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph::regularize {

namespace detail {

/// Per-thread sums over old particles for each new cell of a dense index grid.
template <int D>
struct alignas(64) Sums {  // one per thread: aligned so that no two threads write to one cache line
  std::vector<Conserved<D>> cell;
  double max_mismatch = 0.0;

  std::size_t size() const { return cell.size(); }
  void resize(std::size_t n) {
    cell.assign(n, Conserved<D>{});
    max_mismatch = 0.0;
  }
  /// Adds old particle (m_o, v_o, e_o) to the cells `idx` with overlaps `omega`; V_o, the sum of the omega
  /// (eq. 7), hands its mass m_o out exactly. `exact_volume` is the cell's own volume, for the log.
  void add(std::span<const Overlap> overlaps, double V_o, double m_o, const Vec<D>& v_o, double e_o,
           double exact_volume) {
    if (!(V_o > 0.0)) throw NumericalError("regularization: an old cell overlaps no new cell");
    max_mismatch = std::max(max_mismatch, std::abs(V_o - exact_volume) / exact_volume);
    const double density = m_o / V_o;
    const double specific_energy = e_o + 0.5 * v_o.squaredNorm();
    for (const auto& [n, omega] : overlaps) {
      const double dm = density * omega;                                           // eq. (6)
      cell[n] += Conserved<D>{dm, Vec<D>(dm * v_o), dm * specific_energy, omega};  // eqs. (8), (9)
    }
  }
  /// Adds o's sums of the cells [begin, end); the mismatch is merged by the caller.
  void merge(const Sums& o, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) cell[i] += o.cell[i];
  }
};

/// Zeroes the per-thread sums, each thread its own, and, once they are filled, reduces them into the first,
/// split by cells: each cell still adds the threads' sums in thread order, so the result is the serial
/// reduction's to the bit. On two threads the serial passes over the grid had cost a tenth of the remap.
template <int D>
void clear_sums(std::vector<Sums<D>>& sums, std::size_t n_cells) {
  sums.resize(static_cast<std::size_t>(max_threads()));
  rsph::run_parallel(sums.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) sums[t].resize(n_cells);
  });
}
template <int D>
void reduce_sums(std::vector<Sums<D>>& sums) {
  if (sums.size() < 2) return;
  rsph::run_parallel(sums[0].size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = 1; t < sums.size(); ++t) sums[0].merge(sums[t], begin, end);
  });
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
  std::vector<std::size_t> order;
  std::vector<double> closing;
  /// Distance from each old particle to its cell's farthest vertex, when the overlap pass is asked for it
  /// (the multi-level remap finds the few cells that meet a 2:1 face by it).
  std::vector<double> reach;
};

}  // namespace rsph::regularize
