#pragma once
// A sum whose bits do not depend on the order of its terms: every term is cut into fixed-point limbs below a
// common scale 2^E and the limbs are summed as integers, which is associative. Partial sums made on threads
// or on ranks and combined in any order give the same bits, so a total (mass, momentum, energy) is the same
// whether one process or many computed it.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace rsph {

/// Fixed-point accumulator below 2^exponent: kLimbs limbs of kBits bits each, so a term is kept to
/// 2^(exponent - kLimbs kBits) absolutely (120 bits below the largest term's scale) and up to 2^32 terms fit
/// without overflow. The exponent must be the same for every partial sum that is combined (a global maximum,
/// ExactSum::exponent_for).
class ExactSum {
 public:
  static constexpr int kLimbs = 4;
  static constexpr int kBits = 30;
  using Limbs = std::array<std::int64_t, kLimbs>;

  /// The smallest E with |x| < 2^E for a largest magnitude x_max (0 for x_max = 0).
  static int exponent_for(double x_max) {
    if (!(x_max > 0.0)) return 0;
    int e = 0;
    std::frexp(x_max, &e);  // x_max = f 2^e, 0.5 <= f < 1
    return e;
  }

  explicit ExactSum(int exponent)
      : exponent_(exponent), scale_(exponent >= -1022 && exponent <= 1022 ? std::ldexp(1.0, -exponent) : 0.0) {}

  /// Adds x (|x| < 2^exponent); the part below the last limb is dropped, the same way whatever the order.
  /// Scaling by a power of two is one correctly rounded product: the bits ldexp gives, at half the cost.
  void add(double x) {
    static_assert(kBits == 30, "a limb's scale below is 2^kBits");
    double y = scale_ != 0.0 ? x * scale_ : std::ldexp(x, -exponent_);
    for (int i = 0; i < kLimbs; ++i) {
      y *= 0x1p30;
      const double digit = std::trunc(y);
      limbs_[static_cast<std::size_t>(i)] += static_cast<std::int64_t>(digit);
      y -= digit;
    }
  }
  /// Adds another partial sum with the same exponent.
  void add(const ExactSum& o) {
    for (std::size_t i = 0; i < limbs_.size(); ++i) limbs_[i] += o.limbs_[i];
  }

  Limbs& limbs() { return limbs_; }
  const Limbs& limbs() const { return limbs_; }
  int exponent() const { return exponent_; }

  /// The sum, rounded to a double: carries are moved up first, so equal integer sums give equal bits.
  double value() const {
    Limbs l = limbs_;
    for (int i = kLimbs - 1; i > 0; --i) {  // each lower limb into [0, 2^kBits)
      const std::int64_t carry = l[static_cast<std::size_t>(i)] >> kBits;
      l[static_cast<std::size_t>(i)] -= carry << kBits;
      l[static_cast<std::size_t>(i - 1)] += carry;
    }
    long double s = 0.0L;  // smallest limb first; the same limbs always round the same way
    for (int i = kLimbs - 1; i >= 0; --i)
      s += std::ldexp(static_cast<long double>(l[static_cast<std::size_t>(i)]), exponent_ - kBits * (i + 1));
    return static_cast<double>(s);
  }

 private:
  int exponent_;
  double scale_;  ///< 2^-exponent where a double holds it, 0 where ldexp must scale
  Limbs limbs_{};
};

}  // namespace rsph
