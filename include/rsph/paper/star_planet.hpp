#pragma once
// §5 of the paper (after de Val-Borro et al. 2006): a star and a planet on a fixed circular orbit about
// their common centre of mass, the planet's mass ramped in by eq. (20), its potential Plummer-softened.
// The orbit lies in the plane z = 0: in 3D the same pull acts on gas above and below it.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace rsph::paper {

/// A point of the orbit's plane in D dimensions: (x, y) or (x, y, 0).
template <int D>
Vec<D> in_dim(const Vec<2>& x) {
  static_assert(D == 2 || D == 3, "the star and planet orbit in the plane z = 0 of a 2D or 3D disk");
  if constexpr (D == 2)
    return x;
  else
    return Vec<3>(x.x(), x.y(), 0.0);
}

struct StarAndPlanet {
  double M_star = 1.0;
  double q = 1e-3;           ///< M_p / (M_* + M_p)
  double a = 1.0;            ///< orbital radius of the planet
  double softening = 0.03;   ///< of the planet's potential, in units of a
  double ramp_orbits = 5.0;  ///< eq. (20): M_p sin^2(pi t / (2 ramp_orbits P_p)) until ramp_orbits P_p

  void validate() const {
    require(M_star > 0.0, "star and planet: the star's mass must be positive");
    require(q >= 0.0 && q < 1.0,
            "star and planet: q = M_p / (M_* + M_p) must lie in [0, 1) (got " + std::to_string(q) + ")");
    require(a > 0.0, "star and planet: the orbital radius must be positive");
    require(softening >= 0.0, "star and planet: the softening must be non-negative");
    require(ramp_orbits >= 0.0, "star and planet: the ramp length must be non-negative");
  }
  double planet_mass() const { return q / (1.0 - q) * M_star; }
  /// Angular velocity of the fixed orbit, set by the full planet mass throughout.
  double Omega_p() const { return std::sqrt((M_star + planet_mass()) / (a * a * a)); }
  double period() const { return 2.0 * std::numbers::pi / Omega_p(); }
  /// Eq. (20): the planet mass at time t.
  double planet_mass_at(double t) const {
    const double ramp = ramp_orbits * period();
    if (t >= ramp || ramp <= 0.0) return planet_mass();
    const double s = std::sin(0.5 * std::numbers::pi * t / ramp);
    return planet_mass() * s * s;
  }
  /// Azimuth of the planet at time t (it starts on the +x axis).
  double planet_phase(double t) const { return Omega_p() * t; }
  Vec<2> planet_position(double t) const {
    const double r = a * (1.0 - q), phi = planet_phase(t);
    return {r * std::cos(phi), r * std::sin(phi)};
  }
  Vec<2> star_position(double t) const {
    const double r = -a * q, phi = planet_phase(t);
    return {r * std::cos(phi), r * std::sin(phi)};
  }
  /// The pull at one instant: both bodies placed and the planet's mass ramped once.
  struct AtTime {
    Vec<2> star, planet;
    double M_star, M_planet, eps2;
    /// Point-mass gravity of the star plus the softened planet at x, a point in the plane (D = 2) or in space
    /// (D = 3), or an expression of one.
    template <class X, int D = X::RowsAtCompileTime>
    Vec<D> acceleration(const Eigen::MatrixBase<X>& x) const {
      const Vec<D> d_s = x - in_dim<D>(star), d_p = x - in_dim<D>(planet);
      const double r2_s = d_s.squaredNorm();
      const double r2_p = d_p.squaredNorm() + eps2;
      return (-M_star / (r2_s * std::sqrt(r2_s))) * d_s + (-M_planet / (r2_p * std::sqrt(r2_p))) * d_p;
    }
  };
  AtTime at(double t) const {
    const double eps = softening * a;
    return {star_position(t), planet_position(t), M_star, planet_mass_at(t), eps * eps};
  }
  template <class X, int D = X::RowsAtCompileTime>
  Vec<D> acceleration(const Eigen::MatrixBase<X>& x, double t) const {
    return at(t).acceleration(x);
  }
};

}  // namespace rsph::paper
