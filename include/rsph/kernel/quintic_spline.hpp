#pragma once
#include <numbers>

namespace rsph::kernel {

/// M6 quintic B-spline, support 3h (Morris 1996); used by the paper for the linear waves (§3.1).
struct QuinticSpline {
  static constexpr double support = 3.0;
  template <int D>
  static constexpr double sigma() {
    if constexpr (D == 1)
      return 1.0 / 120.0;
    else if constexpr (D == 2)
      return 7.0 / (478.0 * std::numbers::pi);
    else
      return 1.0 / (120.0 * std::numbers::pi);
  }
  static double f(double q) {
    if (q >= 3.0) return 0.0;
    const double a = 3.0 - q, b = 2.0 - q, c = 1.0 - q;
    double w = a * a * a * a * a;
    if (q < 2.0) w -= 6.0 * b * b * b * b * b;
    if (q < 1.0) w += 15.0 * c * c * c * c * c;
    return w;
  }
  static double df(double q) {
    if (q >= 3.0) return 0.0;
    const double a = 3.0 - q, b = 2.0 - q, c = 1.0 - q;
    double w = -5.0 * a * a * a * a;
    if (q < 2.0) w += 30.0 * b * b * b * b;
    if (q < 1.0) w -= 75.0 * c * c * c * c;
    return w;
  }
};

}  // namespace rsph::kernel
