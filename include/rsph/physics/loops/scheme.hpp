#pragma once
// What the pair loops need to know of a scheme at compile time: the kernel, the dimension, and which
// sums the composed policies switch on. Simulation derives it from its policies; a loop called directly
// (a benchmark, a test) names one.
namespace rsph::physics::loops {

template <class Kernel_, int D, bool has_energy_, bool has_pressure_ = true, bool grad_h_ = false,
          bool corrected_ = false, bool has_stress_ = false, bool has_switch_ = false>
struct Scheme {
  using Kernel = Kernel_;
  static constexpr int dim = D;
  static constexpr bool has_energy = has_energy_;      ///< the gas carries u: eq. (4) is summed
  static constexpr bool has_pressure = has_pressure_;  ///< the pressure terms of eqs. (3)-(4) are summed
  static constexpr bool grad_h = grad_h_;              ///< grad-h SPH (physics/smoothing_length.hpp)
  static constexpr bool corrected = corrected_;        ///< consistent gradients (physics/consistent_gradient.hpp)
  static constexpr bool has_stress = has_stress_;      ///< a viscous stress term (physics/shear_viscosity.hpp)
  static constexpr bool has_switch = has_switch_;      ///< a viscosity switch (physics/viscosity_switch.hpp)
};

/// The specific internal energy of point a, zero for a gas that carries none.
template <bool has_energy, class P>
[[gnu::always_inline]] inline double energy_of(const P& p, std::size_t a) {
  if constexpr (has_energy)
    return p.u[a];
  else
    return 0.0;
}

}  // namespace rsph::physics::loops
