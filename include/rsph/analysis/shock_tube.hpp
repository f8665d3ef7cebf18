#pragma once
// Errors of a shock-tube run against the exact Riemann solution.
#include "rsph/analysis/riemann.hpp"
#include "rsph/core/particle_set.hpp"

#include <cmath>

namespace rsph::analysis {

struct ShockTubeErrors {
  double L1_rho = 0, L1_v = 0, L1_P = 0;
};

/// Volume-weighted L1 errors against the exact solution: sum_a V_a |f_a - f(x_a)| / sum_a V_a with
/// V_a = m_a / rho_a, an estimate of (1/L) integral |f - f_exact| dx over the tube.
template <int D, bool E>
ShockTubeErrors shock_tube_errors(const ParticleSet<D, E>& p, const ExactRiemann& exact, double t, double x0) {
  ShockTubeErrors e;
  double vol = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const double V = p.m[a] / p.rho[a];
    const auto q = exact.sample((p.x[a][0] - x0) / t);
    e.L1_rho += V * std::abs(p.rho[a] - q.rho);
    e.L1_v += V * std::abs(p.v[a][0] - q.v);
    e.L1_P += V * std::abs(p.P[a] - q.P);
    vol += V;
  }
  e.L1_rho /= vol;
  e.L1_v /= vol;
  e.L1_P /= vol;
  return e;
}

}  // namespace rsph::analysis
