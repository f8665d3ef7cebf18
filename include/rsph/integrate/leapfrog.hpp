#pragma once
// The kick-drift-kick leapfrog of one global step: the first half kick and the drift, then (after the
// caller has evaluated the rates at the drifted positions) the second half kick. Frozen particles are
// left to their prescribed motion.
#include "rsph/boundary/walls.hpp"
#include "rsph/core/particle_set.hpp"

#include <algorithm>
#include <vector>

namespace rsph::integrate {

/// The half-step state a leapfrog step carries from its drift to its closing kick.
template <int D, bool E>
struct LeapfrogWorkspace {
  std::vector<Vec<D>> v_half;
  typename ParticleSet<D, E>::EnergyField u_half;
  std::vector<double> rho_half;  ///< only when the density is integrated (continuity equation)
};

/// Half kick, drift by dt (kept inside the box), and the predicted end-of-step v (and u, rho) that the
/// rates are evaluated with. evolve_rho: rho follows d rho/dt like u.
template <bool evolve_rho, int D, bool E>
void kick_drift(ParticleSet<D, E>& p, const Box<D>& box, double dt, const std::vector<double>& drho_dt,
                LeapfrogWorkspace<D, E>& w) {
  const std::size_t n = p.n_real;
  w.v_half.resize(n);
  if constexpr (E) w.u_half.resize(n);
  if constexpr (evolve_rho) w.rho_half.resize(n);
  for (std::size_t a = 0; a < n; ++a) {
    if (p.frozen[a]) continue;
    if constexpr (evolve_rho) {  // the continuity equation, integrated like u
      w.rho_half[a] = p.rho[a] + 0.5 * dt * drho_dt[a];
      p.rho[a] = w.rho_half[a] + 0.5 * dt * drho_dt[a];
    }
    w.v_half[a] = p.v[a] + 0.5 * dt * p.dv_dt[a];
    p.x[a] += dt * w.v_half[a];
    boundary::keep_inside(box, p.x[a], w.v_half[a]);
    p.v[a] = w.v_half[a] + 0.5 * dt * p.dv_dt[a];  // predicted end-of-step velocity for the rates
    if constexpr (E) {
      w.u_half[a] = p.u[a] + 0.5 * dt * p.du_dt[a];
      p.u[a] = std::max(0.0, w.u_half[a] + 0.5 * dt * p.du_dt[a]);
    }
  }
}

/// The closing half kick with the rates at the end of the step.
template <bool evolve_rho, int D, bool E>
void closing_kick(ParticleSet<D, E>& p, double dt, const std::vector<double>& drho_dt,
                  const LeapfrogWorkspace<D, E>& w) {
  for (std::size_t a = 0; a < p.n_real; ++a) {
    if (p.frozen[a]) continue;
    p.v[a] = w.v_half[a] + 0.5 * dt * p.dv_dt[a];
    if constexpr (E) p.u[a] = w.u_half[a] + 0.5 * dt * p.du_dt[a];
    if constexpr (evolve_rho) p.rho[a] = w.rho_half[a] + 0.5 * dt * drho_dt[a];
  }
}

}  // namespace rsph::integrate
