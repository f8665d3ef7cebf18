#pragma once
#include <numbers>

namespace rsph::kernel {

/// M4 cubic B-spline, support 2h (Monaghan 2005 eq. 2.6): the paper's default kernel.
struct CubicSpline {
  static constexpr double support = 2.0;
  template <int D>
  static constexpr double sigma() {
    if constexpr (D == 1)
      return 2.0 / 3.0;
    else if constexpr (D == 2)
      return 10.0 / (7.0 * std::numbers::pi);
    else
      return 1.0 / std::numbers::pi;
  }
  static double f(double q) {
    if (q < 1.0) return 1.0 - 1.5 * q * q + 0.75 * q * q * q;
    if (q < 2.0) {
      const double t = 2.0 - q;
      return 0.25 * t * t * t;
    }
    return 0.0;
  }
  static double df(double q) {
    if (q < 1.0) return -3.0 * q + 2.25 * q * q;
    if (q < 2.0) {
      const double t = 2.0 - q;
      return -0.75 * t * t;
    }
    return 0.0;
  }
};

}  // namespace rsph::kernel
