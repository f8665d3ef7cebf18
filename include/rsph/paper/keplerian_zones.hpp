#pragma once
// Boundary zones of §5.1 (as in PARASPH): gas inside r = inner and outside r = outer (the disk's edge
// rings [0.4, 0.5] and [2.4, 2.5] of §5) moves on fixed circular orbits. Membership is decided by radius
// whenever the particle set is rebuilt (at start and after each regularization); between, a member turns
// by Omega(r) dt exactly.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace rsph::paper {

struct KeplerianZones {
  double GM = 1.0;
  double inner = 0.5;  ///< gas at r <= inner is in the inner zone
  double outer = 2.4;  ///< gas at r >= outer is in the outer zone
  /// v_phi = v_factor sqrt(GM / r): 1 for Keplerian orbits, below 1 where pressure supports the gas.
  double v_factor = 1.0;
  /// Whether the members chosen at the start keep their membership and identity through every regularization
  /// (left out of the remap) instead of membership being decided anew by radius (the paper's zones). A lattice
  /// that follows the orbits no longer mixes gas across the zone's edge, so gas that strayed inside at a remap
  /// would be held there for good: the zone would fill up.
  bool members_kept = false;

  void validate() const {
    require(GM > 0.0, "Keplerian zones: GM must be positive");
    require(inner >= 0.0 && inner < outer, "Keplerian zones: need 0 <= inner < outer");
    require(v_factor > 0.0 && v_factor <= 1.0, "Keplerian zones: v_factor must lie in (0, 1]");
  }
  /// Gas beyond the disk's edges is a member too: it left the disk and is the scene's to remove. In 3D the zones
  /// are cylindrical shells: membership goes by the distance R from the z axis.
  template <int D>
  bool contains(const Vec<D>& x) const {
    const double R = cylindrical_radius(x);
    return R <= inner || R >= outer;
  }
  /// Angular velocity at distance R from the axis and height z: v_factor sqrt(GM / R^3) in the plane, and above it
  /// Omega^2 = GM / R^3 (R / r - 1 + v_factor^2), r = sqrt(R^2 + z^2): the rotation of a vertically isothermal
  /// disk with c_s^2 ~ 1 / R (Nelson et al. 2013, eq. 13 with q = -1, whose midplane term is v_factor^2).
  double Omega(double R, double z = 0.0) const {
    if (z == 0.0) return v_factor * std::sqrt(GM / (R * R * R));
    const double r = std::hypot(R, z);
    return std::sqrt(std::max(0.0, GM / (R * R * R) * (R / r - 1.0 + v_factor * v_factor)));
  }
  /// Circular velocity at x, about the z axis in 3D.
  template <int D>
  Vec<D> velocity(const Vec<D>& x) const {
    const double w = Omega(cylindrical_radius(x), height(x));
    Vec<D> v = Vec<D>::Zero();
    v[0] = -w * x[1];
    v[1] = w * x[0];
    return v;
  }
  /// Turns x by Omega dt about the z axis (the origin in 2D) and sets v to the circular velocity there.
  template <int D>
  void advance(Vec<D>& x, Vec<D>& v, double dt) const {
    const double angle = Omega(cylindrical_radius(x), height(x)) * dt;
    const double c = std::cos(angle), s = std::sin(angle);
    const double x0 = c * x[0] - s * x[1], x1 = s * x[0] + c * x[1];
    x[0] = x0;
    x[1] = x1;
    v = velocity(x);
  }

 private:
  template <int D>
  static double cylindrical_radius(const Vec<D>& x) {
    static_assert(D == 2 || D == 3, "Keplerian zones are annuli of a 2D disk or cylindrical shells of a 3D one");
    if constexpr (D == 2)
      return x.norm();
    else
      return std::hypot(x[0], x[1]);
  }
  template <int D>
  static double height(const Vec<D>& x) {
    if constexpr (D == 2)
      return 0.0;
    else
      return x[2];
  }
};

}  // namespace rsph::paper
