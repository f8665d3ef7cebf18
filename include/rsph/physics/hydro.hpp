#pragma once
// The inviscid SPH equations of the paper, one pair at a time.
#include "rsph/physics/pair.hpp"

namespace rsph::physics {

/// eq. (2) of the paper: the contribution m_b W_ab to rho_a.
inline double density_term(double m_b, double W_ab) { return m_b * W_ab; }

/// The continuity equation, d rho_a / dt += m_b v_ab . nabla_a W_ab (Monaghan 1992): the rate of
/// eq. (2)'s sum, which predicts the density of a particle between its individual time steps.
template <int D>
inline double continuity_term(double m_b, const Vec<D>& v_ab, const Vec<D>& grad_W) {
  return m_b * v_ab.dot(grad_W);
}

/// The continuity equation in volume form, d rho_a / dt += rho_a V_b v_ab . nabla_a W_ab (Monaghan 1992
/// eq. 2.9 with V_b = m_b / rho_b): where particle masses jump (a contact on one lattice), the rate of a
/// particle follows its own density, not its heavier neighbours'.
template <int D>
inline double continuity_term_by_volume(double rho_a, double V_b, const Vec<D>& v_ab, const Vec<D>& grad_W) {
  return rho_a * V_b * v_ab.dot(grad_W);
}

/// eq. (3) of the paper without Pi_ab: dv_a/dt += -m_b (P_b / rho_b^2 + P_a / rho_a^2) nabla_a W_ab.
template <int D>
inline Vec<D> pressure_acceleration(const Pair<D>& p) {
  return (-p.m_b * (p.P_over_rho2_b + p.P_over_rho2_a)) * p.grad_W;
}

/// eq. (4) of the paper without Pi_ab: de_a/dt += m_b (P_a / rho_a^2) v_ab . nabla_a W_ab.
template <int D>
inline double pressure_heating(const Pair<D>& p) {
  return p.m_b * p.P_over_rho2_a * p.v_ab.dot(p.grad_W);
}

/// Price 2012 eq. 34 (grad-h SPH), inviscid part:
/// dv_a/dt += -m_b [P_a / (Omega_a rho_a^2) nabla_a W_ab(h_a) + P_b / (Omega_b rho_b^2) nabla_a W_ab(h_b)].
template <int D>
inline Vec<D> pressure_acceleration_grad_h(const Pair<D>& p) {
  return -p.m_b * ((p.P_a / (p.Omega_a * p.rho_a * p.rho_a)) * p.grad_W_a +
                   (p.P_b / (p.Omega_b * p.rho_b * p.rho_b)) * p.grad_W_b);
}

/// Price 2012 eq. 35 (grad-h SPH), inviscid part: du_a/dt += m_b P_a / (Omega_a rho_a^2) v_ab . nabla_a W_ab(h_a).
template <int D>
inline double pressure_heating_grad_h(const Pair<D>& p) {
  return p.m_b * (p.P_a / (p.Omega_a * p.rho_a * p.rho_a)) * p.v_ab.dot(p.grad_W_a);
}

}  // namespace rsph::physics
