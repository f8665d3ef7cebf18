#pragma once
// What one pair (a, b) knows, and what a pair term returns. Built once per pair by the loop driver.
#include "rsph/core/dimension.hpp"

namespace rsph::physics {

template <int D>
struct Pair {
  Vec<D> r_ab;                       ///< x_a - x_b
  Vec<D> v_ab;                       ///< v_a - v_b
  Vec<D> grad_W;                     ///< nabla_a W(r_ab, h_ab); with grad-h SPH the mean of the two gradients below
  Vec<D> grad_W_a = Vec<D>::Zero();  ///< grad-h SPH only: nabla_a W(r_ab, h_a)
  Vec<D> grad_W_b = Vec<D>::Zero();  ///< grad-h SPH only: nabla_a W(r_ab, h_b)
  double r;                          ///< |r_ab|
  double h_ab;                       ///< (h_a + h_b) / 2
  double m_a, m_b, rho_a, rho_b, cs_a, cs_b;
  double P_a = 0.0, P_b = 0.0;  ///< zero for a gas that exerts no pressure (the driver skips them)
  /// P / rho^2 of each side, as eqs. (3)-(4) use it: the driver divides once per particle, not per pair.
  double P_over_rho2_a = 0.0, P_over_rho2_b = 0.0;
  double u_a = 0.0, u_b = 0.0;            ///< specific internal energies, zero when the gas carries none
  double Omega_a = 1.0, Omega_b = 1.0;    ///< grad-h correction factors, 1 with fixed h
  double switch_a = 1.0, switch_b = 1.0;  ///< a viscosity switch's factors (ViscositySwitch), 1 without one
};

/// Contribution of b to the rates of a.
template <int D>
struct PairRates {
  Vec<D> dv_dt = Vec<D>::Zero();
  double du_dt = 0.0;
  double v_sig = 0.0;  ///< signal speed for the Courant condition
};

}  // namespace rsph::physics
