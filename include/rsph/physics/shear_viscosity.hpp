#pragma once
// Physical shear viscosity with a prescribed kinematic viscosity nu, two ways:
//  - ShearViscosityMG: the Monaghan & Gingold (1983) artificial viscosity applied to every pair, with
//    alpha c h set from nu (Meglicki, Wickramasinghe & Bicknell 1993) -- what the paper uses in §4;
//  - NavierStokesViscosity: the viscous stress tensor (Flebbe et al. 1994; Speith & Kley 2003), which
//    needs each particle's velocity gradient before the force sum (the driver runs that pass).
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/kernel/lattice_sum.hpp"
#include "rsph/physics/pair.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace rsph::physics {

/// In the continuum limit, sum_b (m_b / rho_b) K (v_ab . r_ab) / r_ab^2 nabla_a W_ab becomes
/// K / (2 (D + 2)) (lap v + 2 grad div v) for any normalised kernel (expand v_b about x_a; the
/// isotropic fourth moment of the unit vector is 1 / (D (D + 2)) and int s dW/ds d^Ds = -D). So the MG
/// term with alpha c h = 2 (D + 2) nu carries a shear viscosity nu: 8 nu in 2D (Meglicki et al. 1993),
/// 10 nu in 3D. Kernel independent; only the eta^2 softening below depends on the kernel.
template <int D>
constexpr double meglicki_constant() {
  return 2.0 * (D + 2);
}

/// The factor by which eta^2 h^2 in the denominator weakens the MG operator for kernel K:
/// int s^(D+2) W'(s) / (s^2 + eta^2) ds / int s^D W'(s) ds (h = 1), by Simpson's rule. For the cubic
/// spline in 2D with eta^2 = 0.01 it is 0.9816; the constant of every kernel is in the README.
template <class Kernel, int D>
double eta_softening_factor(double eta2) {
  constexpr int n = 4000;  // even
  const double ds = Kernel::support / n;
  double num = 0.0, den = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double s = i * ds;
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    double sD = 1.0;
    for (int k = 0; k < D; ++k) sD *= s;
    const double dW = kernel::dW_dr<Kernel, D>(s, 1.0);
    den += w * sD * dW;
    if (s > 0.0) num += w * sD * dW * s * s / (s * s + eta2);
  }
  return num / den;
}

/// The MG operator summed over a square lattice of spacing Delta = h / h_over_dx (2D), relative to
/// the continuum value without softening: sum_b Delta^2 x^2 y^2 W'(r) / (r (r^2 + eta^2)) / (-1/4).
/// RSPH particles sit on or near their lattice, where this -- not the continuum -- is the operator's
/// strength: 0.66 for the cubic spline at h/Delta = 1.0, 0.79 at 1.2, 0.95 at 1.6 (table in the README).
/// `hexagonal`: the same over a hexagonal lattice of nearest-neighbour distance Delta (cells of area
/// sqrt(3)/2 Delta^2), whose six-fold symmetry makes the sum isotropic.
template <class Kernel>
double lattice_factor(double h_over_dx, double eta2, bool hexagonal) {
  const double dx = 1.0 / h_over_dx;  // h = 1
  const double cell_area = (hexagonal ? (std::numbers::sqrt3 / 2.0) : 1.0) * dx * dx;
  double sum = 0.0;
  kernel::for_each_lattice_offset(hexagonal, Kernel::support * h_over_dx, [&](const Vec<2>& offset) {
    const double x = offset.x() * dx, y = offset.y() * dx, r = std::hypot(x, y);
    if (r > 0.0) sum += cell_area * x * x * y * y * kernel::dW_dr<Kernel, 2>(r, 1.0) / (r * (r * r + eta2));
  });
  return sum / -0.25;
}
/// The same over rows that slide past each other (lattice::Rings under shear): the own row adds nothing (y = 0),
/// every other row is averaged over its offset (kernel::sheared_rows_lattice_sum).
template <class Kernel>
double sheared_rows_lattice_factor(double h_over_dx, double eta2) {
  const double dx = 1.0 / h_over_dx;  // h = 1
  double sum = 0.0;
  for (int k = 1; k <= static_cast<int>(std::ceil(Kernel::support * h_over_dx)); ++k) {
    const double y = k * dx;
    sum += 2.0 * dx * kernel::row_integral(Kernel::support, [&](double x) {
             const double r = std::hypot(x, y);
             return x * x * y * y * kernel::dW_dr<Kernel, 2>(r, 1.0) / (r * (r * r + eta2));
           });
  }
  return sum / -0.25;
}
template <class Kernel>
double square_lattice_factor(double h_over_dx, double eta2) {
  return lattice_factor<Kernel>(h_over_dx, eta2, false);
}
template <class Kernel>
double hexagonal_lattice_factor(double h_over_dx, double eta2) {
  return lattice_factor<Kernel>(h_over_dx, eta2, true);
}

/// Monaghan & Gingold (1983) viscosity on all pairs, approaching and receding, as a shear viscosity nu:
/// Pi_ab = -K (v_ab . r_ab) / ((r_ab^2 + eta^2 h_ab^2) rho_ab) with K = alpha c h = 2 (D + 2) nu / f
/// (Meglicki et al. 1993), f the operator's strength relative to the continuum: eta_softening_factor
/// for disordered particles, square_lattice_factor for particles on a lattice. Adds a bulk term
/// 2 nu grad div v; zero for the shear flows it is meant for.
template <class Kernel, int D>
struct ShearViscosityMG {
  double nu = 0.0;
  double eta2 = 0.01;
  double K = 0.0;  ///< alpha c h, set from nu by the constructor

