#pragma once
// Wave-damping zones at a disk's edges, after de Val-Borro et al. (2006): inside a zone the velocity
// relaxes toward the circular orbit of the Keplerian zones (keplerian_zones.hpp),
//   dv/dt = -(v - v0(x)) R(r) / tau,
// R a parabola from 1 at the edge of the free gas to 0 at the zone's far side, and tau a fraction of the orbital
// period at that edge. The zones lie just inside the free disk, beside the fixed orbits of §5.1, and take up the
// radial motion that reaches the edges, as a grid code's zones take up its waves (on the orbit-following rings
// they keep the inner zone from filling, but not the disk's own noise from growing: docs/results/rings.md).
// Unlike a grid code's zones, they leave the surface density alone: every particle keeps its mass.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/paper/keplerian_zones.hpp"

#include <cmath>
#include <numbers>

namespace rsph::paper {

struct DampingZones {
  KeplerianZones orbits;     ///< the fixed zones: their edges and the circular velocity damped toward
  double inner_width = 0.0;  ///< the inner damping zone is orbits.inner < R < orbits.inner + inner_width (0: none)
  double outer_width = 0.0;  ///< the outer one orbits.outer - outer_width < R < orbits.outer (0: none)
  double tau_periods = 0.1;  ///< tau, in orbital periods at the zone's edge (de Val-Borro et al.: 1/10)

  void validate() const {
    orbits.validate();
    require(inner_width >= 0.0 && outer_width >= 0.0, "damping zones: the widths must not be negative");
    require(orbits.inner + inner_width <= orbits.outer - outer_width, "damping zones: the two zones overlap");
    require(tau_periods > 0.0 && std::isfinite(tau_periods), "damping zones: tau must be positive");
  }
  bool active() const { return inner_width > 0.0 || outer_width > 0.0; }

  /// R(R_cyl) / tau at distance R from the axis: 0 outside both zones.
  double rate(double R) const {
    if (inner_width > 0.0 && R > orbits.inner && R < orbits.inner + inner_width)
      return ramp(orbits.inner + inner_width - R, inner_width) / tau(orbits.inner);
    if (outer_width > 0.0 && R < orbits.outer && R > orbits.outer - outer_width)
      return ramp(R - (orbits.outer - outer_width), outer_width) / tau(orbits.outer);
    return 0.0;
  }
  /// v relaxed over dt toward the circular velocity at x: the exact solution of the linear relaxation, so any
  /// step is stable and two half steps equal one whole.
  template <int D>
  void damp(const Vec<D>& x, Vec<D>& v, double dt) const {
    const double k = rate(std::hypot(x[0], x[1]));
    if (k == 0.0) return;
    const Vec<D> v0 = orbits.velocity(x);
    v = v0 + (v - v0) * std::exp(-k * dt);
  }

 private:
  /// The parabola: 0 at the zone's far side (d = 0), 1 at the edge of the free gas (d = width).
  static double ramp(double d, double width) { return (d / width) * (d / width); }
  double tau(double R) const { return tau_periods * 2.0 * std::numbers::pi / orbits.Omega(R); }
};

}  // namespace rsph::paper
