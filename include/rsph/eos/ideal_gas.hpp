#pragma once
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <cmath>
#include <string>

namespace rsph::eos {

/// P = (gamma - 1) rho u: eq. (5) of the paper.
struct IdealGas {
  static constexpr bool has_internal_energy = true;
  double gamma = 1.4;
  static constexpr const char* name = "ideal gas: P = (gamma - 1) rho u";
  /// Its constants, f(name, value) each, for snapshots.
  template <class F>
  void describe(F&& f) const {
    f("gamma", gamma);
  }

  void validate() const { require(gamma > 1.0, "ideal gas: gamma must exceed 1 (got " + std::to_string(gamma) + ")"); }
  template <class X>
  double pressure(double rho, double u, const X&) const {
    return (gamma - 1.0) * rho * u;
  }
  template <class X>
  double sound_speed(double, double u, const X&) const {
    return std::sqrt(gamma * (gamma - 1.0) * std::max(u, 0.0));
  }
  /// u for a given pressure and density, for setting up initial states.
  double internal_energy(double rho, double P) const { return P / ((gamma - 1.0) * rho); }
};

}  // namespace rsph::eos
