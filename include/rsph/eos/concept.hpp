#pragma once
// The equation-of-state policy axis.
#include "rsph/core/dimension.hpp"

#include <concepts>

namespace rsph {

/// P(rho, u, x) and c_s(rho, u, x); `has_internal_energy` says whether particles carry u and eq. (4) runs.
template <class E, int D>
concept EquationOfState = requires(const E& e, double rho, double u, const Vec<D>& x) {
  { E::has_internal_energy } -> std::convertible_to<bool>;
  { e.pressure(rho, u, x) } -> std::same_as<double>;
  { e.sound_speed(rho, u, x) } -> std::same_as<double>;
};

/// Whether the gas pushes at all. An equation of state without pressure (dust, a pressureless ring)
/// says `static constexpr bool exerts_pressure = false`, and the pair loops then skip eqs. (3)-(4)'s
/// pressure terms instead of summing zeros; every other one exerts pressure.
template <class E>
constexpr bool exerts_pressure() {
  if constexpr (requires { E::exerts_pressure; })
    return E::exerts_pressure;
  else
    return true;
}

/// Pressure and sound speed of one state, as the driver refreshes them together.
struct GasState {
  double P = 0.0, cs = 0.0;
};

/// An equation of state may give both at once (`GasState state(rho, u, x) const`) when they share work,
/// such as c_s(x) of a locally isothermal disk; otherwise the driver asks for each.
template <class E, int D>
GasState gas_state(const E& e, double rho, double u, const Vec<D>& x) {
  if constexpr (requires {
                  { e.state(rho, u, x) } -> std::same_as<GasState>;
                })
    return e.state(rho, u, x);
  else
    return {e.pressure(rho, u, x), e.sound_speed(rho, u, x)};
}

template <class E, int D>
constexpr bool check_equation_of_state() {
  static_assert(
      requires { E::has_internal_energy; },
      "an equation of state needs `static constexpr bool has_internal_energy` (does the gas carry u?)");
  static_assert(
      requires(const E& e, double rho, double u, const Vec<D>& x) {
        { e.pressure(rho, u, x) } -> std::same_as<double>;
      },
      "an equation of state needs `double pressure(double rho, double u, const Vec<D>& x) const`");
  static_assert(
      requires(const E& e, double rho, double u, const Vec<D>& x) {
        { e.sound_speed(rho, u, x) } -> std::same_as<double>;
      },
      "an equation of state needs `double sound_speed(double rho, double u, const Vec<D>& x) const`");
  return true;
}

}  // namespace rsph
