#pragma once
// Conserved totals over the real particles.
#include "rsph/core/dimension.hpp"
#include "rsph/core/particle_set.hpp"

#include <cmath>
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

}  // namespace rsph
