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

/// W(r, h) of eq. (2).
template <class K, int D>
requires SmoothingKernel<K, D>
inline double W(double r, double h) {
  const double inv_h = 1.0 / h;  // one division: the pair loops are bound by their divisions
  return K::template sigma<D>() * pow_dim<D>(inv_h) * K::f(r * inv_h);
}

/// dW/dr; the gradient is dW_dr * r_ab / |r_ab|.
template <class K, int D>
requires SmoothingKernel<K, D>
inline double dW_dr(double r, double h) {
  const double inv_h = 1.0 / h;
  return K::template sigma<D>() * (pow_dim<D>(inv_h) * inv_h) * K::df(r * inv_h);
}

/// nabla_a W_ab for r_ab = x_a - x_b, |r_ab| = r > 0.
template <class K, int D>
requires SmoothingKernel<K, D>
inline Vec<D> grad_W(const Vec<D>& r_ab, double r, double h) {
  if (r <= 0.0) return Vec<D>::Zero();
  return (dW_dr<K, D>(r, h) / r) * r_ab;
}

}  // namespace rsph::kernel
