#pragma once
// Boundary zones of §5.1 (as in PARASPH): gas inside r = inner and outside r = outer (the disk's edge
// rings [0.4, 0.5] and [2.4, 2.5] of §5) moves on fixed circular orbits. Membership is decided by radius
// whenever the particle set is rebuilt (at start and after each regularization); between, a member turns
// by Omega(r) dt exactly.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

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
  /// Gas beyond the disk's edges is a member too: it left the disk and is the scene's to remove.
  bool contains(const Vec<2>& x) const {
    const double r = x.norm();
    return r <= inner || r >= outer;
  }
  double Omega(double r) const { return v_factor * std::sqrt(GM / (r * r * r)); }
  /// Circular velocity at x.
  Vec<2> velocity(const Vec<2>& x) const {
    const double r = x.norm();
    return Omega(r) * Vec<2>(-x[1], x[0]);
  }
  /// Turns x by Omega(r) dt about the origin and sets v to the circular velocity there.
  void advance(Vec<2>& x, Vec<2>& v, double dt) const {
    const double angle = Omega(x.norm()) * dt;
    const double c = std::cos(angle), s = std::sin(angle);
    x = Vec<2>(c * x[0] - s * x[1], s * x[0] + c * x[1]);
    v = velocity(x);
  }
};

}  // namespace rsph::paper
