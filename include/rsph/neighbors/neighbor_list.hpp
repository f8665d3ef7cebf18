#pragma once
// Full neighbour lists (both directions) in CSR form, so per-particle loops run in parallel without
// write conflicts. A pair (a, b) is a neighbour pair when |x_a - x_b| < support * h_ab, h_ab = (h_a + h_b)/2.
#include "rsph/core/dimension.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace rsph::neighbors {

struct NeighborList {
  std::vector<std::uint64_t> offset;  ///< neighbours of a: index[offset[a] .. offset[a+1])
  std::vector<std::uint32_t> index;
  /// Per-thread gather buffers, kept between builds so that a list rebuilt every step reuses its pages.
  struct alignas(64) Buffers {
    std::vector<std::uint32_t> gathered;  ///< sized generously and never shrunk: growing a vector zero-fills
    std::size_t n_gathered = 0;           ///< the entries of `gathered` the last build wrote
    std::vector<std::pair<std::uint32_t, std::uint32_t>> scattered;  ///< (row of a, b) from b's side
  };
  std::vector<Buffers> buffers;

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

/// Rows of a neighbour list: the first n points, in order (every real particle).
struct FirstN {
  std::size_t n = 0;
  std::size_t size() const { return n; }
  std::uint32_t operator[](std::size_t i) const { return static_cast<std::uint32_t>(i); }
  std::int64_t row_of(std::size_t a) const { return a < n ? static_cast<std::int64_t>(a) : -1; }
};

/// Rows of a neighbour list: a subset of the points (the active ones of individual time steps);
/// `row[a]` is a's row or -1, sized for all points.
struct Subset {
  const std::vector<std::uint32_t>* index = nullptr;
  const std::vector<std::int32_t>* row = nullptr;
  std::size_t size() const { return index->size(); }
  std::uint32_t operator[](std::size_t i) const { return (*index)[i]; }
  std::int64_t row_of(std::size_t a) const { return a < row->size() ? (*row)[a] : -1; }
};

namespace detail {

/// Rows [begin, end) gathered into buf from `used` on: each a sees the b within its own radius. Row i's
/// count lands in offset[i + 1]; returns where the thread's writing ends.
template <int D, class Rows, class Reach>
std::size_t gather_rows(const std::vector<Vec<D>>& x, const std::vector<double>& h, const Rows& rows, Reach reach_of,
                        const CellList<D>& cells, std::size_t begin, std::size_t end, std::vector<std::uint32_t>& buf,
                        std::vector<std::uint64_t>& offset) {
  std::size_t used = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const std::uint32_t a = rows[i];
    const Vec<D> xa = x[a];
    const double ha = h[a];
    const double own = reach_of(ha, ha);
    const double own2 = own * own;
    const std::size_t start = used;
    cells.for_each_run_within(xa, own, [&](const std::uint32_t* index, const Vec<D>* at, std::size_t count) {
      if (buf.size() < used + count) buf.resize(std::max(2 * buf.size(), used + count));
      std::uint32_t* kept = buf.data();
      // Without a branch: whether a candidate lies inside is a coin toss no predictor learns.
      for (std::size_t s = 0; s < count; ++s) {
        kept[used] = index[s];
        used += static_cast<std::size_t>(((xa - at[s]).squaredNorm() < own2) & (index[s] != a));
      }
    });
    // A b with a smaller radius may see a at a shorter reach than a's own (never on one lattice).
    std::size_t kept_end = start;
    for (std::size_t k = start; k < used; ++k) {
      const std::uint32_t b = buf[k];
      const double reach = reach_of(ha, h[b]);
      if (reach < own && (xa - x[b]).squaredNorm() >= reach * reach) continue;
      buf[kept_end++] = b;
    }
    used = kept_end;
    offset[i + 1] = used - start;
  }
  return used;
}

/// Points [begin, end) with a radius larger than own_min find the query points a that did not reach them:
/// (row, b) pairs into ext.
template <int D, class Rows, class Reach>
void scatter_points(const std::vector<Vec<D>>& x, const std::vector<double>& h, const Rows& rows, Reach reach_of,
                    const CellList<D>& cells, std::size_t begin, std::size_t end, double own_min,
                    std::vector<std::pair<std::uint32_t, std::uint32_t>>& ext) {
  for (std::size_t b = begin; b < end; ++b) {
    const Vec<D> xb = x[b];
    const double hb = h[b];
    const double own_b = reach_of(hb, hb);
    if (own_b <= own_min) continue;
    cells.for_each_within(xb, own_b, [&](std::uint32_t a) {
      const std::int64_t row = rows.row_of(a);
      if (row < 0 || a == b) return;
      const double own_a = reach_of(h[a], h[a]);
      if (own_a >= own_b) return;  // a's own gather covers this pair
      const double reach = reach_of(h[a], hb);
      const double r2 = (x[a] - xb).squaredNorm();
      if (r2 < reach * reach && r2 >= own_a * own_a)
        ext.emplace_back(static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(b));
    });
  }
}

/// The scattered pairs merged in: counts first, then each row's gathered list followed by its extras.
inline void merge_scattered(NeighborList& out, std::size_t n_rows) {
  std::vector<std::uint64_t> gathered(n_rows);
  for (std::size_t i = 0; i < n_rows; ++i) gathered[i] = out.offset[i + 1];
  std::vector<std::uint64_t> gathered_start(n_rows + 1, 0);
  for (std::size_t i = 0; i < n_rows; ++i) gathered_start[i + 1] = gathered_start[i] + gathered[i];
  std::vector<std::uint64_t> extra_count(n_rows, 0);
  for (const auto& b : out.buffers)
    for (const auto& pr : b.scattered) ++extra_count[pr.first];
  out.offset[0] = 0;
  for (std::size_t i = 0; i < n_rows; ++i) out.offset[i + 1] = out.offset[i] + gathered[i] + extra_count[i];
  out.index.resize(out.offset[n_rows]);
  std::vector<std::uint32_t> all_gathered;
  all_gathered.reserve(gathered_start[n_rows]);
  for (const auto& b : out.buffers)
    all_gathered.insert(all_gathered.end(), b.gathered.begin(),
                        b.gathered.begin() + static_cast<std::ptrdiff_t>(b.n_gathered));
  std::vector<std::uint64_t> fill(n_rows);
  for (std::size_t i = 0; i < n_rows; ++i) {
    std::copy(all_gathered.begin() + static_cast<std::ptrdiff_t>(gathered_start[i]),
              all_gathered.begin() + static_cast<std::ptrdiff_t>(gathered_start[i + 1]),
              out.index.begin() + static_cast<std::ptrdiff_t>(out.offset[i]));
    fill[i] = out.offset[i] + gathered[i];
  }
  for (const auto& b : out.buffers)
    for (const auto& pr : b.scattered) out.index[fill[pr.first]++] = pr.second;
}

}  // namespace detail

