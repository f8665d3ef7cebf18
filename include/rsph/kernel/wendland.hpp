#pragma once
#include <numbers>

namespace rsph::kernel {

/// Wendland C2 of 2D/3D, support 2h (Dehnen & Aly 2012 Table 1, rescaled to q = r/h in [0, 2]):
/// (1 - q/2)^4 (1 + 2q). Positive definite up to 3D, so it is a valid (smoother) kernel in 1D too,
/// normalised there by 3/4; WendlandC2_1D is the genuine one-dimensional member of the family.
struct WendlandC2 {
  static constexpr double support = 2.0;
  template <int D>
  static constexpr double sigma() {
    if constexpr (D == 1)
      return 3.0 / 4.0;
    else if constexpr (D == 2)
      return 7.0 / (4.0 * std::numbers::pi);
    else
      return 21.0 / (16.0 * std::numbers::pi);
  }
  static double f(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q;
    return t * t * t * t * (1.0 + 2.0 * q);
  }
  static double df(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q;
    return -5.0 * q * t * t * t;  // d/dq[(1-q/2)^4 (1+2q)]
  }
};

/// Wendland C4 of 2D/3D, support 2h (Dehnen & Aly 2012 Table 1, rescaled to q = r/h in [0, 2]):
/// (1 - q/2)^6 (1 + 3q + 35/12 q^2). Stable against pairing at large neighbour numbers (Dehnen & Aly §4);
/// normalised in 1D too, where it is positive definite as well.
struct WendlandC4 {
  static constexpr double support = 2.0;
  template <int D>
  static constexpr double sigma() {
    if constexpr (D == 1)
      return 27.0 / 32.0;
    else if constexpr (D == 2)
      return 9.0 / (4.0 * std::numbers::pi);
    else
      return 495.0 / (256.0 * std::numbers::pi);
  }
  static double f(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q, t2 = t * t;
    return t2 * t2 * t2 * (1.0 + q * (3.0 + 35.0 / 12.0 * q));
  }
  static double df(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q, t2 = t * t;
    return -7.0 / 3.0 * q * t2 * t2 * t * (2.0 + 5.0 * q);  // d/dq[(1-q/2)^6 (1 + 3q + 35q^2/12)]
  }
};

/// Wendland C6 of 2D/3D, support 2h (Dehnen & Aly 2012 Table 1, rescaled to q = r/h in [0, 2]):
/// (1 - q/2)^8 (1 + 4q + 25/4 q^2 + 4q^3).
struct WendlandC6 {
  static constexpr double support = 2.0;
  template <int D>
  static constexpr double sigma() {
    if constexpr (D == 1)
      return 15.0 / 16.0;
    else if constexpr (D == 2)
      return 39.0 / (14.0 * std::numbers::pi);
    else
      return 1365.0 / (512.0 * std::numbers::pi);
  }
  static double f(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q, t2 = t * t, t4 = t2 * t2;
    return t4 * t4 * (1.0 + q * (4.0 + q * (25.0 / 4.0 + 4.0 * q)));
  }
  static double df(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q, t2 = t * t, t4 = t2 * t2;
    return -11.0 / 4.0 * q * t4 * t2 * t * (2.0 + q * (7.0 + 8.0 * q));  // d/dq[(1-q/2)^8 (1 + 4q + ...)]
  }
};

/// Wendland C2 in one dimension, support 2h: (1 - q/2)^3 (1 + 3q/2).
struct WendlandC2_1D {
  static constexpr double support = 2.0;
  template <int D>
  static constexpr double sigma() {
    static_assert(D == 1, "WendlandC2_1D is the one-dimensional Wendland C2 kernel; use WendlandC2 in 2D and 3D");
    return 5.0 / 8.0;
  }
  static double f(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q;
    return t * t * t * (1.0 + 1.5 * q);
  }
  static double df(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q;
    return -3.0 * q * t * t;  // d/dq[(1-q/2)^3 (1+3q/2)]
  }
};

}  // namespace rsph::kernel
