#pragma once
#include "rsph/core/errors.hpp"
#include "rsph/physics/pair.hpp"

#include <cmath>
#include <string>

namespace rsph::physics {

/// Artificial conductivity of Price (2008), eq. 28 there:
///   du_a/dt += sum_b m_b alpha_u v_sig^u (u_a - u_b) / rho_ab  r_hat_ab . nabla_a W_ab,
/// with v_sig^u = sqrt(|P_a - P_b| / rho_ab) (Price 2008 eq. 30) and rho_ab = (rho_a + rho_b) / 2.
/// Antisymmetric in a and b, so sum_a m_a du_a/dt gains nothing: total energy is conserved.
struct ArtificialConductivity {
  static constexpr bool needs_internal_energy = true;
  double alpha_u = 1.0;

  void validate() const {
    require(alpha_u >= 0.0,
            "artificial conductivity: alpha_u must be non-negative (got " + std::to_string(alpha_u) + ")");
  }

  template <int D>
  PairRates<D> pair(const Pair<D>& p) const {
    PairRates<D> out;
    const double rho_ab = 0.5 * (p.rho_a + p.rho_b);
    const double v_sig = std::sqrt(std::abs(p.P_a - p.P_b) / rho_ab);
    // r_hat . nabla_a W = dW/dr <= 0: heat runs from the hotter particle to the colder one
    const double r_hat_grad_W = p.r_ab.dot(p.grad_W) / p.r;
    out.du_dt = p.m_b * alpha_u * v_sig * (p.u_a - p.u_b) / rho_ab * r_hat_grad_W;
    return out;
  }
};

}  // namespace rsph::physics
