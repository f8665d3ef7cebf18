#pragma once
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <cmath>
#include <string>
#include <utility>

namespace rsph::eos {

/// P = K(x) rho^gamma: eq. (21) of the paper, with K a function of position; no energy equation.
template <class KOfPosition>
struct Polytropic {
  static constexpr bool has_internal_energy = false;
  double gamma;
  KOfPosition K_of_x;
  static constexpr const char* name = "polytropic: P = K(x) rho^gamma";
  template <class F>
  void describe(F&& f) const {
    f("gamma", gamma);
    if constexpr (requires { K_of_x.describe(f); }) K_of_x.describe(f);
  }

  Polytropic(double gamma_, KOfPosition K) : gamma(gamma_), K_of_x(std::move(K)) {}
  void validate() const {
    require(gamma > 1.0, "polytropic gas: gamma must exceed 1 (got " + std::to_string(gamma) + ")");
  }
  template <class X>
  double pressure(double rho, double, const X& x) const {
    return K_of_x(x) * std::pow(rho, gamma);
  }
  template <class X>
  double sound_speed(double rho, double u, const X& x) const {
    return rho > 0.0 ? std::sqrt(gamma * pressure(rho, u, x) / rho) : 0.0;
  }
};

/// K constant in space.
struct ConstantK {
  double K = 1.0;
  template <class F>
  void describe(F&& f) const {
    f("K", K);
  }
  template <class X>
  double operator()(const X&) const {
    return K;
  }
};

}  // namespace rsph::eos
