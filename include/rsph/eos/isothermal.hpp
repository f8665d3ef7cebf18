#pragma once
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/eos/concept.hpp"

#include <string>
#include <utility>

namespace rsph::eos {

/// P = c_s^2 rho with one sound speed everywhere; no energy equation.
struct Isothermal {
  static constexpr bool has_internal_energy = false;
  double cs = 1.0;
  static constexpr const char* name = "isothermal: P = cs^2 rho";
  template <class F>
  void describe(F&& f) const {
    f("cs", cs);
  }

  void validate() const {
    require(cs > 0.0, "isothermal gas: sound speed must be positive (got " + std::to_string(cs) + ")");
  }
  template <class X>
  double pressure(double rho, double, const X&) const {
    return cs * cs * rho;
  }
  template <class X>
  double sound_speed(double, double, const X&) const {
    return cs;
  }
};

/// P = c_s(x)^2 rho with the sound speed a function of position (c_s / v_K fixed in a disk, §5).
template <class SoundSpeedOfPosition>
struct LocallyIsothermal {
  static constexpr bool has_internal_energy = false;
  SoundSpeedOfPosition cs_of_x;
  static constexpr const char* name = "locally isothermal: P = cs(x)^2 rho";
  template <class F>
  void describe(F&& f) const {
    if constexpr (requires { cs_of_x.describe(f); }) cs_of_x.describe(f);
  }

  explicit LocallyIsothermal(SoundSpeedOfPosition f) : cs_of_x(std::move(f)) {}
  template <class X>
  double pressure(double rho, double, const X& x) const {
    const double c = cs_of_x(x);
    return c * c * rho;
  }
  template <class X>
  double sound_speed(double, double, const X& x) const {
    return cs_of_x(x);
  }
  template <class X>
  GasState state(double rho, double, const X& x) const {
    const double c = cs_of_x(x);  // once for both
    return {c * c * rho, c};
  }
};

/// No pressure at all (the viscous ring of §4).
struct Pressureless {
  static constexpr bool has_internal_energy = false;
  static constexpr bool exerts_pressure = false;
  static constexpr const char* name = "pressureless: P = 0";
  template <class F>
  void describe(F&&) const {}
  template <class X>
  double pressure(double, double, const X&) const {
    return 0.0;
  }
  template <class X>
  double sound_speed(double, double, const X&) const {
    return 0.0;
  }
};

}  // namespace rsph::eos
