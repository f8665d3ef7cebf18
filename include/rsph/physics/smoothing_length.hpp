#pragma once
// Adaptive smoothing lengths of equal-mass SPH: h_a = eta (m_a / rho_a)^(1/D) solved together with the
// density sum, and the grad-h terms Omega_a that keep the equations exactly conservative
// (Price & Monaghan 2007; Price 2012 eqs. 10-12, 30-35). Without this term h stays as set, which is
// what an RSPH lattice does (eqs. 2-4 of the paper with h_ab = (h_a + h_b) / 2).
#include "rsph/core/errors.hpp"
#include "rsph/kernel/kernel.hpp"

#include <cmath>
#include <string>

namespace rsph::physics {

template <int D>
struct GradH {
  static constexpr bool solves_smoothing_length = true;
  double eta = 1.2;         ///< h = eta (m / rho)^(1/D)
  double tolerance = 1e-6;  ///< relative change of h at which the iteration stops
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

}  // namespace rsph::physics