/// Neighbours of the query points `rows` among all of x (ghosts included): every b != a with
/// |x_a - x_b| < reach(h_a, h_b), row i of `out` holding those of point rows[i]. Works for any spread of
/// h: each point a gathers within its own radius reach(h_a, h_a); a point b with a larger radius scatters
/// itself onto the a's that could not see it. `cells` must be built over all of x; its cell size may be
/// smaller than the largest radius.
template <int D, class Rows, class Reach>
void build_neighbor_list(const std::vector<Vec<D>>& x, const std::vector<double>& h, const Rows& rows, Reach reach_of,
                         const CellList<D>& cells, NeighborList& out) {
  const std::size_t n_rows = rows.size();
  out.offset.assign(n_rows + 1, 0);
  int n_threads = 1;
#ifdef _OPENMP
  if (n_rows >= kParallelMin) n_threads = omp_get_max_threads();
#endif
  const std::size_t T = static_cast<std::size_t>(n_threads);
  out.buffers.resize(T);
  const std::size_t n_all = x.size();
  auto chunk = [](std::size_t n, std::size_t t, std::size_t parts) { return n * t / parts; };
  // A point whose radius no query point falls short of has nothing to scatter: with one h for all
  // (an RSPH lattice) the scatter pass costs one comparison per point.
  const double own_min = [&] {  // a value, not a variable the parallel region shares, so it stays in a register
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n_rows; ++i) least = std::min(least, reach_of(h[rows[i]], h[rows[i]]));
    return least;
  }();
  std::size_t n_extra = 0;
#pragma omp parallel num_threads(n_threads)
  {
    std::size_t t = 0;
#ifdef _OPENMP
    t = static_cast<std::size_t>(omp_get_thread_num());
#endif
    auto& buf = out.buffers[t].gathered;
    auto& ext = out.buffers[t].scattered;
    ext.clear();
    const std::size_t used =
        detail::gather_rows(x, h, rows, reach_of, cells, chunk(n_rows, t, T), chunk(n_rows, t + 1, T), buf, out.offset);
    out.buffers[t].n_gathered = used;
    detail::scatter_points(x, h, rows, reach_of, cells, chunk(n_all, t, T), chunk(n_all, t + 1, T), own_min, ext);
#pragma omp barrier
#pragma omp single
    {
      for (const auto& b : out.buffers) n_extra += b.scattered.size();
      if (n_extra == 0) {
        for (std::size_t i = 0; i < n_rows; ++i) out.offset[i + 1] += out.offset[i];
        out.index.resize(out.offset[n_rows]);
      }
    }
    // Without scattered pairs each thread's rows are a contiguous run of the index: copy in parallel.
    if (n_extra == 0)
      std::copy(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(used),
                out.index.begin() + static_cast<std::ptrdiff_t>(out.offset[chunk(n_rows, t, T)]));
  }
  if (n_extra > 0) detail::merge_scattered(out, n_rows);
}

/// Neighbours of the first n_query points (row a holds point a's).
template <int D, class Reach>
void build_neighbor_list(const std::vector<Vec<D>>& x, const std::vector<double>& h, std::size_t n_query,
                         Reach reach_of, const CellList<D>& cells, NeighborList& out) {
  build_neighbor_list<D>(x, h, FirstN{n_query}, reach_of, cells, out);
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
