#pragma once
// Adaptive smoothing lengths of equal-mass SPH: h_a = eta (m_a / rho_a)^(1/D) solved together with the
// density sum, and the grad-h terms Omega_a that keep the equations exactly conservative
// (Price & Monaghan 2007; Price 2012 eqs. 10-12, 30-35). Without this term h stays as set, which is
// what an RSPH lattice does (eqs. 2-4 of the paper with h_ab = (h_a + h_b) / 2).
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/neighbor_list.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace rsph::physics {

template <int D>
struct GradH {
  static constexpr bool solves_smoothing_length = true;
  static constexpr int dim = D;  ///< h = eta (m / rho)^(1/D) holds in this dimension only
  double eta = 1.2;              ///< h = eta (m / rho)^(1/D)
  double tolerance = 1e-6;       ///< relative change of h at which the iteration stops
  int max_iterations = 50;

  void validate() const {
    require(eta > 0.0, "adaptive smoothing length: eta (h/dx) must be positive (got " + std::to_string(eta) + ")");
    require(tolerance > 0.0, "adaptive smoothing length: tolerance must be positive");
  }

  /// rho_h(h) = m (eta / h)^D: the density that h stands for (Price 2012 eq. 10).
  double rho_of_h(double m, double h) const { return m * kernel::pow_dim<D>(eta / h); }
  /// h(rho) = eta (m / rho)^(1/D).
  double h_of_rho(double m, double rho) const {
    const double vol = m / rho;
    if constexpr (D == 1)
      return eta * vol;
    else if constexpr (D == 2)
      return eta * std::sqrt(vol);
    else
      return eta * std::cbrt(vol);
  }
};

/// dW/dh at fixed r: -sigma / h^(D+1) (D f(q) + q f'(q)) (Price 2012 eq. 12).
template <class K, int D>
inline double dW_dh(double r, double h) {
  const double q = r / h;
  return -K::template sigma<D>() / (kernel::pow_dim<D>(h) * h) * (D * K::f(q) + q * K::df(q));
}

/// Omega_a = 1 - (dh_a/drho_a) sum_b m_b dW_ab(h_a)/dh_a, with dh/drho = -h / (D rho) (Price 2012 eq. 31).
template <int D>
inline double omega(double h, double rho, double sum_m_dW_dh) {
  return 1.0 + h / (D * rho) * sum_m_dW_dh;
}

/// What the grad-h solve keeps between passes: Omega of every point (real and ghosts).
struct GradHWorkspace {
  std::vector<double> Omega;
};

/// Newton-Raphson on rho_sum(h) - rho_h(h) = 0 per particle (Price 2012 §3.1), bisection-guarded, over
/// neighbour lists searched out to `margin` h; sets h, rho and Omega (ghosts: 1 until the pressure pass
/// copies their sources'). Returns false when some h outgrew the search margin.
template <class Kernel, int D, class Solver, class P>
bool solve_density_and_h(const Solver& solver, P& p, const neighbors::NeighborList& nl, double margin,
                         GradHWorkspace& ws) {
  const std::size_t n = p.n_real;
  ws.Omega.assign(p.size_with_ghosts(), 1.0);
  bool fits = true;
#pragma omp parallel reduction(&& : fits) if (n >= kParallelMin)
  {
    std::vector<std::pair<double, double>> r_m;  // (r_ab, m_b) of the candidates, computed once per particle
#pragma omp for schedule(dynamic, kRowChunk)
    for (std::size_t a = 0; a < n; ++a) {
      const double m_a = p.m[a];
      const double h_search = p.h[a] * margin;
      r_m.clear();
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
        const std::uint32_t b = nl.index[k];
        r_m.emplace_back((p.x[a] - p.x[b]).norm(), p.m[b]);
      }
      double h = p.h[a], lo = 0.0, hi = h_search;
      double rho = 0.0, sum_dW_dh = 0.0;
      for (int it = 0; it < solver.max_iterations; ++it) {
        rho = m_a * kernel::W<Kernel, D>(0.0, h);
        sum_dW_dh = m_a * dW_dh<Kernel, D>(0.0, h);
        const double r_max = Kernel::support * h;
        for (const auto& [r, m_b] : r_m) {
          if (r >= r_max) continue;
          rho += m_b * kernel::W<Kernel, D>(r, h);
          sum_dW_dh += m_b * dW_dh<Kernel, D>(r, h);
        }
        const double rho_h = solver.rho_of_h(m_a, h);
        const double f = rho - rho_h;
        if (std::abs(f) <= solver.tolerance * rho_h) break;
        if (f > 0.0)
          hi = h;
        else
          lo = h;  // f rises with h: rho_h falls as h^-D
        const double df = sum_dW_dh + D * rho_h / h;
        double next = df != 0.0 ? h - f / df : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        h = next;
      }
      p.h[a] = h;
      p.rho[a] = rho;
      ws.Omega[a] = omega<D>(h, rho, sum_dW_dh);
      if (h >= h_search * (1.0 - 1e-12)) fits = false;
    }
  }
  return fits;
}

}  // namespace rsph::physics
