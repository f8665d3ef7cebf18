#pragma once
// Artificial viscosity scaled by Balsara's (1995) switch: each particle's factor f = |div v| / (|div v| + |curl v|
// + eps c_s / h) from its velocity gradient, so that the viscosity acts where the flow compresses and fades
// where it only shears (a Keplerian disk's orbits). A pair takes (f_a + f_b) / 2 of Monaghan's Pi_ab, as in
// Monaghan's (2005) review and the SPH codes that use the switch (GADGET-2, Phantom).
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/physics/artificial_viscosity.hpp"
#include "rsph/physics/pair.hpp"

#include <cmath>
#include <string>

namespace rsph::physics {

/// The divergence of a velocity gradient G (G_ij = d v_i / d x_j, or its transpose: the trace is either's).
template <int D>
double divergence(const Mat<D>& G) {
  return G.trace();
}

/// |curl v| of a velocity gradient: 0 in 1D, |G_yx - G_xy| in 2D, the norm of the antisymmetric part's vector
/// in 3D (the same for G and its transpose).
template <int D>
double curl_norm(const Mat<D>& G) {
  if constexpr (D == 1)
    return 0.0;
  else if constexpr (D == 2)
    return std::abs(G(1, 0) - G(0, 1));
  else
    return Vec<3>(G(2, 1) - G(1, 2), G(0, 2) - G(2, 0), G(1, 0) - G(0, 1)).norm();
}

/// Balsara's (1995) factor f = |div v| / (|div v| + |curl v| + eps c_s / h), in [0, 1]; eps keeps it finite
/// where the gas is at rest.
inline double balsara_factor(double div, double curl, double cs, double h, double eps) {
  const double d = std::abs(div);
  const double den = d + curl + eps * cs / h;
  return den > 0.0 ? d / den : 0.0;
}

/// Monaghan's artificial viscosity (ArtificialViscosity) with alpha and beta scaled, pair by pair, by the mean
/// of both particles' Balsara factors (Pair::switch_a, switch_b), which the driver computes from each
/// particle's velocity gradient before the force pass. With alpha = beta = 0 it is off: the driver skips the
/// gradient pass and the pair adds nothing.
struct SwitchedViscosity {
  ArtificialViscosity av{0.0, 0.0};
  double eps = 1e-4;  ///< Balsara's eps: the floor eps c_s / h of the denominator

  void validate() const {
    av.validate();
    require(eps > 0.0, "switched viscosity: eps must be positive (got " + std::to_string(eps) + ")");
  }
  /// Whether it acts at all (alpha or beta positive).
  bool active() const { return av.alpha > 0.0 || av.beta > 0.0; }

  /// The particle's factor from its velocity gradient, sound speed and smoothing length.
  template <int D>
  double switch_factor(const Mat<D>& grad_v, double cs, double h) const {
    return balsara_factor(divergence<D>(grad_v), curl_norm<D>(grad_v), cs, h, eps);
  }

  /// Pi_ab with alpha and beta times (f_a + f_b) / 2, entering eqs. (3) and (4) as ArtificialViscosity's.
  template <int D>
  PairRates<D> pair(const Pair<D>& p) const {
    if (!active()) return {};
    const double f = 0.5 * (p.switch_a + p.switch_b);
    return ArtificialViscosity{f * av.alpha, f * av.beta, av.eta2}.pair(p);
  }
};

}  // namespace rsph::physics
