#pragma once
// The density pass: eq. (2) summed over neighbour lists, and n_a of eq. (A1) for a schedule that asks.
// The pair physics it sums is physics::density_term (hydro.hpp); this is only the loop.
#include "rsph/core/parallel.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/physics/hydro.hpp"

#include <cstdint>
#include <type_traits>
#include <vector>

namespace rsph::physics::loops {

/// n_a = sum_{b != a} W_ab of eq. (A1), and W_ab of each neighbour-list entry as the pass summed it.
struct NumberDensity {
  std::vector<double> n;
  std::vector<double> pair_kernel;
  bool pair_kernel_full = false;  ///< whether the last pass (over every particle) filled pair_kernel
};

/// The density sum (eq. 2) for the points of `rows` (row i of the neighbour lists is point rows[i]).
/// write_rho: store it (not so with consistent gradients, whose density follows the continuity equation).
/// with_number_density: also n_a into nd, and W_ab when the pass covers every particle.
template <class Kernel, int D, bool write_rho, bool with_number_density, class P, class Rows>
void density_rows(P& p, const neighbors::NeighborList& nl, const Rows& rows, NumberDensity& nd) {
  const auto& x = p.x;
  const auto& h = p.h;
  const auto& m = p.m;
  const std::size_t n_rows = rows.size();
  // The kernel values are kept only from a pass over every particle, the one a schedule looks at.
  constexpr bool keep_pair_kernel = with_number_density && std::is_same_v<Rows, neighbors::FirstN>;
  if constexpr (with_number_density) nd.n.resize(p.n_real);
  if constexpr (keep_pair_kernel) nd.pair_kernel.resize(nl.pairs());
  nd.pair_kernel_full = keep_pair_kernel;  // a subset pass leaves the kept values stale
#pragma omp parallel for schedule(dynamic, kRowChunk) if (n_rows >= kParallelMin)
  for (std::size_t i = 0; i < n_rows; ++i) {
    const std::uint32_t a = rows[i];
    const double h_a = h[a], inv_h_a = 1.0 / h_a;
    double rho = m[a] * kernel::W_inv_h<Kernel, D>(0.0, inv_h_a);
    double n_a = 0.0;
    for (auto k = nl.offset[i]; k < nl.offset[i + 1]; ++k) {
      const std::uint32_t b = nl.index[k];
      const double r = (x[a] - x[b]).norm();
      const double W_ab = kernel::W_inv_h<Kernel, D>(r, kernel::inv_h_ab(h_a, inv_h_a, h[b]));
      rho += physics::density_term(m[b], W_ab);
      if constexpr (with_number_density) {  // eq. (A1), for the regularization schedule
        n_a += W_ab;
        if constexpr (keep_pair_kernel) nd.pair_kernel[k] = W_ab;
      }
    }
    if constexpr (write_rho) p.rho[a] = rho;
    if constexpr (with_number_density) nd.n[a] = n_a;
  }
}

}  // namespace rsph::physics::loops
