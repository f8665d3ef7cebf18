#pragma once
#include "rsph/core/errors.hpp"

#include <cmath>
#include <string>

namespace rsph::physics {

/// h_a = eta (m_a / rho_a)^(1/D), set from each density sum for the next step (equal-mass SPH, where
/// resolution follows mass). Without it h stays as set, as on an RSPH lattice.
template <int D>
struct DensityAdaptiveH {
  double eta = 1.2;

  void validate() const { require(eta > 0.0, "adaptive smoothing length: eta must be positive (got " + std::to_string(eta) + ")"); }
  double next_h(double m, double rho, double) const {
    const double vol = m / rho;
    if constexpr (D == 1) return eta * vol;
    else if constexpr (D == 2) return eta * std::sqrt(vol);
    else return eta * std::cbrt(vol);
  }
};

}  // namespace rsph::physics
