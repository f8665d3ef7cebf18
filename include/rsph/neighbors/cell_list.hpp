#pragma once
// Uniform cell list over the bounding box of a point set: O(N) build, O(1) candidates per point.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace rsph::neighbors {

template <int D>
class CellList {
 public:
  /// Bins x[0..n) into cubic cells of side >= cell_size; every pair closer than cell_size lies in
  /// adjacent cells.
  void build(const std::vector<Vec<D>>& x, double cell_size) {
    require(cell_size > 0.0 && std::isfinite(cell_size), "cell list: the cell size must be positive and finite");
    const std::size_t n = x.size();
    lo_ = Vec<D>::Constant(std::numeric_limits<double>::max());
    Vec<D> hi = Vec<D>::Constant(std::numeric_limits<double>::lowest());
#pragma omp parallel if (n >= kParallelMin)
    {
      Vec<D> lo_t = lo_, hi_t = hi;
#pragma omp for schedule(static) nowait
      for (std::size_t i = 0; i < n; ++i) {
        lo_t = lo_t.cwiseMin(x[i]);
        hi_t = hi_t.cwiseMax(x[i]);
      }
#pragma omp critical(rsph_cell_list_bounds)
      {
        lo_ = lo_.cwiseMin(lo_t);
        hi = hi.cwiseMax(hi_t);
      }
    }
    if (n == 0) {
      lo_.setZero();
      hi.setZero();
    }
    // Cap the cell count near the particle count so sparse or huge domains stay cheap.
    double size = cell_size;
    for (;;) {
      std::size_t total = 1;
      for (int k = 0; k < D; ++k) {
        // as a double first: an extent of many cells (a far outlier, a degenerate axis) cannot overflow
        const double cells = std::min((hi[k] - lo_[k]) / size + 1.0, static_cast<double>(4 * n + 65));
        dims_[k] = std::max<std::int64_t>(1, static_cast<std::int64_t>(cells));
        total *= static_cast<std::size_t>(dims_[k]);
      }
      if (total <= 4 * n + 64) break;
      size *= 1.5;
    }
    inv_size_ = 1.0 / size;
    std::size_t n_cells = 1;
    for (int k = 0; k < D; ++k) n_cells *= static_cast<std::size_t>(dims_[k]);
    cell_start_.assign(n_cells + 1, 0);
    cell_of_.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::size_t i = 0; i < n; ++i) cell_of_[i] = static_cast<std::uint32_t>(cell_index(coords(x[i])));
    for (std::size_t i = 0; i < n; ++i) ++cell_start_[cell_of_[i] + 1];
    for (std::size_t c = 0; c < n_cells; ++c) cell_start_[c + 1] += cell_start_[c];
    sorted_.resize(n);
    fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) sorted_[fill_[cell_of_[i]]++] = static_cast<std::uint32_t>(i);
    sorted_x_.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::size_t k = 0; k < n; ++k) sorted_x_[k] = x[sorted_[k]];
  }

  /// Calls f(j) for every point j in the cells that meet the square of half-width `radius` around p
  /// (a superset of the points closer than `radius`).
  template <class F>
  void for_each_within(const Vec<D>& p, double radius, F&& f) const {
    for_each_run_within(p, radius, [&](const std::uint32_t* index, const Vec<D>*, std::size_t count) {
      for (std::size_t s = 0; s < count; ++s) f(index[s]);
    });
  }

  /// The candidates of for_each_within as runs: f(index, x, count) for each row of cells along the first
  /// axis, whose points (and their positions, copied in cell order) are contiguous, so a caller may test a
  /// whole run without a branch per point.
  template <class F>
  void for_each_run_within(const Vec<D>& p, double radius, F&& f) const {
    for_each_run_in_box(p - Vec<D>::Constant(radius), p + Vec<D>::Constant(radius), f);
  }

  /// The same runs for the cells that meet the box [box_lo, box_hi].
  template <class F>
  void for_each_run_in_box(const Vec<D>& box_lo, const Vec<D>& box_hi, F&& f) const {
    std::array<std::int64_t, D> lo, hi;
    block_of(box_lo, box_hi, lo, hi);
    std::array<std::int64_t, D> idx = lo;
    const std::size_t row_length = static_cast<std::size_t>(hi[0] - lo[0] + 1);
    for (;;) {
      const std::size_t first = cell_index(idx);
      const std::uint32_t begin = cell_start_[first], end = cell_start_[first + row_length];
      if (end > begin) f(sorted_.data() + begin, sorted_x_.data() + begin, std::size_t{end - begin});
      int k = 1;
      for (; k < D; ++k) {
        if (++idx[k] <= hi[k]) break;
        idx[k] = lo[k];
      }
      if (k >= D) break;
    }
  }

  /// Whether the square of half-width `radius` around p holds every cell, so for_each_within has seen
  /// every point.
  bool covers(const Vec<D>& p, double radius) const {
    for (int k = 0; k < D; ++k)
      if (p[k] - radius > lo_[k] || p[k] + radius < lo_[k] + static_cast<double>(dims_[k]) / inv_size_) return false;
    return true;
  }

  double cell_size() const { return 1.0 / inv_size_; }

  /// The points in cell order: iterating particles this way keeps neighbours close in memory.
  const std::vector<std::uint32_t>& sorted() const { return sorted_; }

 private:
  // The index block of the cells meeting the box [box_lo, box_hi].
  void block_of(const Vec<D>& box_lo, const Vec<D>& box_hi, std::array<std::int64_t, D>& lo,
                std::array<std::int64_t, D>& hi) const {
    for (int k = 0; k < D; ++k) {
      lo[k] = bin_along(k, box_lo[k]);
      hi[k] = bin_along(k, box_hi[k]);
    }
  }

  /// The bin along axis k that coordinate x falls in, clamped to the grid (clamped first as a double, so a far
  /// or non-finite coordinate cannot overflow the integer).
  std::int64_t bin_along(int k, double x) const {
    double at = (x - lo_[k]) * inv_size_;
    at = at > 0.0 ? at : 0.0;  // NaN too: floor_index is then given a number in range
    const double top = static_cast<double>(dims_[k] - 1);
    return floor_index(at < top ? at : top);
  }

  std::array<std::int64_t, D> coords(const Vec<D>& p) const {
    std::array<std::int64_t, D> c;
    for (int k = 0; k < D; ++k) c[k] = bin_along(k, p[k]);
    return c;
  }
  std::size_t cell_index(const std::array<std::int64_t, D>& c) const {
    std::size_t idx = 0;
    for (int k = D - 1; k >= 0; --k) idx = idx * static_cast<std::size_t>(dims_[k]) + static_cast<std::size_t>(c[k]);
    return idx;
  }

  Vec<D> lo_ = Vec<D>::Zero();
  double inv_size_ = 1.0;
  std::array<std::int64_t, D> dims_{};
  std::vector<std::uint32_t> cell_start_, sorted_, fill_;  // fill_: build scratch, kept to reuse its storage
  std::vector<std::uint32_t> cell_of_;                     // cell counts stay below 4 n + 64 (build)
  std::vector<Vec<D>> sorted_x_;                           // positions in cell order
};

}  // namespace rsph::neighbors
