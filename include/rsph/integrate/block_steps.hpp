#pragma once
// Individual time steps in power-of-two bins (TimeStepParams::max_bin > 0): every particle steps in the
// longest bin dt_block / 2^k its own Courant and force conditions allow, kick-drift-kick with its own step;
// all drift on the finest step. Between its steps a particle's density is predicted by the continuity
// equation from its last evaluation. This file plans a block and moves the particles; the caller evaluates
// the rates of the particles whose step ends (active()) after each substep, and all of them at the last.
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/integrate/leapfrog.hpp"
#include "rsph/integrate/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace rsph::integrate {

template <int D, bool E>
class BlockSteps {
 public:
  /// A block of n_sub substeps of length delta.
  struct Plan {
    std::uint64_t n_sub = 1;
    double delta = 0.0, block = 0.0;
  };

  /// The block, at most `limit` long, and each particle's bin. `time` names the moment in errors.
  /// `over_all(lo, hi)` turns the shortest and longest finite limits of these particles into those of all that
  /// step together (on many ranks a minimum and a maximum over the ranks), so every rank plans the same block.
  template <class OverAll>
  Plan plan(const ParticleSet<D, E>& p, const std::vector<double>& v_sig, const TimeStepParams& params, double limit,
            double time, OverAll&& over_all) {
    const std::size_t n = p.n_real;
    double dt_lo = std::numeric_limits<double>::infinity(), dt_hi = 0.0;
    dt_own_.assign(n, std::numeric_limits<double>::infinity());
#pragma omp parallel for schedule(static) reduction(min : dt_lo) reduction(max : dt_hi) if (n >= kParallelMin)
    for (std::size_t a = 0; a < n; ++a) {
      if (p.frozen[a]) continue;
      dt_own_[a] = particle_time_step(p, v_sig, params, a);
      dt_lo = std::min(dt_lo, dt_own_[a]);
      if (std::isfinite(dt_own_[a])) dt_hi = std::max(dt_hi, dt_own_[a]);
    }
    over_all(dt_lo, dt_hi);
    if (!std::isfinite(dt_lo))
      throw InputError("no time-step constraint: nothing moves or exerts force; set TimeStepParams::dt_max");
    int K = 0;
    while (K < params.max_bin && dt_lo * double(std::uint64_t{2} << K) <= dt_hi) ++K;
    Plan plan;
    plan.block = dt_lo * double(std::uint64_t{1} << K);
    if (plan.block > limit) {  // a shorter block, still with its finest step within every particle's limit
      plan.block = limit;
      K = 0;
      while (K < params.max_bin && plan.block / double(std::uint64_t{1} << K) > dt_lo) ++K;
    }
    plan.n_sub = std::uint64_t{1} << K;
    plan.delta = plan.block / double(plan.n_sub);
    check_time_step(plan.delta, params, time);
    assign_bins(n, plan);
    half.v_half.resize(n);
    if constexpr (E) half.u_half.resize(n);
    step_start_.assign(n, 0);
    return plan;
  }

  /// Substep `sub`: the first half kick of the particles whose step begins, the drift of all by delta, the
  /// predicted v (and u) at the substep's end; active() then lists the particles whose step ends.
  void drift(ParticleSet<D, E>& p, const Box<D>& box, std::uint64_t sub, double delta) {
    const std::size_t n = p.n_real;
    ends_now_.assign(n, 0);
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::size_t a = 0; a < n; ++a) {
      if (p.frozen[a]) continue;
      const double dt_a = delta * double(stride_[a]);
      if (sub % stride_[a] == 0) {  // its step begins: first half kick
        step_start_[a] = sub;
        half.v_half[a] = p.v[a] + 0.5 * dt_a * p.dv_dt[a];
        if constexpr (E) half.u_half[a] = p.u[a] + 0.5 * dt_a * p.du_dt[a];
      }
      p.x[a] += delta * half.v_half[a];
      boundary::keep_inside(box, p.x[a], half.v_half[a]);
      // predicted velocity (and energy) at the end of this substep, for the pair terms
      const double lead = double(sub + 1 - step_start_[a]) * delta - 0.5 * dt_a;
      p.v[a] = half.v_half[a] + lead * p.dv_dt[a];
      if constexpr (E) p.u[a] = std::max(0.0, half.u_half[a] + lead * p.du_dt[a]);
      ends_now_[a] = (sub + 1) % stride_[a] == 0;
    }
    active_.clear();
    for (std::size_t a = 0; a < n; ++a)
      if (ends_now_[a]) active_.push_back(static_cast<std::uint32_t>(a));
  }

  /// The particles whose step ends with the last drift, in index order.
  const std::vector<std::uint32_t>& active() const { return active_; }

  /// Their closing half kick, with the rates just evaluated.
  void closing_kicks(ParticleSet<D, E>& p, double delta) const {
    for (const std::uint32_t a : active_) {
      const double dt_a = delta * double(stride_[a]);
      p.v[a] = half.v_half[a] + 0.5 * dt_a * p.dv_dt[a];
      if constexpr (E) p.u[a] = half.u_half[a] + 0.5 * dt_a * p.du_dt[a];
    }
  }

  /// Every particle's density was evaluated now.
  void evaluated_all(const ParticleSet<D, E>& p, double time) {
    rho_eval_.assign(p.rho.begin(), p.rho.begin() + static_cast<std::ptrdiff_t>(p.n_real));
    t_eval_.assign(p.n_real, time);
  }
  /// The active particles' densities were evaluated now.
  void evaluated_active(const ParticleSet<D, E>& p, double time) {
    for (const std::uint32_t a : active_) {
      rho_eval_[a] = p.rho[a];
      t_eval_[a] = time;
    }
  }
  /// The density of each particle outside `rows` (row[a] < 0), predicted from its last evaluation.
  void predict_density(ParticleSet<D, E>& p, const std::vector<std::int32_t>& row, double time,
                       const std::vector<double>& drho_dt) const {
    const std::size_t n = p.n_real;
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::size_t a = 0; a < n; ++a)
      if (row[a] < 0) p.rho[a] = std::max(rho_eval_[a] + (time - t_eval_[a]) * drho_dt[a], 0.01 * rho_eval_[a]);
  }

  LeapfrogWorkspace<D, E> half;  ///< each particle's half-step state

 private:
  /// Each particle's bin: the longest step 2^-k of the block within its own limit.
  void assign_bins(std::size_t n, const Plan& plan) {
    stride_.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::size_t a = 0; a < n; ++a) {
      stride_[a] = plan.n_sub;
      while (stride_[a] > 1 && plan.delta * double(stride_[a]) > dt_own_[a]) stride_[a] >>= 1;
    }
  }

  std::vector<double> dt_own_, rho_eval_, t_eval_;  ///< per-particle limits; last evaluated density and its time
  std::vector<std::uint64_t> stride_, step_start_;  ///< in finest substeps
  std::vector<std::uint32_t> active_;
  std::vector<std::uint8_t> ends_now_;  ///< per particle: whether its step ends with this substep
};

}  // namespace rsph::integrate
