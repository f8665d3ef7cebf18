#pragma once
// Kernel evaluation shared by every kernel policy.
#include "rsph/core/dimension.hpp"
#include "rsph/kernel/concept.hpp"

namespace rsph::kernel {

template <int D>
constexpr double pow_dim(double h) {
  if constexpr (D == 1)
    return h;
  else if constexpr (D == 2)
    return h * h;
  else
    return h * h * h;
}

// Each function comes in two forms: of h, and of 1 / h. The pair loops are bound by their divisions, so
// they pass one reciprocal for all the pairs of a particle that share its h (every pair on one RSPH
// lattice level); both forms give the same bits.

/// W(r, h) of eq. (2), given 1 / h.
template <class K, int D>
requires SmoothingKernel<K, D>
inline double W_inv_h(double r, double inv_h) { return K::template sigma<D>() * pow_dim<D>(inv_h) * K::f(r * inv_h); }

template <class K, int D>
requires SmoothingKernel<K, D>
inline double W(double r, double h) { return W_inv_h<K, D>(r, 1.0 / h); }

/// dW/dr given 1 / h; the gradient is dW_dr * r_ab / |r_ab|.
template <class K, int D>
requires SmoothingKernel<K, D>
inline double dW_dr_inv_h(double r, double inv_h) {
  return K::template sigma<D>() * (pow_dim<D>(inv_h) * inv_h) * K::df(r * inv_h);
}

template <class K, int D>
requires SmoothingKernel<K, D>
inline double dW_dr(double r, double h) { return dW_dr_inv_h<K, D>(r, 1.0 / h); }

/// nabla_a W_ab for r_ab = x_a - x_b, |r_ab| = r > 0, given 1 / h.
template <class K, int D>
requires SmoothingKernel<K, D>
inline Vec<D> grad_W_inv_h(const Vec<D>& r_ab, double r, double inv_h) {
  if (r <= 0.0) return Vec<D>::Zero();
  return (dW_dr_inv_h<K, D>(r, inv_h) / r) * r_ab;
}

template <class K, int D>
requires SmoothingKernel<K, D>
inline Vec<D> grad_W(const Vec<D>& r_ab, double r, double h) { return grad_W_inv_h<K, D>(r_ab, r, 1.0 / h); }

/// 1 / h_ab of a pair, h_ab = (h_a + h_b) / 2: where h_b equals h_a it is 1 / h_a, which the caller has.
inline double inv_h_ab(double h_a, double inv_h_a, double h_b) { return h_b == h_a ? inv_h_a : 2.0 / (h_a + h_b); }

}  // namespace rsph::kernel