  ShearViscosityMG() = default;
  ShearViscosityMG(double nu_s, double strength, double eta2_ = 0.01)
      : nu(nu_s), eta2(eta2_), K(meglicki_constant<D>() * nu_s / strength) {
    require(strength > 0.0, "shear viscosity: the operator strength f must be positive");
  }
  /// Calibrated for disordered particles (the continuum limit).
  static ShearViscosityMG continuum(double nu_s, double eta2_ = 0.01) {
    return {nu_s, eta_softening_factor<Kernel, D>(eta2_), eta2_};
  }
  /// Calibrated for particles on a square lattice with the given h/Delta (2D).
  static ShearViscosityMG on_square_lattice(double nu_s, double h_over_dx, double eta2_ = 0.01) requires(D == 2) {
    return {nu_s, square_lattice_factor<Kernel>(h_over_dx, eta2_), eta2_};
  }
  /// Calibrated for particles on rings that slide past each other (lattice::Rings), Delta apart.
  static ShearViscosityMG on_sheared_rows(double nu_s, double h_over_dx, double eta2_ = 0.01) requires(D == 2) {
    return {nu_s, sheared_rows_lattice_factor<Kernel>(h_over_dx, eta2_), eta2_};
  }
  /// Calibrated for particles on a hexagonal lattice with the given h/Delta (Delta: nearest-neighbour distance).
  static ShearViscosityMG on_hexagonal_lattice(double nu_s, double h_over_dx, double eta2_ = 0.01) requires(D == 2) {
    return {nu_s, hexagonal_lattice_factor<Kernel>(h_over_dx, eta2_), eta2_};
  }

  void validate() const {
    require(nu >= 0.0, "shear viscosity: nu must be non-negative (got " + std::to_string(nu) + ")");
    require(eta2 > 0.0, "shear viscosity: eta^2 must be positive");
  }

  /// eqs. (3) and (4) of the paper with this Pi_ab. The signal speed K / h keeps the explicit step at
  /// Courant 0.3 below 0.0375 f h^2 / nu: compressive modes diffuse at 3 nu (shear plus the bulk term),
  /// and at h/Delta = 1.2 a step of 0.09 h^2 / nu was measured to go unstable.
  PairRates<D> pair(const Pair<D>& p) const {
    PairRates<D> out;
    const double rho_ab = 0.5 * (p.rho_a + p.rho_b);
    const double Pi_ab = -K * p.v_ab.dot(p.r_ab) / ((p.r * p.r + eta2 * p.h_ab * p.h_ab) * rho_ab);
    out.dv_dt = (-p.m_b * Pi_ab) * p.grad_W;
    out.du_dt = 0.5 * p.m_b * Pi_ab * p.v_ab.dot(p.grad_W);
    out.v_sig = K / p.h_ab;
    return out;
  }
};

/// Navier-Stokes shear stress S = rho nu (G + G^T - trace_factor tr(G) I), G_ij = dv_i/dx_j
/// (Flebbe et al. 1994 eq. 8). trace_factor 2/3 is the 3D traceless form used for thin disks
/// (Speith & Kley 2003); 2/D makes it traceless in D dimensions.
template <int D>
struct NavierStokesViscosity {
  double nu = 0.0;
  double trace_factor = 2.0 / 3.0;

  void validate() const {
    require(nu >= 0.0, "Navier-Stokes viscosity: nu must be non-negative (got " + std::to_string(nu) + ")");
  }
  Mat<D> stress(const Mat<D>& grad_v, double rho) const {
    return rho * nu * (grad_v + grad_v.transpose() - trace_factor * grad_v.trace() * Mat<D>::Identity());
  }
  /// The Courant condition's diffusion speed: dt <= courant * h / v_sig = 0.075 h^2 / nu at 0.3.
  double signal_speed(double h) const { return 4.0 * nu / h; }
};

/// b's share of the velocity gradient G_a = sum_b (m_b / rho_b) (v_b - v_a) (x) nabla_a W_ab. Flebbe
/// et al. (1994) eq. (13) divides by rho_a instead; with rho_b a light particle next to heavy ones (the
/// tail of a ring) gets a bounded gradient rather than one scaled by m_b / m_a.
template <int D>
Mat<D> velocity_gradient_term(double m_b, double rho_b, const Vec<D>& v_ab, const Vec<D>& grad_W) {
  return (-m_b / rho_b) * v_ab * grad_W.transpose();
}

/// Flebbe et al. (1994) eq. (12): dv_a/dt += m_b (S_a / rho_a^2 + S_b / rho_b^2) nabla_a W_ab, the
/// stress analogue of the pressure term of eq. (3) (sigma = -P I + S).
template <int D>
Vec<D> stress_acceleration(double m_b, const Mat<D>& S_over_rho2_a, const Mat<D>& S_over_rho2_b, const Vec<D>& grad_W) {
  return m_b * ((S_over_rho2_a + S_over_rho2_b) * grad_W);
}

/// Viscous heating paired with stress_acceleration so that total energy is conserved exactly:
/// du_a/dt += -m_b v_ab . (S_a / rho_a^2) nabla_a W_ab (the analogue of eq. 4).
template <int D>
double stress_heating(double m_b, const Mat<D>& S_over_rho2_a, const Vec<D>& v_ab, const Vec<D>& grad_W) {
  return -m_b * v_ab.dot(S_over_rho2_a * grad_W);
}

}  // namespace rsph::physics
