#pragma once
// Full neighbour lists (both directions) in CSR form, so per-particle loops run in parallel without
// write conflicts. A pair (a, b) is a neighbour pair when |x_a - x_b| < support * h_ab, h_ab = (h_a + h_b)/2.
#include "rsph/core/dimension.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <algorithm>
#include <cstdint>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace rsph::neighbors {

struct NeighborList {
  std::vector<std::uint64_t> offset;  ///< neighbours of a: index[offset[a] .. offset[a+1])
  std::vector<std::uint32_t> index;

  std::size_t count(std::size_t a) const { return offset[a + 1] - offset[a]; }
  std::size_t pairs() const { return index.size(); }
};

/// Interaction radius of the paper's eqs. (2)-(4): support * (h_a + h_b) / 2.
struct MeanH {
  double support;
  double operator()(double ha, double hb) const { return support * 0.5 * (ha + hb); }
};
/// Interaction radius of grad-h SPH, where a and b each see the other with their own h:
/// support * max(h_a, h_b), times a margin for h growing while it is solved.
struct MaxH {
  double support;
  double margin = 1.0;
  double operator()(double ha, double hb) const { return support * margin * std::max(ha, hb); }
};

/// Neighbours of the first n_query points among all of x (ghosts included), found through `cells`:
/// every b != a with |x_a - x_b| < reach(h_a, h_b).
template <int D, class Reach>
void build_neighbor_list(const std::vector<Vec<D>>& x, const std::vector<double>& h, std::size_t n_query,
                         Reach reach_of, const CellList<D>& cells, NeighborList& out) {
  out.offset.assign(n_query + 1, 0);
  int n_threads = 1;
#ifdef _OPENMP
  n_threads = omp_get_max_threads();
#endif
  std::vector<std::vector<std::uint32_t>> local(static_cast<std::size_t>(n_threads));
  std::vector<std::size_t> begin(static_cast<std::size_t>(n_threads) + 1, 0);
  for (int t = 0; t <= n_threads; ++t) begin[static_cast<std::size_t>(t)] = n_query * static_cast<std::size_t>(t) / static_cast<std::size_t>(n_threads);

#pragma omp parallel num_threads(n_threads)
  {
    int t = 0;
#ifdef _OPENMP
    t = omp_get_thread_num();
#endif
    auto& buf = local[static_cast<std::size_t>(t)];
    buf.clear();
    for (std::size_t a = begin[static_cast<std::size_t>(t)]; a < begin[static_cast<std::size_t>(t) + 1]; ++a) {
      const Vec<D> xa = x[a];
      const double ha = h[a];
      std::uint64_t n = 0;
      cells.for_each_candidate(xa, [&](std::uint32_t b) {
        if (b == a) return;
        const double reach = reach_of(ha, h[b]);
        if ((xa - x[b]).squaredNorm() < reach * reach) {
          buf.push_back(b);
          ++n;
        }
      });
      out.offset[a + 1] = n;
    }
  }
  for (std::size_t a = 0; a < n_query; ++a) out.offset[a + 1] += out.offset[a];
  out.index.resize(out.offset[n_query]);
#pragma omp parallel for num_threads(n_threads)
  for (int t = 0; t < n_threads; ++t) {
    const auto& buf = local[static_cast<std::size_t>(t)];
    std::copy(buf.begin(), buf.end(), out.index.begin() + static_cast<std::ptrdiff_t>(out.offset[begin[static_cast<std::size_t>(t)]]));
  }
}

/// O(N^2) oracle: every b with |separation(x_a, x_b)| < reach(h_a, h_b), using minimum images when
/// `box` has periodic axes. Returns (a, b) pairs for a < n_query.
template <int D, class Reach>
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const std::vector<Vec<D>>& x,
                                                                       const std::vector<double>& h,
                                                                       std::size_t n_query, Reach reach_of,
                                                                       const Box<D>& box) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t a = 0; a < n_query; ++a)
    for (std::size_t b = 0; b < x.size(); ++b) {
      if (a == b) continue;
      const double reach = reach_of(h[a], h[b]);
      if (box.separation(x[a], x[b]).squaredNorm() < reach * reach)
        pairs.emplace_back(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
    }
  return pairs;
}

}  // namespace rsph::neighbors
