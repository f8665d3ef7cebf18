#pragma once
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <cmath>
#include <string>

namespace rsph::physics {

/// Gravity of a point mass GM at `centre`, Plummer-softened by epsilon: g = -GM r / (r^2 + eps^2)^(3/2).
template <int D>
struct PointMass {
  double GM = 1.0;
  Vec<D> centre = Vec<D>::Zero();
  double softening = 0.0;

  void validate() const {
    require(GM >= 0.0, "point mass: GM must be non-negative (got " + std::to_string(GM) + ")");
    require(softening >= 0.0, "point mass: the softening length must be non-negative");
  }
  Vec<D> acceleration(const Vec<D>& x, double) const {
    const Vec<D> r = x - centre;
    const double s2 = r.squaredNorm() + softening * softening;
    return (-GM / (s2 * std::sqrt(s2))) * r;
  }
  /// Potential energy per unit mass, for energy diagnostics.
  double potential(const Vec<D>& x) const {
    return -GM / std::sqrt((x - centre).squaredNorm() + softening * softening);
  }
};

}  // namespace rsph::physics
