#pragma once
// Time-step criteria: Courant on the signal speed and the force condition (Monaghan 1992 §10).
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace rsph {

struct TimeStepParams {
  double courant = 0.3;  ///< dt <= courant * h_a / v_sig_a
  double force = 0.25;   ///< dt <= force * sqrt(h_a / |dv_a/dt|)
  double dt_max = std::numeric_limits<double>::infinity();
  double dt_min = 0.0;           ///< a step below this is an error: the run has gone bad
  bool check_every_step = true;  ///< stop with a NumericalError at the first NaN or negative density/energy
  /// Individual time steps: each particle steps in a power-of-two bin dt_block / 2^k with k <= max_bin
  /// (0: one global step for all).
  int max_bin = 0;

  void validate() const {
    require(courant > 0.0 && courant <= 1.0,
            "time step: Courant factor must lie in (0, 1] (got " + std::to_string(courant) + ")");
    require(force > 0.0, "time step: force factor must be positive");
    require(dt_max > 0.0, "time step: dt_max must be positive");
    require(max_bin >= 0 && max_bin <= 12,
            "time step: max_bin must lie in [0, 12] (got " + std::to_string(max_bin) + ")");
  }
};

/// A step that is no step at all (nothing constrains it) is an input error; one at or below dt_min means
/// the run has gone bad. `time` names the moment.
inline void check_time_step(double dt, const TimeStepParams& params, double time) {
  if (!std::isfinite(dt))
    throw InputError("no time-step constraint: nothing moves or exerts force; set TimeStepParams::dt_max");
  if (!(dt > params.dt_min))
    throw NumericalError("time step " + std::to_string(dt) + " fell below the minimum " +
                         std::to_string(params.dt_min) + " at t = " + std::to_string(time));
}

/// The Courant and force conditions of particle a, capped by dt_max.
template <int D, bool E>
double particle_time_step(const ParticleSet<D, E>& p, const std::vector<double>& v_sig, const TimeStepParams& params,
                          std::size_t a) {
  double dt = params.dt_max;
  if (v_sig[a] > 0.0) dt = std::min(dt, params.courant * p.h[a] / v_sig[a]);
  const double acc = p.dv_dt[a].norm();
  if (acc > 0.0) dt = std::min(dt, params.force * std::sqrt(p.h[a] / acc));
  return dt;
}

/// min over real, integrated particles of the Courant and force conditions, capped by dt_max.
template <int D, bool E>
double stable_time_step(const ParticleSet<D, E>& p, const std::vector<double>& v_sig, const TimeStepParams& params) {
  double dt = params.dt_max;
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (!p.frozen[a]) dt = std::min(dt, particle_time_step(p, v_sig, params, a));
  return dt;
}

}  // namespace rsph
