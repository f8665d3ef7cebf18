#pragma once
// Conserved totals over the real particles, and the checks of their fields at the start and during a run.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace rsph {

template <int D>
struct Conservation {
  double mass = 0.0;
  Vec<D> momentum = Vec<D>::Zero();
  double angular_momentum = 0.0;  ///< z-component about the origin (zero in 1D; L_z in 3D)
  double kinetic = 0.0;
  double thermal = 0.0;  ///< sum m u, zero for gases without u
  double total_energy() const { return kinetic + thermal; }
};

template <int D, bool E>
Conservation<D> conservation(const ParticleSet<D, E>& p) {
  Conservation<D> c;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    c.mass += p.m[a];
    c.momentum += p.m[a] * p.v[a];
    if constexpr (D >= 2) c.angular_momentum += p.m[a] * (p.x[a][0] * p.v[a][1] - p.x[a][1] * p.v[a][0]);
    c.kinetic += 0.5 * p.m[a] * p.v[a].squaredNorm();
    if constexpr (E) c.thermal += p.m[a] * p.u[a];
  }
  return c;
}

/// Index of the first real particle with a non-finite or unphysical field, and the field's name;
/// {size_t max, ""} when all is well.
template <int D, bool E>
std::pair<std::size_t, std::string> first_unphysical(const ParticleSet<D, E>& p) {
  for (std::size_t a = 0; a < p.n_real; ++a) {
    if (!p.x[a].allFinite()) return {a, "position is not finite"};
    if (!p.v[a].allFinite()) return {a, "velocity is not finite"};
    if (!std::isfinite(p.rho[a]) || !(p.rho[a] > 0.0)) return {a, "density is not positive and finite"};
    if (!std::isfinite(p.h[a]) || !(p.h[a] > 0.0)) return {a, "smoothing length is not positive and finite"};
    if constexpr (E)
      if (!std::isfinite(p.u[a]) || p.u[a] < 0.0) return {a, "internal energy is negative or not finite"};
  }
  return {std::numeric_limits<std::size_t>::max(), ""};
}

/// What is unphysical about the particles of `p` after step `step` at time t: the first such particle and its
/// field, in words; empty when all is well.
template <int D, bool E>
std::string unphysical_after(const ParticleSet<D, E>& p, double t, std::uint64_t step) {
  const auto [a, what] = first_unphysical(p);
  if (what.empty()) return what;
  return "particle " + std::to_string(a) + ": " + what + " at t = " + std::to_string(t) + " (step " +
         std::to_string(step) + ")";
}

/// Initial data a run can start from: particles, no ghosts, a non-empty box, and for every particle a
/// positive finite m and h, finite x and v, u >= 0, x inside the box on each closed axis, and rho > 0 when
/// the density is evolved from its initial value (need_rho). Throws InputError naming the particle.
template <int D, bool E>
void validate_initial_particles(const ParticleSet<D, E>& p, const Box<D>& box, bool need_rho) {
  require(p.n_real > 0, "the domain holds no particles");
  require(p.n_real == p.size_with_ghosts(), "initial particle sets must not contain ghosts");
  for (int k = 0; k < D; ++k)
    require(box.hi[k] > box.lo[k], "the box is empty along axis " + std::to_string(k) + " (hi <= lo)");
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const std::string who = "particle " + std::to_string(a) + ": ";
    require(p.m[a] > 0.0 && std::isfinite(p.m[a]), who + "mass must be positive and finite");
    require(p.h[a] > 0.0 && std::isfinite(p.h[a]), who + "smoothing length h must be positive and finite");
    require(p.x[a].allFinite() && p.v[a].allFinite(), who + "position and velocity must be finite");
    if constexpr (E) require(p.u[a] >= 0.0 && std::isfinite(p.u[a]), who + "internal energy must be non-negative");
    if (need_rho)
      require(p.rho[a] > 0.0 && std::isfinite(p.rho[a]),
              who + "consistent gradients evolve the density from its initial value: give rho > 0 (m / V)");
    for (int k = 0; k < D; ++k)
      if (box.edge[k] != Edge::open)
        require(p.x[a][k] >= box.lo[k] && p.x[a][k] <= box.hi[k],
                who + "lies outside the box along axis " + std::to_string(k));
  }
}

}  // namespace rsph
