#pragma once
// Composes the policies into a simulation. Owns the policies and the particle set, nothing else:
// pair physics live in physics/, neighbour search in neighbors/, ghosts in boundary/.
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/conjugate_gradient.hpp"
#include "rsph/core/diagnostics.hpp"
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/eos/concept.hpp"
#include "rsph/integrate/time_step.hpp"
#include "rsph/kernel/concept.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/cell_list.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/physics/concept.hpp"
#include "rsph/physics/consistent_gradient.hpp"
#include "rsph/physics/hydro.hpp"
#include "rsph/physics/shear_viscosity.hpp"
#include "rsph/physics/smoothing_length.hpp"
#include "rsph/regularize/concept.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace rsph {

/// Seconds spent in each phase, accumulated over the run.
struct PhaseTimes {
  double neighbors = 0.0, density = 0.0, forces = 0.0, integrate = 0.0, regularization = 0.0;
  double total() const { return neighbors + density + forces + integrate + regularization; }
};

template <int D, class Kernel, class EOS, class Reg, class... Terms>
requires SupportedDimension<D>
class Simulation {
  static_assert(check_kernel<Kernel, D>());
  static_assert(check_equation_of_state<EOS, D>());
  static_assert(check_regularizer<Reg, D, EOS::has_internal_energy>());
  static_assert((check_term<Terms, D>() && ...));
  static_assert(((!requires { Terms::needs_internal_energy; } || EOS::has_internal_energy) && ...),
                "a term that conducts heat needs an equation of state that carries internal energy");

 public:
  static constexpr int dim = D;
  static constexpr bool has_energy = EOS::has_internal_energy;
  /// Pressureless gas skips the pressure terms of the pair loops (eos/concept.hpp).
  static constexpr bool has_pressure = exerts_pressure<EOS>();
  /// Equal-mass SPH with h solved from the density (a SmoothingLengthSolver term); otherwise h is fixed
  /// between regularizations and pairs use h_ab = (h_a + h_b) / 2 as in the paper.
  static constexpr bool grad_h = (SmoothingLengthSolver<Terms> || ...);
  static_assert((int(SmoothingLengthSolver<Terms>) + ... + 0) <= 1,
                "a simulation takes at most one smoothing-length solver");
  /// A viscous stress term (Navier-Stokes) adds a velocity-gradient pass before the force sum.
  static constexpr bool has_stress = (StressTerm<Terms, D> || ...);
  static_assert((int(StressTerm<Terms, D>) + ... + 0) <= 1, "a simulation takes at most one viscous stress term");
  /// Consistent pair gradients (physics/consistent_gradient.hpp): the density follows the continuity
  /// equation from the remapped rho = m / V, and pairs use G_ab, so uniform states are exact equilibria.
  static constexpr bool corrected = (GradientCorrection<Terms> || ...);
  static_assert((int(GradientCorrection<Terms>) + ... + 0) <= 1, "a simulation takes at most one gradient correction");
  static_assert(!(corrected && grad_h),
                "consistent gradients need fixed smoothing lengths (no smoothing-length solver)");
  /// Boundary zones (gas on fixed orbits) choose their members whenever the particle set is rebuilt.
  static constexpr bool has_zones = (BoundaryZone<Terms, D> || ...);
  using Particles = ParticleSet<D, has_energy>;
  using KernelType = Kernel;
  /// The density pass also sums n_a of eq. (A1) when the regularizer's schedule uses it (fixed h only).
  static constexpr bool wants_number_density = !grad_h && requires { requires Reg::wants_number_density; };

  Simulation(Particles particles, Box<D> box, EOS eos, Reg reg, TimeStepParams params, Terms... terms)
      : p_(std::move(particles)),
        box_(box),
        eos_(std::move(eos)),
        reg_(std::move(reg)),
        params_(params),
        terms_(std::move(terms)...) {
    validate();
    mark_zone_members();
    compute_rates();
  }

  const Particles& particles() const { return p_; }
  /// Mutable access for scene set-up between steps; call compute_rates() after changing fields.
  Particles& particles() { return p_; }
  const Box<D>& box() const { return box_; }
  const EOS& eos() const { return eos_; }
  const Reg& regularizer() const { return reg_; }
  Reg& regularizer() { return reg_; }
  const neighbors::NeighborList& neighbor_list() const { return nl_; }
  /// n_a of eq. (A1) from the last density pass (only when the regularizer wants it).
  const std::vector<double>& number_density() const requires wants_number_density { return number_density_; }
  double time() const { return time_; }
  std::uint64_t steps() const { return step_; }
  std::uint64_t particle_updates() const { return particle_updates_; }
  std::uint64_t regularizations() const { return regularizations_; }
  double kinetic_energy_removed() const { return kinetic_removed_; }
  const PhaseTimes& phase_times() const { return times_; }
  /// The last psi solve of the gradient correction (summed over axes), and the solves so far.
  const CgResult& gradient_solve() const requires corrected { return psi_solve_; }
  std::uint64_t gradient_solves() const requires corrected { return psi_solves_; }
  std::uint64_t gradient_solve_iterations() const requires corrected { return psi_iterations_; }
  Conservation<D> totals() const { return conservation(p_); }

  /// The next time step: the Courant and force conditions over all real, integrated particles.
  double time_step() const { return stable_time_step(p_, v_sig_, params_); }

