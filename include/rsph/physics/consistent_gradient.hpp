#pragma once
// Pair gradients made consistent at level faces, where h jumps between lattice levels (variable
// resolution). With h_ab = (h_a + h_b) / 2 the sums  sum_b m_b W_ab  and  sum_b V_b grad W_ab  are not
// normalised across a face even on perfect lattices, so a uniform state is no equilibrium there. This
// policy fixes both, keeping every conservation law:
//  - the density follows the continuity equation from the remapped density rho_n = m_n / V_n (mass over
//    the covered volume of the new cell), instead of the kernel sum of eq. (2);
//  - pairs within the band of particles around level faces (those with a neighbour of another h, and a
//    few neighbour layers more) use G_ab = grad_a W_ab + W_ab (psi_b - psi_a), antisymmetric in a and b,
//    with the per-particle vectors psi chosen so that  sum_b V_b G_ab = 0  for every band particle
//    (V_b = m_b / rho_b): a graph Laplacian  sum_b V_a V_b W_ab (psi_a - psi_b) = V_a E_a,
//    E_a = sum_b V_b grad_a W_ab, solved by conjugate gradients, one per axis. Away from faces pairs keep
//    grad W, and on a uniform lattice E = 0 there.
// A uniform state (rho, P, v constant) is then an exact equilibrium on any lattice; momentum and total
// energy stay conserved to round-off because G_ab = -G_ba.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <string>

namespace rsph::physics {

/// The policy: name it among a simulation's terms (fixed h only, one global time step).
struct ConsistentGradient {
  static constexpr bool corrects_gradient = true;
  double tolerance = 1e-12;   ///< relative residual of the psi solve
  int max_iterations = 5000;  ///< per axis and solve
  /// Re-solve psi at every force pass (warm-started). false: only after a remap, cheaper, for flows that
  /// barely move between regularizations (solved over the whole domain, a stale psi broke Sod within ten steps).
  bool every_step = true;
  int band_layers = 2;  ///< neighbour layers added around the particles that see another h

  void validate() const {
    require(tolerance > 0.0 && tolerance < 1.0,
            "consistent gradient: the solver tolerance must lie in (0, 1) (got " + std::to_string(tolerance) + ")");
    require(max_iterations > 0, "consistent gradient: max_iterations must be positive");
    require(band_layers >= 0, "consistent gradient: band_layers must be non-negative");
  }
};

/// G_ab = grad_a W_ab + W_ab (psi_b - psi_a): the corrected pair gradient (antisymmetric in a, b).
template <int D>
inline Vec<D> consistent_gradient(const Vec<D>& grad_W, double W_ab, const Vec<D>& psi_a, const Vec<D>& psi_b) {
  return grad_W + W_ab * (psi_b - psi_a);
}

/// V_b grad_a W_ab: b's share of E_a, the zeroth-order error of the gradient sum.
template <int D>
inline Vec<D> zeroth_order_error_term(double V_b, const Vec<D>& grad_W) {
  return V_b * grad_W;
}

/// V_a V_b W_ab: the weight of the pair in the psi Laplacian (symmetric in a, b).
inline double laplacian_weight(double V_a, double V_b, double W_ab) { return V_a * V_b * W_ab; }

}  // namespace rsph::physics
