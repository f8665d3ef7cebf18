#pragma once
// The smoothing-kernel policy axis.
#include <concepts>

namespace rsph {

/// A kernel W(r, h) = sigma<D>() / h^D * f(r / h), zero for r / h >= support.
template <class K, int D>
concept SmoothingKernel = requires(double q) {
  { K::support } -> std::convertible_to<double>;
  { K::template sigma<D>() } -> std::convertible_to<double>;
  { K::f(q) } -> std::same_as<double>;
  { K::df(q) } -> std::same_as<double>;
};

/// Names what a kernel type misses, as a sentence, where a plain concept failure would be cryptic.
template <class K, int D>
constexpr bool check_kernel() {
  static_assert(
      requires { K::support; }, "a smoothing kernel needs `static constexpr double support` (radius in units of h)");
  static_assert(
      requires { K::template sigma<D>(); },
      "a smoothing kernel needs `template <int D> static constexpr double sigma()`, its normalisation in D dimensions");
  static_assert(
      requires(double q) {
        { K::f(q) } -> std::same_as<double>;
      },
      "a smoothing kernel needs `static double f(double q)`, its shape");
  static_assert(
      requires(double q) {
        { K::df(q) } -> std::same_as<double>;
      },
      "a smoothing kernel needs `static double df(double q)`, the derivative of its shape");
  return true;
}

}  // namespace rsph
