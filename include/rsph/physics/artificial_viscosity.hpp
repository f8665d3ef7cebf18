#pragma once
#include "rsph/core/errors.hpp"
#include "rsph/physics/pair.hpp"

#include <algorithm>
#include <string>

namespace rsph::physics {

/// Monaghan & Gingold (1983) artificial viscosity Pi_ab, entering eqs. (3) and (4) of the paper
/// (form of Monaghan 1992 eq. 4.1-4.2).
struct ArtificialViscosity {
  double alpha = 1.0;
  double beta = 2.0;
  double eta2 = 0.01;  ///< eta^2 in mu_ab's denominator, keeps it finite as r -> 0

  void validate() const {
    require(alpha >= 0.0 && beta >= 0.0, "artificial viscosity: alpha and beta must be non-negative (got " +
                                             std::to_string(alpha) + ", " + std::to_string(beta) + ")");
  }

  /// mu_ab = h_ab v_ab . r_ab / (r_ab^2 + eta^2 h_ab^2), Monaghan 1992 eq. 4.2; zero for receding pairs.
  template <int D>
  static double mu(const Pair<D>& p, double eta2_) {
    const double vr = p.v_ab.dot(p.r_ab);
    if (vr >= 0.0) return 0.0;
    return p.h_ab * vr / (p.r * p.r + eta2_ * p.h_ab * p.h_ab);
  }

  /// Pi_ab = (-alpha c_ab mu_ab + beta mu_ab^2) / rho_ab, Monaghan 1992 eq. 4.1.
  template <int D>
  double Pi(const Pair<D>& p, double mu_ab) const {
    if (mu_ab == 0.0) return 0.0;
    const double c_ab = 0.5 * (p.cs_a + p.cs_b);
    const double rho_ab = 0.5 * (p.rho_a + p.rho_b);
    return (-alpha * c_ab * mu_ab + beta * mu_ab * mu_ab) / rho_ab;
  }

  /// Pi_ab's share of eq. (3) (-m_b Pi_ab nabla_a W) and of eq. (4) (m_b Pi_ab / 2 v_ab . nabla_a W);
  /// signal speed of Monaghan (1989): c_a + 1.2 (alpha c_a + beta |mu_ab|).
  template <int D>
  PairRates<D> pair(const Pair<D>& p) const {
    PairRates<D> out;
    const double m = mu(p, eta2);
    out.v_sig = p.cs_a + 1.2 * (alpha * p.cs_a + beta * std::abs(m));
    if (m == 0.0) return out;
    const double Pi_ab = Pi(p, m);
    out.dv_dt = (-p.m_b * Pi_ab) * p.grad_W;
    out.du_dt = 0.5 * p.m_b * Pi_ab * p.v_ab.dot(p.grad_W);
    return out;
  }
};

}  // namespace rsph::physics