  /// One kick-drift-kick leapfrog step of at most dt_limit; regularizes afterwards when due.
  /// Returns the step taken.
  double step(double dt_limit = std::numeric_limits<double>::infinity()) {
    if (params_.max_bin > 0) return block_step(dt_limit);
    double dt = std::min(time_step(), dt_limit);
    if constexpr (requires { reg_.time_until_due(info_); }) {
      const double left = reg_.time_until_due(info_);  // land on a time-based regularization exactly
      if (left > 0.0) dt = std::min(dt, left);
    }
    if (!std::isfinite(dt))
      throw InputError("no time-step constraint: nothing moves or exerts force; set TimeStepParams::dt_max");
    if (!(dt > params_.dt_min))
      throw NumericalError("time step " + std::to_string(dt) + " fell below the minimum " +
                           std::to_string(params_.dt_min) + " at t = " + std::to_string(time_));
    auto t0 = clock::now();
    const std::size_t n = p_.n_real;
    v_half_.resize(n);
    if constexpr (has_energy) u_half_.resize(n);
    if constexpr (corrected) rho_half_.resize(n);
    for (std::size_t a = 0; a < n; ++a) {
      if (p_.frozen[a]) continue;
      if constexpr (corrected) {  // the continuity equation, integrated like u
        rho_half_[a] = p_.rho[a] + 0.5 * dt * drho_dt_[a];
        p_.rho[a] = rho_half_[a] + 0.5 * dt * drho_dt_[a];
      }
      v_half_[a] = p_.v[a] + 0.5 * dt * p_.dv_dt[a];
      p_.x[a] += dt * v_half_[a];
      keep_inside(a);
      p_.v[a] = v_half_[a] + 0.5 * dt * p_.dv_dt[a];  // predicted end-of-step velocity for the rates
      if constexpr (has_energy) {
        u_half_[a] = p_.u[a] + 0.5 * dt * p_.du_dt[a];
        p_.u[a] = std::max(0.0, u_half_[a] + 0.5 * dt * p_.du_dt[a]);
      }
    }
    time_ += dt;
    prescribe_frozen(dt);
    times_.integrate += seconds_since(t0);
    compute_rates();
    t0 = clock::now();
    for (std::size_t a = 0; a < n; ++a) {
      if (p_.frozen[a]) continue;
      p_.v[a] = v_half_[a] + 0.5 * dt * p_.dv_dt[a];
      if constexpr (has_energy) p_.u[a] = u_half_[a] + 0.5 * dt * p_.du_dt[a];
      if constexpr (corrected) p_.rho[a] = rho_half_[a] + 0.5 * dt * drho_dt_[a];
    }
    times_.integrate += seconds_since(t0);
    ++step_;
    ++info_.steps_since_last;
    info_.time_since_last += dt;
    particle_updates_ += n;
    finish_step();
    return dt;
  }

  /// After a step (or a block of them): the regularizer's turn, then the physical check.
  void finish_step() {
    info_.step = step_;
    info_.time = time_;
    info_.neighbors = &nl_;
    if constexpr (wants_number_density) {
      info_.number_density = &number_density_;
      info_.pair_kernel = pair_kernel_full_ ? &pair_kernel_ : nullptr;
    }
    const auto t0 = clock::now();
    const bool due = reg_.due(p_, box_, info_);  // an adaptive schedule's check is regularization cost too
    times_.regularization += seconds_since(t0);
    if (due) regularize_now();
    if (params_.check_every_step) check_physical();
  }

  /// One block of individual time steps (TimeStepParams::max_bin > 0) of at most dt_limit: every
  /// particle steps in the power-of-two bin its own Courant and force conditions allow, kick-drift-kick
  /// with its own step; all drift on the finest step. A particle is evaluated (neighbours, density,
  /// forces) only when its step ends; between, its density is predicted by the continuity equation.
  /// At the end of the block all are synchronised, evaluated afresh, and the regularizer may act.
  /// Returns the block's length.
  double block_step(double dt_limit) {
    const std::size_t n = p_.n_real;
    auto t0 = clock::now();
    double dt_lo = std::numeric_limits<double>::infinity(), dt_hi = 0.0;
    dt_own_.assign(n, std::numeric_limits<double>::infinity());
#pragma omp parallel for schedule(static) reduction(min : dt_lo) reduction(max : dt_hi)
    for (std::size_t a = 0; a < n; ++a) {
      if (p_.frozen[a]) continue;
      dt_own_[a] = particle_time_step(p_, v_sig_, params_, a);
      dt_lo = std::min(dt_lo, dt_own_[a]);
      if (std::isfinite(dt_own_[a])) dt_hi = std::max(dt_hi, dt_own_[a]);
    }
    if (!std::isfinite(dt_lo))
      throw InputError("no time-step constraint: nothing moves or exerts force; set TimeStepParams::dt_max");
    int K = 0;
    while (K < params_.max_bin && dt_lo * double(std::uint64_t{2} << K) <= dt_hi) ++K;
    double block = dt_lo * double(std::uint64_t{1} << K);
    double limit = dt_limit;
    if constexpr (requires { reg_.time_until_due(info_); }) {
      const double left = reg_.time_until_due(info_);  // land on a time-based regularization exactly
      if (left > 0.0) limit = std::min(limit, left);
    }
    if (block > limit) {  // a shorter block, still with its finest step within every particle's limit
      block = limit;
      K = 0;
      while (K < params_.max_bin && block / double(std::uint64_t{1} << K) > dt_lo) ++K;
    }
    const std::uint64_t n_sub = std::uint64_t{1} << K;
    const double delta = block / double(n_sub);
    if (!(delta > params_.dt_min))
      throw NumericalError("time step " + std::to_string(delta) + " fell below the minimum " +
                           std::to_string(params_.dt_min) + " at t = " + std::to_string(time_));
    // Each particle's bin: the longest step 2^-k of the block within its own limit.
    stride_.resize(n);
#pragma omp parallel for schedule(static)
    for (std::size_t a = 0; a < n; ++a) {
      stride_[a] = n_sub;
      while (stride_[a] > 1 && delta * double(stride_[a]) > dt_own_[a]) stride_[a] >>= 1;
    }
    v_half_.resize(n);
    if constexpr (has_energy) u_half_.resize(n);
    step_start_.assign(n, 0);
    times_.integrate += seconds_since(t0);
    for (std::uint64_t sub = 0; sub < n_sub; ++sub) {
      t0 = clock::now();
      const bool sync = sub + 1 == n_sub;
      ends_now_.assign(n, 0);
#pragma omp parallel for schedule(static)
      for (std::size_t a = 0; a < n; ++a) {
        if (p_.frozen[a]) continue;
        const double dt_a = delta * double(stride_[a]);
        if (sub % stride_[a] == 0) {  // its step begins: first half kick
          step_start_[a] = sub;
          v_half_[a] = p_.v[a] + 0.5 * dt_a * p_.dv_dt[a];
          if constexpr (has_energy) u_half_[a] = p_.u[a] + 0.5 * dt_a * p_.du_dt[a];
        }
        p_.x[a] += delta * v_half_[a];
        keep_inside(a);
        // predicted velocity (and energy) at the end of this substep, for the pair terms
        const double lead = double(sub + 1 - step_start_[a]) * delta - 0.5 * dt_a;
        p_.v[a] = v_half_[a] + lead * p_.dv_dt[a];
        if constexpr (has_energy) p_.u[a] = std::max(0.0, u_half_[a] + lead * p_.du_dt[a]);
        ends_now_[a] = (sub + 1) % stride_[a] == 0;
      }
      active_.clear();
      for (std::size_t a = 0; a < n; ++a)
        if (ends_now_[a]) active_.push_back(static_cast<std::uint32_t>(a));
      time_ += delta;
      prescribe_frozen(delta);
      times_.integrate += seconds_since(t0);
      if (sync)
        compute_rates();
      else
        compute_rates_of_active();
      t0 = clock::now();
      for (const std::uint32_t a : active_) {  // its step ends: second half kick
        const double dt_a = delta * double(stride_[a]);
        p_.v[a] = v_half_[a] + 0.5 * dt_a * p_.dv_dt[a];
        if constexpr (has_energy) p_.u[a] = u_half_[a] + 0.5 * dt_a * p_.du_dt[a];
      }
      times_.integrate += seconds_since(t0);
      particle_updates_ += sync ? n : active_.size();
      ++step_;
      ++info_.steps_since_last;
      info_.time_since_last += delta;
    }
    finish_step();
    return block;
  }

