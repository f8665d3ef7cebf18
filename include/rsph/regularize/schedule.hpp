#pragma once
// When to regularize: every c_r steps, every T_reg of simulated time, or adaptively (Appendix A).
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/kernel/lattice_sum.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/regularize/concept.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace rsph::schedule {

/// Every c_r steps (the paper's §3.3 and §4).
struct EveryNSteps {
  std::uint64_t steps = 40;
  void validate() const { require(steps >= 1, "regularization schedule: the step count must be at least 1"); }
  template <class P, class B>
  bool due(const P&, const B&, const StepInfo& s) {
    return s.steps_since_last >= steps;
  }
};

/// Every T_reg of simulated time (§2.1, §3.1); the simulation shortens the step that would pass it.
struct EveryT {
  double period = 1.0;
  void validate() const { require(period > 0.0, "regularization schedule: the period T_reg must be positive"); }
  template <class P, class B>
  bool due(const P&, const B&, const StepInfo& s) {
    return s.time_since_last >= period * (1.0 - 1e-12);
  }
  double time_until_due(const StepInfo& s) const { return period - s.time_since_last; }
};

/// Appendix A: regularize when the estimated neighbour number N_a (eqs. A1-A2) leaves [N_min, N_max]
/// or its local spread delta N_a (eqs. A3-A4) exceeds delta N_max, or after max_steps steps.
template <class Kernel, int D>
struct Adaptive {
  static constexpr bool wants_number_density = true;
  double N_min = 9.5;
  double N_max = 308.0;
  double dN_max = 0.4;
  std::uint64_t max_steps = 128;

  Adaptive() = default;
  Adaptive(double n_min, double n_max, double dn_max, std::uint64_t steps_cap)
      : N_min(n_min), N_max(n_max), dN_max(dn_max), max_steps(steps_cap) {}

  /// Why the last check fired (for logs): 0 none, 1 N below N_min, 2 above N_max, 3 spread, 4 step cap.
  int last_reason = 0;

  void validate() const {
    require(N_min > 0.0 && N_max > N_min, "adaptive regularization: need 0 < N_min < N_max");
    require(dN_max > 0.0, "adaptive regularization: delta N_max must be positive");
    require(max_steps >= 1, "adaptive regularization: the maximum step count must be at least 1");
  }

  /// V(h): the interaction volume of eq. (A2), the kernel's support disc (rod, ball).
  static double interaction_volume(double h) {
    const double R = Kernel::support * h;
    if constexpr (D == 1)
      return 2.0 * R;
    else if constexpr (D == 2)
      return std::numbers::pi * R * R;
    else
      return 4.0 / 3.0 * std::numbers::pi * R * R * R;
  }

  /// N_a of eq. (A2) on a regular Cartesian lattice (square, cubic) at the given h/Delta: V(h) / Delta^D times
  /// the lattice sum of W without the particle itself (eq. A1). In 2D it gives the paper's pairs: 9.5 at h/Delta
  /// = 1.1, 308 at 5.0 (§3.2), 4.5 at 0.9 and 107 at 3.0 (§5); in 3D the same h/Delta give other numbers.
  static double lattice_neighbour_number(double h_over_dx) {
    const double self = kernel::W<Kernel, D>(0.0, h_over_dx);  // Delta = 1
    return interaction_volume(h_over_dx) * (kernel::lattice_sum<Kernel, D>(h_over_dx) - self);
  }
  /// The schedule whose bounds are the neighbour numbers of a lattice at h/Delta = h_min and h_max: Appendix A
  /// in any dimension from the paper's h/Delta.
  static Adaptive for_h_over_dx(double h_min, double h_max, double dn_max, std::uint64_t steps_cap) {
    require(h_min > 0.0 && h_max > h_min, "adaptive regularization: need 0 < h/Delta min < h/Delta max");
    return Adaptive(lattice_neighbour_number(h_min), lattice_neighbour_number(h_max), dn_max, steps_cap);
  }

  /// N_a of eq. (A2) for the real particles, from the current neighbour lists.
  template <bool E>
  std::vector<double> neighbour_numbers(const ParticleSet<D, E>& p, const neighbors::NeighborList& nl) const {
    std::vector<double> N(p.n_real);
    const std::size_t n = p.n_real;
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::size_t a = 0; a < n; ++a) {
      double n_a = 0.0;  // eq. (A1): the particle itself left out
      const double h_a = p.h[a], inv_h_a = 1.0 / h_a;
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
        const std::uint32_t b = nl.index[k];
        n_a += kernel::W_inv_h<Kernel, D>((p.x[a] - p.x[b]).norm(), kernel::inv_h_ab(h_a, inv_h_a, p.h[b]));
      }
      N[a] = interaction_volume(p.h[a]) * n_a;
    }
    return N;
  }

  template <bool E>
  bool due(const ParticleSet<D, E>& p, const Box<D>&, const StepInfo& s) {
    last_reason = 0;
    if (s.steps_since_last >= max_steps) return (last_reason = 4), true;
    if (!s.neighbors) return false;
    const auto& nl = *s.neighbors;
    auto& N = N_;
    if (!s.number_density.empty()) {  // eq. (A1) summed by the driver's density pass
      N.resize(p.n_real);
      const auto n_a = s.number_density;
#pragma omp parallel for schedule(static) if (p.n_real >= kParallelMin)
      for (std::size_t a = 0; a < p.n_real; ++a) N[a] = interaction_volume(p.h[a]) * n_a[a];
    } else {
      N = neighbour_numbers(p, nl);
    }
    if (s.refresh_halos) {  // other ranks' particles among the neighbours: their N from their ranks
      N.resize(p.size_with_ghosts());
      s.refresh_halos(N);
    }
    // m_b / rho_b N_b of every point, ghosts taking their source's N
    auto& volume_N = volume_N_;
    volume_N.resize(p.size_with_ghosts());
#pragma omp parallel for schedule(static) if (p.size_with_ghosts() >= kParallelMin)
    for (std::size_t b = 0; b < p.size_with_ghosts(); ++b)
      volume_N[b] = p.m[b] / p.rho[b] * N[b < p.n_real ? b : p.ghost_source[b - p.n_real]];
    // Which condition particle a violates (0: none).
    auto reason = [&](std::size_t a) {
      if (N[a] < N_min) return 1;  // eq. (A5)
      if (N[a] > N_max) return 2;
      // eq. (A4): <N>_a = sum_b m_b / rho_b N_b W_ab, the particle itself included
      double mean = p.m[a] / p.rho[a] * N[a] * kernel::W<Kernel, D>(0.0, p.h[a]);
      if (!s.pair_kernel.empty()) {
        const auto W = s.pair_kernel;
        for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) mean += volume_N[nl.index[k]] * W[k];
      } else {
        const double h_a = p.h[a], inv_h_a = 1.0 / h_a;
        for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
          const std::uint32_t b = nl.index[k];
          mean += volume_N[b] *
                  kernel::W_inv_h<Kernel, D>((p.x[a] - p.x[b]).norm(), kernel::inv_h_ab(h_a, inv_h_a, p.h[b]));
        }
      }
      const double dN = (N[a] - mean) / N[a];  // eq. (A3)
      return std::abs(dN) > dN_max ? 3 : 0;    // eq. (A6)
    };
    // The first particle in index order that fires, whatever the thread count.
    const std::size_t n = p.n_real;
    std::size_t first = n;
#pragma omp parallel for schedule(static) reduction(min : first) if (n >= kParallelMin)
    for (std::size_t a = 0; a < n; ++a)
      if (a < first && reason(a) != 0) first = a;
    if (first == n) return false;
    last_reason = reason(first);
    return true;
  }

  std::vector<double> N_, volume_N_;  ///< scratch, kept between checks to reuse its storage
};

}  // namespace rsph::schedule
