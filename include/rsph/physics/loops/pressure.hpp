#pragma once
// The pressure pass after a density sum: P and c_s from the equation of state for every real particle,
// ghosts refreshed from their sources, and P / rho^2 of every point for the force pass.
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/eos/concept.hpp"
#include "rsph/physics/loops/scheme.hpp"

#include <vector>

namespace rsph::physics::loops {

template <int D, class EOS, bool E>
void update_pressure(const EOS& eos, ParticleSet<D, E>& p, std::vector<double>& P_over_rho2) {
  const std::size_t n = p.n_real;
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (std::size_t a = 0; a < n; ++a) {
    const GasState g = gas_state<EOS, D>(eos, p.rho[a], energy_of<E>(p, a), p.x[a]);
    p.P[a] = g.P;
    p.cs[a] = g.cs;
  }
  boundary::refresh_ghosts(p);
  if constexpr (exerts_pressure<EOS>()) {  // the pair loops read it only for a gas that pushes
    const std::size_t n_all = p.size_with_ghosts();
    P_over_rho2.resize(n_all);
#pragma omp parallel for schedule(static) if (n_all >= kParallelMin)
    for (std::size_t a = 0; a < n_all; ++a) P_over_rho2[a] = p.P[a] / (p.rho[a] * p.rho[a]);
  }
}

}  // namespace rsph::physics::loops