  /// Regularizes now, whatever the schedule says.
  void regularize_now() {
    const auto t0 = clock::now();
    p_.clear_ghosts();
    kinetic_removed_ += reg_.remap(p_, box_);
    if constexpr (corrected) psi_.clear();  // new particles: solve afresh
    mark_zone_members();
    ++regularizations_;
    info_.steps_since_last = 0;
    info_.time_since_last = 0.0;
    times_.regularization += seconds_since(t0);
    compute_rates();
  }

  /// Steps until t_end, calling on_step(*this) after each step.
  template <class OnStep>
  void run_until(double t_end, OnStep&& on_step) {
    while (time_ < t_end * (1.0 - 1e-14)) {
      step(t_end - time_);
      on_step(*this);
    }
  }
  void run_until(double t_end) {
    run_until(t_end, [](const Simulation&) {});
  }

  /// Ghosts, neighbours, density (eq. 2), pressure, then accelerations (eq. 3) and heating (eq. 4).
  void compute_rates() {
    if constexpr (grad_h) {
      // Neighbours with a margin, so h may grow while it is solved; rebuilt if it outgrows the margin.
      for (int attempt = 0;; ++attempt) {
        build_neighbors(kHMargin);
        auto t0 = clock::now();
        const bool fits = solve_density_and_h(kHMargin);
        times_.density += seconds_since(t0);
        if (fits) break;
        if (attempt == 4)
          throw NumericalError("smoothing lengths keep outgrowing their neighbour search at t = " +
                               std::to_string(time_));
      }
      auto t0 = clock::now();
      update_pressure();
      times_.density += seconds_since(t0);
    } else {
      build_neighbors(1.0);
      auto t0 = clock::now();
      if constexpr (corrected) {
        if constexpr (wants_number_density) density_rows(neighbors::FirstN{p_.n_real});  // n_a only
        update_pressure();
      } else {
        compute_density();
      }
      times_.density += seconds_since(t0);
    }
    auto t0 = clock::now();
    if constexpr (corrected) solve_gradient_correction();
    if constexpr (has_stress) compute_stress();
    compute_forces();
    if (params_.max_bin > 0) {
      rho_eval_.assign(p_.rho.begin(), p_.rho.begin() + static_cast<std::ptrdiff_t>(p_.n_real));
      t_eval_.assign(p_.n_real, time_);
    }
    times_.forces += seconds_since(t0);
  }

  /// The viscous stress over rho^2 of every particle (ghosts mirrored) from the velocity gradients
  /// (physics/shear_viscosity.hpp), over current neighbour lists and densities.
  void compute_stress() requires has_stress {
    const std::size_t n = p_.n_real;
    const auto& term = std::get<stress_index()>(terms_);
    S_over_rho2_.resize(p_.size());
#pragma omp parallel for schedule(static)
    for (std::size_t a = 0; a < n; ++a) {
      Mat<D> G = Mat<D>::Zero();
      const double h_a = p_.h[a], inv_h_a = 1.0 / h_a;
      for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k) {
        const std::uint32_t b = nl_.index[k];
        const Vec<D> r_ab = p_.x[a] - p_.x[b];
        const double r = r_ab.norm();
        if (r <= 0.0) continue;
        if constexpr (grad_h)
          if (r >= Kernel::support * std::max(h_a, p_.h[b])) continue;
        G += physics::velocity_gradient_term<D>(p_.m[b], p_.rho[b], p_.v[a] - p_.v[b],
                                                pair_grad_W(r_ab, r, h_a, inv_h_a, p_.h[b]));
      }
      const double rho = p_.rho[a];
      S_over_rho2_[a] = term.stress(G, rho) / (rho * rho);
    }
    // A mirror ghost sees the stress reflected: S' = M S M with M = diag(+-1).
    for (std::size_t g = n; g < p_.size(); ++g) {
      const std::size_t src = p_.ghost_source[g - n];
      Vec<D> sign = Vec<D>::Ones();
      for (int k = 0; k < D; ++k)
        if (box_.edge[k] == Edge::reflecting && p_.x[g][k] != p_.x[src][k]) sign[k] = -1.0;
      S_over_rho2_[g] = sign.asDiagonal() * S_over_rho2_[src] * sign.asDiagonal();
    }
  }

  /// The density sum alone (eq. 2) with P and c_s, over current neighbour lists; for benchmarks.
  void compute_density() {
    density_rows(neighbors::FirstN{p_.n_real});
    update_pressure();
  }

  /// Accelerations and heating rates over current neighbour lists and densities; for benchmarks.
  void compute_forces() {
    if (params_.max_bin > 0 || corrected)
      force_rows<true>(neighbors::FirstN{p_.n_real});
    else
      force_rows<false>(neighbors::FirstN{p_.n_real});
  }

 private:
  /// The density sum (eq. 2) for the points of `rows` (row i of the neighbour lists is point rows[i]).
  template <class Rows>
  void density_rows(const Rows& rows) {
    const auto& x = p_.x;
    const auto& h = p_.h;
    const auto& m = p_.m;
    const std::size_t n_rows = rows.size();
    // The kernel values are kept only from a pass over every particle, the one a schedule looks at.
    constexpr bool keep_pair_kernel = wants_number_density && std::is_same_v<Rows, neighbors::FirstN>;
    if constexpr (wants_number_density) number_density_.resize(p_.n_real);
    if constexpr (keep_pair_kernel) pair_kernel_.resize(nl_.pairs());
    pair_kernel_full_ = keep_pair_kernel;  // a subset pass leaves the kept values stale
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n_rows; ++i) {
      const std::uint32_t a = rows[i];
      const double h_a = h[a], inv_h_a = 1.0 / h_a;
      double rho = m[a] * kernel::W_inv_h<Kernel, D>(0.0, inv_h_a);
      double n_a = 0.0;
      for (auto k = nl_.offset[i]; k < nl_.offset[i + 1]; ++k) {
        const std::uint32_t b = nl_.index[k];
        const double r = (x[a] - x[b]).norm();
        const double W_ab = kernel::W_inv_h<Kernel, D>(r, kernel::inv_h_ab(h_a, inv_h_a, h[b]));
        rho += physics::density_term(m[b], W_ab);
        if constexpr (wants_number_density) {  // eq. (A1), for the regularization schedule
          n_a += W_ab;
          if constexpr (keep_pair_kernel) pair_kernel_[k] = W_ab;
        }
      }
      if constexpr (!corrected) p_.rho[a] = rho;
      if constexpr (wants_number_density) number_density_[a] = n_a;
    }
  }

  /// Accelerations and heating rates of the points of `rows`; with_drho also sums the continuity
  /// equation's d rho / dt, which predicts the density of particles between their steps.
  template <bool with_drho, class Rows>
  void force_rows(const Rows& rows) {
    const std::size_t n = p_.n_real;
    v_sig_.resize(n);
    if constexpr (with_drho) drho_dt_.resize(n);
    const std::size_t n_rows = rows.size();
    const auto forces_now =
        std::apply([&](const auto&... term) { return std::tuple{body_force_now(term)...}; }, terms_);
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n_rows; ++i) {
      const std::uint32_t a = rows[i];
      Vec<D> dv = Vec<D>::Zero();
      double drho = 0.0;
      double du = 0.0;
      double v_sig = p_.cs[a];
      physics::Pair<D> pr;
      pr.m_a = p_.m[a];
      pr.rho_a = p_.rho[a];
      if constexpr (has_pressure) {
        pr.P_a = p_.P[a];
        pr.P_over_rho2_a = P_over_rho2_[a];
      }
      pr.cs_a = p_.cs[a];
      pr.u_a = energy_of(a);
      const double h_a = p_.h[a], inv_h_a = 1.0 / h_a;
      if constexpr (grad_h) pr.Omega_a = Omega_[a];
      for (auto k = nl_.offset[i]; k < nl_.offset[i + 1]; ++k) {
        const std::uint32_t b = nl_.index[k];
        pr.r_ab = p_.x[a] - p_.x[b];
        pr.r = pr.r_ab.norm();
        if (pr.r <= 0.0) continue;
        const double h_b = p_.h[b];
        if constexpr (grad_h)
          if (pr.r >= Kernel::support * std::max(h_a, h_b)) continue;  // inside the search margin only
        pr.v_ab = p_.v[a] - p_.v[b];
        pr.h_ab = 0.5 * (h_a + h_b);
        pr.m_b = p_.m[b];
        pr.rho_b = p_.rho[b];
        if constexpr (has_pressure) {
          pr.P_b = p_.P[b];
          pr.P_over_rho2_b = P_over_rho2_[b];
        }
        pr.cs_b = p_.cs[b];
        pr.u_b = energy_of(b);
        if constexpr (grad_h) {
          pr.grad_W_a = kernel::grad_W_inv_h<Kernel, D>(pr.r_ab, pr.r, inv_h_a);
          pr.grad_W_b = kernel::grad_W<Kernel, D>(pr.r_ab, pr.r, h_b);
          pr.grad_W = 0.5 * (pr.grad_W_a + pr.grad_W_b);
          pr.Omega_b = Omega_[b];
          if constexpr (has_pressure) dv += physics::pressure_acceleration_grad_h(pr);
          if constexpr (has_pressure && has_energy) du += physics::pressure_heating_grad_h(pr);
        } else {
          const double inv_h = kernel::inv_h_ab(h_a, inv_h_a, h_b);
          pr.grad_W = kernel::grad_W_inv_h<Kernel, D>(pr.r_ab, pr.r, inv_h);
          if constexpr (corrected)
            if (band_[a] && band_[b])
              pr.grad_W =
                  physics::consistent_gradient<D>(pr.grad_W, kernel::W_inv_h<Kernel, D>(pr.r, inv_h), psi_[a], psi_[b]);
          if constexpr (corrected)
            drho += physics::continuity_term_by_volume(pr.rho_a, pr.m_b / pr.rho_b, pr.v_ab, pr.grad_W);
          else if constexpr (with_drho)
            drho += physics::continuity_term(pr.m_b, pr.v_ab, pr.grad_W);
          if constexpr (has_pressure) dv += physics::pressure_acceleration(pr);
          if constexpr (has_pressure && has_energy) du += physics::pressure_heating(pr);
        }
        std::apply([&](const auto&... term) { (add_pair_term(term, pr, dv, du, v_sig), ...); }, terms_);
        if constexpr (has_stress) {
          dv += physics::stress_acceleration<D>(pr.m_b, S_over_rho2_[a], S_over_rho2_[b], pr.grad_W);
          if constexpr (has_energy) du += physics::stress_heating<D>(pr.m_b, S_over_rho2_[a], pr.v_ab, pr.grad_W);
        }
      }
      if constexpr (has_stress) v_sig = std::max(v_sig, std::get<stress_index()>(terms_).signal_speed(h_a));
      std::apply([&](const auto&... force) { (add_body_force(force, p_.x[a], dv), ...); }, forces_now);
      p_.dv_dt[a] = dv;
      if constexpr (has_energy) p_.du_dt[a] = du;
      if constexpr (with_drho) drho_dt_[a] = drho;
      v_sig_[a] = v_sig;
    }
  }

  using clock = std::chrono::steady_clock;
  static double seconds_since(clock::time_point t0) { return std::chrono::duration<double>(clock::now() - t0).count(); }

  double energy_of(std::size_t a) const {
    if constexpr (has_energy)
      return p_.u[a];
    else
      return 0.0;
  }

  template <class T>
  static void add_pair_term(const T& term, const physics::Pair<D>& pr, Vec<D>& dv, double& du, double& v_sig) {
    if constexpr (PairTerm<T, D>) {
      const physics::PairRates<D> r = term.pair(pr);
      dv += r.dv_dt;
      if constexpr (has_energy) du += r.du_dt;
      v_sig = std::max(v_sig, r.v_sig);
    }
  }

  /// Each term's body force at the current time (nothing for other terms), taken once per force pass.
  struct NoBodyForce {};
  template <class T>
  struct BodyForceAt {
    const T* term;
    double time;
    Vec<D> acceleration(const Vec<D>& x) const { return term->acceleration(x, time); }
  };
  template <class T>
  auto body_force_now(const T& term) const {
    if constexpr (BodyForceAtTime<T, D>)
      return term.at(time_);
    else if constexpr (BodyForce<T, D>)
      return BodyForceAt<T>{&term, time_};
    else
      return NoBodyForce{};
  }
  template <class F>
  static void add_body_force(const F& force, const Vec<D>& x, Vec<D>& dv) {
    if constexpr (!std::is_same_v<F, NoBodyForce>) dv += force.acceleration(x);
  }

  static constexpr double kHMargin = 1.25;  // search radius over h while h is solved

  /// Position in Terms of the first term of a kind (the kinds that allow at most one).
  static constexpr std::size_t first_of(std::array<bool, sizeof...(Terms)> is_kind) {
    for (std::size_t i = 0; i < is_kind.size(); ++i)
      if (is_kind[i]) return i;
    return 0;
  }
  static constexpr std::size_t solver_index() { return first_of({SmoothingLengthSolver<Terms>...}); }
  static constexpr std::size_t stress_index() { return first_of({StressTerm<Terms, D>...}); }
  static constexpr std::size_t correction_index() { return first_of({GradientCorrection<Terms>...}); }
  const auto& h_solver() const { return std::get<solver_index()>(terms_); }

  /// nabla_a W of a pair as the force sum uses it: at h_ab, or the mean of both h in grad-h SPH.
  static Vec<D> pair_grad_W(const Vec<D>& r_ab, double r, double h_a, double inv_h_a, double h_b) {
    if constexpr (grad_h)
      return 0.5 * (kernel::grad_W_inv_h<Kernel, D>(r_ab, r, inv_h_a) + kernel::grad_W<Kernel, D>(r_ab, r, h_b));
    else
      return kernel::grad_W_inv_h<Kernel, D>(r_ab, r, kernel::inv_h_ab(h_a, inv_h_a, h_b));
  }

  /// psi of the consistent gradient (physics/consistent_gradient.hpp) on the band of particles around level
  /// faces (those with a neighbour of another h, grown by term.band_layers neighbour layers); pairs with a
  /// member outside keep grad W. Per axis k by conjugate gradients:
  ///   sum_{b in band} w_ab (psi_a - s_b psi_src(b)) = V_a E_a,
  /// where a ghost b stands for its source with s_b = -1 when it mirrors axis k (a mirrored psi flips its
  /// normal component). Outside the band a uniform lattice has E = 0; so the band's flux balances and a
  /// uniform state is exact. Warm-started from the last psi. Ghosts take their source's psi and membership.
  void solve_gradient_correction() requires corrected {
    const auto& term = std::get<correction_index()>(terms_);
    const std::size_t n = p_.n_real, n_all = p_.size();
    const bool fresh = psi_.size() < n;
    auto source_of = [&](std::uint32_t b) -> std::size_t { return b < n ? b : p_.ghost_source[b - n]; };
    if (fresh || term.every_step) {
      // the band
      band_.assign(n_all, 0);
      for (std::size_t a = 0; a < n; ++a)
        for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k)
          if (std::abs(p_.h[nl_.index[k]] - p_.h[a]) > 1e-12 * p_.h[a]) {
            band_[a] = 1;
            break;
          }
      for (int layer = 0; layer < term.band_layers; ++layer) {
        band_grow_.assign(band_.begin(), band_.begin() + static_cast<std::ptrdiff_t>(n));
        for (std::size_t a = 0; a < n; ++a) {
          if (band_[a]) continue;
          for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k)
            if (band_[source_of(nl_.index[k])]) {
              band_grow_[a] = 1;
              break;
            }
        }
        std::copy(band_grow_.begin(), band_grow_.end(), band_.begin());
      }
      band_index_.assign(n, -1);
      band_members_.clear();
      for (std::size_t a = 0; a < n; ++a)
        if (band_[a]) {
          band_index_[a] = static_cast<std::int32_t>(band_members_.size());
          band_members_.push_back(static_cast<std::uint32_t>(a));
        }
      const std::size_t m = band_members_.size();
      std::vector<Vec<D>> psi_old;
      if (!fresh) psi_old.assign(psi_.begin(), psi_.begin() + static_cast<std::ptrdiff_t>(n));
      psi_.assign(n_all, Vec<D>::Zero());
      psi_solve_ = CgResult{};
      psi_solve_.converged = true;
      if (m > 0) {
        V_.resize(n_all);
        for (std::size_t a = 0; a < n_all; ++a) V_[a] = p_.m[a] / p_.rho[a];
        ghost_flips_.resize(n_all - n);
        for (std::size_t g = n; g < n_all; ++g) {
          const std::size_t src = p_.ghost_source[g - n];
          std::uint8_t flips = 0;
          for (int k = 0; k < D; ++k)
            if (box_.edge[k] == Edge::reflecting && p_.x[g][k] != p_.x[src][k]) flips |= std::uint8_t(1u << k);
          ghost_flips_[g - n] = flips;
        }
        pair_w_.resize(nl_.index.size());
        for (auto& r : psi_rhs_) r.resize(m);
#pragma omp parallel for schedule(static)
        for (std::size_t i = 0; i < m; ++i) {
          const std::uint32_t a = band_members_[i];
          Vec<D> E = Vec<D>::Zero();
          for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k) {
            const std::uint32_t b = nl_.index[k];
            const Vec<D> r_ab = p_.x[a] - p_.x[b];
            const double r = r_ab.norm();
            const double h_ab = 0.5 * (p_.h[a] + p_.h[b]);
            const bool inside = r > 0.0 && band_[source_of(b)];
            pair_w_[k] = inside ? physics::laplacian_weight(V_[a], V_[b], kernel::W<Kernel, D>(r, h_ab)) : 0.0;
            if (r > 0.0) E += physics::zeroth_order_error_term<D>(V_[b], kernel::grad_W<Kernel, D>(r_ab, r, h_ab));
          }
          for (int k = 0; k < D; ++k) psi_rhs_[static_cast<std::size_t>(k)][i] = V_[a] * E[k];
        }
        // Connected pieces of the band, and per axis whether a mirror pair anchors a piece (otherwise psi
        // is fixed only up to a constant there, and the right-hand side is kept in the range).
        piece_.assign(m, -1);
        std::vector<std::array<bool, D>> anchored;
        std::vector<std::size_t> stack;
        for (std::size_t start = 0; start < m; ++start) {
          if (piece_[start] >= 0) continue;
          const auto id = static_cast<std::int32_t>(anchored.size());
          anchored.push_back({});
          piece_[start] = id;
          stack.assign(1, start);
          while (!stack.empty()) {
            const std::uint32_t a = band_members_[stack.back()];
            stack.pop_back();
            for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k) {
              if (pair_w_[k] == 0.0) continue;
              const std::uint32_t b = nl_.index[k];
              if (b >= n)
                for (int ax = 0; ax < D; ++ax)
                  if (ghost_flips_[b - n] & (1u << ax)) anchored.back()[static_cast<std::size_t>(ax)] = true;
              const auto j = static_cast<std::size_t>(band_index_[source_of(b)]);
              if (piece_[j] < 0) {
                piece_[j] = id;
                stack.push_back(j);
              }
            }
          }
        }
        // The band's matrix: row i holds, for each pair with a band member b that is not i's own mirror
        // image, b's band index and per axis its weight times the sign of b's mirroring; the rest of each row
        // lands on the diagonal. Iterating on it instead of the neighbour list skips the pairs leaving the
        // band and the ghost look-ups in every product.
        band_row_.assign(m + 1, 0);
        band_col_.clear();
        for (auto& c : band_coef_) c.clear();
        std::array<std::vector<double>, D> diagonal;
        for (auto& d : diagonal) d.assign(m, 0.0);
        for (std::size_t i = 0; i < m; ++i) {
          const std::uint32_t a = band_members_[i];
          for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k) {
            const double w = pair_w_[k];
            if (w == 0.0) continue;
            const std::uint32_t b = nl_.index[k];
            const std::uint8_t flips = b >= n ? ghost_flips_[b - n] : std::uint8_t(0);
            if (source_of(b) == a) {  // a's mirror image: w (psi_a - s psi_a)
              for (int axis = 0; axis < D; ++axis)
                diagonal[static_cast<std::size_t>(axis)][i] += (flips & (1u << axis)) ? 2.0 * w : 0.0;
              continue;
            }
            band_col_.push_back(static_cast<std::uint32_t>(band_index_[source_of(b)]));
            for (int axis = 0; axis < D; ++axis) {
              diagonal[static_cast<std::size_t>(axis)][i] += w;
              band_coef_[static_cast<std::size_t>(axis)].push_back((flips & (1u << axis)) ? -w : w);
            }
          }
          band_row_[i + 1] = band_col_.size();
        }
        std::vector<double> component(m), mean(anchored.size()), count(anchored.size());
        for (int axis = 0; axis < D; ++axis) {
          const auto& diag = diagonal[static_cast<std::size_t>(axis)];
          const auto& coef = band_coef_[static_cast<std::size_t>(axis)];
          auto apply = [&](const std::vector<double>& in, std::vector<double>& out) {
            out.resize(m);
#pragma omp parallel for schedule(static)
            for (std::size_t i = 0; i < m; ++i) {
              double off = 0.0;
              for (std::size_t e = band_row_[i]; e < band_row_[i + 1]; ++e) off += coef[e] * in[band_col_[e]];
              out[i] = diag[i] * in[i] - off;
            }
          };
          auto& rhs = psi_rhs_[static_cast<std::size_t>(axis)];
          std::fill(mean.begin(), mean.end(), 0.0);
          std::fill(count.begin(), count.end(), 0.0);
          for (std::size_t i = 0; i < m; ++i) {
            mean[static_cast<std::size_t>(piece_[i])] += rhs[i];
            count[static_cast<std::size_t>(piece_[i])] += 1.0;
          }
          for (std::size_t i = 0; i < m; ++i) {
            const auto c = static_cast<std::size_t>(piece_[i]);
            if (!anchored[c][static_cast<std::size_t>(axis)]) rhs[i] -= mean[c] / count[c];
          }
          for (std::size_t i = 0; i < m; ++i) component[i] = fresh ? 0.0 : psi_old[band_members_[i]][axis];
          const CgResult res = conjugate_gradient(apply, diag, rhs, component, term.tolerance, term.max_iterations);
          psi_solve_.iterations += res.iterations;
          psi_solve_.relative_residual = std::max(psi_solve_.relative_residual, res.relative_residual);
          psi_solve_.converged = psi_solve_.converged && res.converged;
          for (std::size_t i = 0; i < m; ++i) psi_[band_members_[i]][axis] = component[i];
        }
      }
      ++psi_solves_;
      psi_iterations_ += static_cast<std::uint64_t>(psi_solve_.iterations);
    }
    psi_.resize(n_all);
    band_.resize(n_all);
    for (std::size_t g = n; g < n_all; ++g) {
      const std::size_t src = p_.ghost_source[g - n];
      psi_[g] = psi_[src];
      band_[g] = band_[src];
      for (int k = 0; k < D; ++k)
        if (box_.edge[k] == Edge::reflecting && p_.x[g][k] != p_.x[src][k]) psi_[g][k] = -psi_[g][k];
    }
  }

  /// Rates of the particles whose step ends now (active_): their neighbours, density and forces; every
  /// other particle's density is predicted from its last evaluation by the continuity equation.
  void compute_rates_of_active() {
    auto t0 = clock::now();
    const std::size_t n = p_.n_real;
    build_cells(1.0, false);
    row_.assign(p_.size(), -1);
    for (std::size_t i = 0; i < active_.size(); ++i) row_[active_[i]] = static_cast<std::int32_t>(i);
    const neighbors::Subset rows{&active_, &row_};
    neighbors::build_neighbor_list<D>(p_.x, p_.h, rows, neighbors::MeanH{Kernel::support}, cells_, nl_);
    times_.neighbors += seconds_since(t0);
    t0 = clock::now();
#pragma omp parallel for schedule(static)
    for (std::size_t a = 0; a < n; ++a)
      if (row_[a] < 0) p_.rho[a] = std::max(rho_eval_[a] + (time_ - t_eval_[a]) * drho_dt_[a], 0.01 * rho_eval_[a]);
    density_rows(rows);
    update_pressure();
    times_.density += seconds_since(t0);
    t0 = clock::now();
    force_rows<true>(rows);
    for (const std::uint32_t a : active_) {
      rho_eval_[a] = p_.rho[a];
      t_eval_[a] = time_;
    }
    times_.forces += seconds_since(t0);
  }

  /// Ghosts out to the widest reach (times the search margin) and the cell list over all points.
  /// h_fresh: h may have changed since the last call (not so between the substeps of a block).
  void build_cells(double margin, bool h_fresh = true) {
    const std::size_t n = p_.n_real;
    if (h_fresh) {
      double h_max = 0.0;
#pragma omp parallel for schedule(static) reduction(max : h_max)
      for (std::size_t a = 0; a < n; ++a) h_max = std::max(h_max, p_.h[a]);
      h_max_ = h_max;
      // Cells sized by the median h: particles with larger h search more cells (neighbor_list.hpp).
      h_scratch_.assign(p_.h.begin(), p_.h.begin() + static_cast<std::ptrdiff_t>(n));
      std::nth_element(h_scratch_.begin(), h_scratch_.begin() + static_cast<std::ptrdiff_t>(n / 2), h_scratch_.end());
      h_median_ = h_scratch_[n / 2];
    }
    boundary::make_ghosts(p_, box_, Kernel::support * h_max_ * margin);
    cells_.build(p_.x, 0.5 * Kernel::support * h_median_ * margin);
  }

  void build_neighbors(double margin) {
    const auto t0 = clock::now();
    build_cells(margin);
    const neighbors::FirstN rows{p_.n_real};
    if constexpr (grad_h)
      neighbors::build_neighbor_list<D>(p_.x, p_.h, rows, neighbors::MaxH{Kernel::support, margin}, cells_, nl_);
    else
      neighbors::build_neighbor_list<D>(p_.x, p_.h, rows, neighbors::MeanH{Kernel::support}, cells_, nl_);
    times_.neighbors += seconds_since(t0);
  }

  /// Newton-Raphson on rho_sum(h) - rho_h(h) = 0 per particle (Price 2012 §3.1), bisection-guarded;
  /// sets h, rho and Omega. Returns false when some h outgrew the neighbour search margin.
  bool solve_density_and_h(double margin) {
    const std::size_t n = p_.n_real;
    const auto& solver = h_solver();
    Omega_.assign(p_.size(), 1.0);
    bool fits = true;
#pragma omp parallel reduction(&& : fits)
    {
      std::vector<std::pair<double, double>> r_m;  // (r_ab, m_b) of the candidates, computed once per particle
#pragma omp for schedule(static)
      for (std::size_t a = 0; a < n; ++a) {
        const double m_a = p_.m[a];
        const double h_search = p_.h[a] * margin;
        r_m.clear();
        for (auto k = nl_.offset[a]; k < nl_.offset[a + 1]; ++k) {
          const std::uint32_t b = nl_.index[k];
          r_m.emplace_back((p_.x[a] - p_.x[b]).norm(), p_.m[b]);
        }
        double h = p_.h[a], lo = 0.0, hi = h_search;
        double rho = 0.0, sum_dW_dh = 0.0;
        for (int it = 0; it < solver.max_iterations; ++it) {
          rho = m_a * kernel::W<Kernel, D>(0.0, h);
          sum_dW_dh = m_a * physics::dW_dh<Kernel, D>(0.0, h);
          const double r_max = Kernel::support * h;
          for (const auto& [r, m_b] : r_m) {
            if (r >= r_max) continue;
            rho += m_b * kernel::W<Kernel, D>(r, h);
            sum_dW_dh += m_b * physics::dW_dh<Kernel, D>(r, h);
          }
          const double rho_h = solver.rho_of_h(m_a, h);
          const double f = rho - rho_h;
          if (std::abs(f) <= solver.tolerance * rho_h) break;
          if (f > 0.0)
            hi = h;
          else
            lo = h;  // f rises with h: rho_h falls as h^-D
          const double df = sum_dW_dh + D * rho_h / h;
          double next = df != 0.0 ? h - f / df : 0.5 * (lo + hi);
          if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
          h = next;
        }
        p_.h[a] = h;
        p_.rho[a] = rho;
        Omega_[a] = physics::omega<D>(h, rho, sum_dW_dh);
        if (h >= h_search * (1.0 - 1e-12)) fits = false;
      }
    }
    return fits;
  }

  void update_pressure() {
    const std::size_t n = p_.n_real;
#pragma omp parallel for schedule(static)
    for (std::size_t a = 0; a < n; ++a) {
      const GasState g = gas_state<EOS, D>(eos_, p_.rho[a], energy_of(a), p_.x[a]);
      p_.P[a] = g.P;
      p_.cs[a] = g.cs;
    }
    boundary::refresh_ghosts(p_);
    if constexpr (grad_h)
      for (std::size_t g = n; g < p_.size(); ++g) Omega_[g] = Omega_[p_.ghost_source[g - n]];
    if constexpr (has_pressure) {  // the pair loops read it only for a gas that pushes
      const std::size_t n_all = p_.size();
      P_over_rho2_.resize(n_all);
#pragma omp parallel for schedule(static)
      for (std::size_t a = 0; a < n_all; ++a) P_over_rho2_[a] = p_.P[a] / (p_.rho[a] * p_.rho[a]);
    }
  }

  void prescribe_frozen(double dt) {
    std::apply(
        [&](const auto&... term) {
          auto apply_motion = [&](const auto& t) {
            using T = std::decay_t<decltype(t)>;
            if constexpr (PrescribedMotion<T, D>)
              for (std::size_t a = 0; a < p_.n_real; ++a)
                if (p_.frozen[a]) t.prescribe(a, p_.x[a], p_.v[a], time_);
            if constexpr (BoundaryZone<T, D>) {
              const std::size_t n = p_.n_real;
#pragma omp parallel for schedule(static)
              for (std::size_t a = 0; a < n; ++a)
                if (p_.frozen[a] && t.contains(p_.x[a])) t.advance(p_.x[a], p_.v[a], dt);
            }
          };
          (apply_motion(term), ...);
          (void)apply_motion;  // unused when the scene names no terms
        },
        terms_);
  }

  /// Flags the particles inside a boundary zone as frozen (other flags stay); their velocity is the zone's.
  void mark_zone_members() {
    if constexpr (has_zones)
      std::apply(
          [&](const auto&... term) {
            auto mark = [&](const auto& t) {
              if constexpr (BoundaryZone<std::decay_t<decltype(t)>, D>)
                for (std::size_t a = 0; a < p_.n_real; ++a)
                  if (t.contains(p_.x[a])) {
                    p_.frozen[a] = 1;
                    Vec<D> x = p_.x[a];
                    t.advance(x, p_.v[a], 0.0);
                  }
            };
            (mark(term), ...);
          },
          terms_);
  }

  // A particle that crossed a reflecting wall is mirrored back; one that left a periodic axis re-enters.
  void keep_inside(std::size_t a) {
    for (int k = 0; k < D; ++k) {
      if (box_.edge[k] == Edge::reflecting) {
        if (p_.x[a][k] < box_.lo[k]) {
          p_.x[a][k] = 2.0 * box_.lo[k] - p_.x[a][k];
          v_half_[a][k] = -v_half_[a][k];
        }
        if (p_.x[a][k] > box_.hi[k]) {
          p_.x[a][k] = 2.0 * box_.hi[k] - p_.x[a][k];
          v_half_[a][k] = -v_half_[a][k];
        }
      }
    }
    box_.wrap(p_.x[a]);
  }

  void validate() {
    require(p_.n_real > 0, "the domain holds no particles");
    require(p_.n_real == p_.size(), "initial particle sets must not contain ghosts");
    for (int k = 0; k < D; ++k)
      require(box_.hi[k] > box_.lo[k], "the box is empty along axis " + std::to_string(k) + " (hi <= lo)");
    params_.validate();
    require(params_.max_bin == 0 || (!grad_h && !has_stress),
            "individual time steps (max_bin > 0) need fixed smoothing lengths and no viscous stress term");
    require(params_.max_bin == 0 || !corrected, "consistent gradients need one global time step (max_bin = 0)");
    validate_policy(eos_);
    validate_policy(reg_);
    std::apply([&](const auto&... term) { (validate_policy(term), ...); }, terms_);
    for (std::size_t a = 0; a < p_.n_real; ++a) {
      const std::string who = "particle " + std::to_string(a) + ": ";
      require(p_.m[a] > 0.0 && std::isfinite(p_.m[a]), who + "mass must be positive and finite");
      require(p_.h[a] > 0.0 && std::isfinite(p_.h[a]), who + "smoothing length h must be positive and finite");
      require(p_.x[a].allFinite() && p_.v[a].allFinite(), who + "position and velocity must be finite");
      if constexpr (has_energy)
        require(p_.u[a] >= 0.0 && std::isfinite(p_.u[a]), who + "internal energy must be non-negative");
      if constexpr (corrected)
        require(p_.rho[a] > 0.0 && std::isfinite(p_.rho[a]),
                who + "consistent gradients evolve the density from its initial value: give rho > 0 (m / V)");
      for (int k = 0; k < D; ++k)
        if (box_.edge[k] != Edge::open)
          require(p_.x[a][k] >= box_.lo[k] && p_.x[a][k] <= box_.hi[k],
                  who + "lies outside the box along axis " + std::to_string(k));
    }
  }

  template <class T>
  static void validate_policy(const T& t) {
    if constexpr (requires { t.validate(); }) t.validate();
  }

  void check_physical() const {
    const auto [a, what] = first_unphysical(p_);
    if (!what.empty())
      throw NumericalError("particle " + std::to_string(a) + ": " + what + " at t = " + std::to_string(time_) +
                           " (step " + std::to_string(step_) + ")");
  }

  Particles p_;
  Box<D> box_;
  EOS eos_;
  Reg reg_;
  TimeStepParams params_;
  std::tuple<Terms...> terms_;

  neighbors::CellList<D> cells_;
  neighbors::NeighborList nl_;
  std::vector<double> v_sig_;
  std::vector<double> h_scratch_;
  double h_max_ = 0.0, h_median_ = 0.0;  ///< of the real particles at the last build_cells with h_fresh
  // individual time steps: per-particle limits, strides (in finest substeps), step starts, the active
  // set and its rows, and the last evaluated density with its time and rate
  std::vector<double> dt_own_, rho_eval_, t_eval_, drho_dt_;
  std::vector<std::uint64_t> stride_, step_start_;
  std::vector<std::uint32_t> active_;
  std::vector<std::uint8_t> ends_now_;  ///< per particle: whether its step ends with this substep
  std::vector<std::int32_t> row_;
  std::vector<double> P_over_rho2_;     ///< P / rho^2 of every point, refreshed with the pressure
  std::vector<double> number_density_;  ///< n_a of eq. (A1), only when the regularizer wants it
  std::vector<double> pair_kernel_;     ///< W_ab of each neighbour-list entry, with number_density_
  bool pair_kernel_full_ = false;       ///< whether the last density pass (over every particle) filled pair_kernel_
  std::vector<double> Omega_;           ///< grad-h factors (real and ghosts), only with a smoothing-length solver
  std::vector<Mat<D>> S_over_rho2_;     ///< viscous stress / rho^2 (real and ghosts), only with a stress term
  std::vector<Vec<D>> v_half_;
  // consistent gradients only: psi (real and ghosts), volumes, pair weights, right-hand sides per axis,
  // which axes each ghost mirrors, the half-step density, and the solver's record
  std::vector<Vec<D>> psi_;
  std::vector<double> V_, pair_w_, rho_half_;
  std::array<std::vector<double>, D> psi_rhs_;
  std::vector<std::uint8_t> ghost_flips_, band_, band_grow_;
  std::vector<std::int32_t> band_index_, piece_;
  std::vector<std::size_t> band_row_;             ///< the psi solve's band matrix (CSR): row offsets,
  std::vector<std::uint32_t> band_col_;           ///< band index of each entry,
  std::array<std::vector<double>, D> band_coef_;  ///< and its signed weight per axis
  std::vector<std::uint32_t> band_members_;
  CgResult psi_solve_;
  std::uint64_t psi_solves_ = 0, psi_iterations_ = 0;
  typename Particles::EnergyField u_half_;
  double time_ = 0.0;
  std::uint64_t step_ = 0;
  std::uint64_t particle_updates_ = 0;
  std::uint64_t regularizations_ = 0;
  double kinetic_removed_ = 0.0;
  StepInfo info_;
  PhaseTimes times_;
};

}  // namespace rsph
