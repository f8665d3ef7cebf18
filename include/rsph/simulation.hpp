#pragma once
// Composes the policies into a simulation: it owns them, the particle set and the run loop's clocks and
// counters. What a step does lives elsewhere: the leapfrog and the individual time steps in integrate/,
// the density, pressure, stress and force passes in physics/loops/, the grad-h solve beside GradH, the
// consistent-gradient solve beside ConsistentGradient, ghosts and walls in boundary/, the remap in
// regularize/.
#include "rsph/boundary/frozen.hpp"
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/diagnostics.hpp"
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/eos/concept.hpp"
#include "rsph/integrate/block_steps.hpp"
#include "rsph/integrate/leapfrog.hpp"
#include "rsph/integrate/time_step.hpp"
#include "rsph/kernel/concept.hpp"
#include "rsph/neighbors/cell_list.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/physics/concept.hpp"
#include "rsph/physics/consistent_gradient_solve.hpp"
#include "rsph/physics/loops/density.hpp"
#include "rsph/physics/loops/forces.hpp"
#include "rsph/physics/loops/pressure.hpp"
#include "rsph/physics/loops/stress.hpp"
#include "rsph/physics/smoothing_length.hpp"
#include "rsph/regularize/concept.hpp"
#include "rsph/regularize/remap_on_ranks.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>
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

namespace detail {
struct Nothing {};  ///< the workspace of a solver a scene does not name
}  // namespace detail

template <int D, class Kernel, class EOS, class Reg, class... Terms>
requires SupportedDimension<D>
class Simulation {
  static_assert(check_kernel<Kernel, D>());
  static_assert(check_equation_of_state<EOS, D>());
  static_assert(check_regularizer<Reg, D, EOS::has_internal_energy>());
  static_assert((check_term<Terms, D>() && ...));
  static_assert((made_for_dimension<Terms, D>() && ...),
                "a term made for another dimension (its `dim`) cannot join this simulation: GradH<D> and the "
                "like take the simulation's D");
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
  /// A viscosity switch (Balsara's) adds a velocity-gradient pass for its per-particle factors.
  static constexpr bool has_switch = (ViscositySwitch<Terms, D> || ...);
  static_assert((int(ViscositySwitch<Terms, D>) + ... + 0) <= 1, "a simulation takes at most one viscosity switch");
  /// Consistent pair gradients (physics/consistent_gradient.hpp): the density follows the continuity
  /// equation from the remapped rho = m / V, and pairs use G_ab, so uniform states are exact equilibria.
  static constexpr bool corrected = (GradientCorrection<Terms> || ...);
  static_assert((int(GradientCorrection<Terms>) + ... + 0) <= 1, "a simulation takes at most one gradient correction");
  static_assert(!(corrected && grad_h),
                "consistent gradients need fixed smoothing lengths (no smoothing-length solver)");
  using Particles = ParticleSet<D, has_energy>;
  using KernelType = Kernel;
  /// The compile-time switches the pair loops take (physics/loops/scheme.hpp).
  using LoopScheme =
      physics::loops::Scheme<Kernel, D, has_energy, has_pressure, grad_h, corrected, has_stress, has_switch>;
  /// The density pass also sums n_a of eq. (A1) when the regularizer's schedule uses it (fixed h only).
  static constexpr bool wants_number_density = !grad_h && requires { requires Reg::wants_number_density; };
  /// Runs on the ranks of a communicator when a scene names a domain decomposition (mpi/decomposition.hpp).
  static constexpr bool distributed = (DomainDecomposition<Terms, D> || ...);
  static_assert((int(DomainDecomposition<Terms, D>) + ... + 0) <= 1, "a simulation takes at most one decomposition");
  static_assert(!distributed || regularize::remaps_on_ranks<Reg>(),
                "this regularizer does not run on many ranks: its lattice does not say `remaps_on_ranks`");

  Simulation(Particles particles, Box<D> box, EOS eos, Reg reg, TimeStepParams params, Terms... terms)
      : p_(std::move(particles)),
        box_(box),
        eos_(std::move(eos)),
        reg_(std::move(reg)),
        params_(params),
        terms_(std::move(terms)...) {
    validate();
    if (p_.id.size() != p_.n_real) p_.renumber();  // a set written field by field (a remap at set-up)
    if constexpr (distributed) {                   // every rank built the same set: each keeps its share
      domain_to_change().distribute(p_);
      rebalance();
    }
    boundary::mark_zone_members<D>(terms_, p_);
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
  const std::vector<double>& number_density() const requires wants_number_density { return nd_.n; }
  double time() const { return time_; }
  std::uint64_t steps() const { return step_; }
  std::uint64_t particle_updates() const { return particle_updates_; }
  std::uint64_t regularizations() const { return regularizations_; }
  double kinetic_energy_removed() const { return kinetic_removed_; }
  const PhaseTimes& phase_times() const { return times_; }
  /// The last psi solve of the gradient correction (summed over axes), and the solves so far.
  const CgResult& gradient_solve() const requires corrected { return cg_.last; }
  std::uint64_t gradient_solves() const requires corrected { return cg_.solves; }
  std::uint64_t gradient_solve_iterations() const requires corrected { return cg_.iterations; }
  /// The conserved totals; over every rank, in the same bits at any rank count, when decomposed.
  Conservation<D> totals() const {
    if constexpr (distributed)
      return domain().totals(p_);
    else
      return conservation(p_);
  }
  /// The decomposition a scene named (mpi/decomposition.hpp).
  const auto& domain() const requires distributed {
    return std::get<first_of_kind<sizeof...(Terms)>({DomainDecomposition<Terms, D>...})>(terms_);
  }

  /// The next time step: the Courant and force conditions over all real, integrated particles (all ranks').
  double time_step() const {
    if constexpr (distributed)
      return domain().min(stable_time_step(p_, v_sig_, params_));
    else
      return stable_time_step(p_, v_sig_, params_);
  }

  /// One kick-drift-kick leapfrog step of at most dt_limit (or a block of individual steps when
  /// TimeStepParams::max_bin > 0); regularizes afterwards when due. Returns the time advanced.
  double step(double dt_limit = std::numeric_limits<double>::infinity()) {
    if (params_.max_bin > 0) return block_step(std::min(dt_limit, time_to_regularization()));
    if constexpr (distributed) rebalance();
    const double dt = std::min({time_step(), dt_limit, time_to_regularization()});
    check_time_step(dt, params_, time_);
    auto t0 = clock::now();
    integrate::kick_drift<corrected>(p_, box_, dt, drho_dt_, leap_);
    time_ += dt;
    boundary::prescribe_frozen<D>(terms_, p_, time_, dt);
    times_.integrate += seconds_since(t0);
    compute_rates();
    t0 = clock::now();
    integrate::closing_kick<corrected>(p_, dt, drho_dt_, leap_);
    boundary::damp_velocities<D>(terms_, p_, dt);
    times_.integrate += seconds_since(t0);
    count_step(dt, p_.n_real);
    finish_step();
    return dt;
  }

  /// Regularizes now, whatever the schedule says.
  void regularize_now() {
    const auto t0 = clock::now();
    p_.clear_ghosts();
    // members of zones that keep them sit the remap out, identities and all
    const bool keep = boundary::any_zone_keeps_members(terms_);
    auto kept = keep ? p_.take_if([&](std::size_t a) { return p_.frozen[a] != 0; }) : Particles{};
    const auto remap_here = [&] {
      kinetic_removed_ += reg_.remap(p_, box_, step_info());
      p_.renumber();  // every particle is new
    };
    if constexpr (distributed) {
      if (on_many_ranks())
        remap_on_ranks();
      else
        remap_here();
    } else {
      remap_here();
    }
    if (keep) p_.append(kept);
    if constexpr (corrected) cg_.reset();  // new particles: solve afresh
    boundary::mark_zone_members<D>(terms_, p_, true);
    ++regularizations_;
    since_ = {};
    times_.regularization += seconds_since(t0);
    compute_rates();
  }

  /// Saves or restores (ar.saving()) everything a later step reads, through a checkpoint archive
  /// (io/checkpoint.hpp): the real particles with their rates (taken at the predicted state, so they cannot be
  /// recomputed from the final one), the signal speeds, d rho/dt, the clocks and counters, the regularizer's
  /// state and the consistent-gradient solve's warm start. Restored, the next step continues bit for bit as
  /// the saved run would have: it rebuilds ghosts, neighbours and every other pass from these (a viscosity
  /// switch's factors are saved too: the substeps of a block read the last evaluation's).
  /// On many ranks every rank adds its own particles (the archive writes them into one file, mpi::FileTurns);
  /// restored on any rank count, each rank takes a share of the file's particles and the decomposition
  /// partitions them afresh. The clocks and the regularizer's log are rank 0's.
  template <class Archive>
  void checkpoint(Archive& ar) {
    const auto scope = ar.scope("simulation");
    p_.checkpoint(ar);
    ar.rows("v_sig", v_sig_);
    ar.rows("drho_dt", drho_dt_);
    if constexpr (has_switch) {  // the real particles' factors, which a block's substeps read
      switch_.resize(p_.n_real);
      ar.rows("switch_factor", switch_);
    }
    ar("time", time_);
    ar("step", step_);
    ar.total("particle_updates", particle_updates_);
    ar("regularizations", regularizations_);
    ar("kinetic_removed", kinetic_removed_);
    ar("steps_since_regularization", since_.steps);
    ar("time_since_regularization", since_.time);
    ar("seconds_neighbors", times_.neighbors);
    ar("seconds_density", times_.density);
    ar("seconds_forces", times_.forces);
    ar("seconds_integrate", times_.integrate);
    ar("seconds_regularization", times_.regularization);
    if constexpr (requires { reg_.checkpoint(ar); }) reg_.checkpoint(ar);
    if constexpr (corrected) cg_.checkpoint(ar, p_.n_real);
    if (!ar.saving() && params_.max_bin > 0) blocks_.evaluated_all(p_, time_);  // a block ends synchronised
    if constexpr (distributed)
      if (!ar.saving() && on_many_ranks()) {
        domain_to_change().repartition();
        rebalance(false);
      }
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

  /// Ghosts, neighbours, density (eq. 2) and pressure, then accelerations (eq. 3) and heating (eq. 4).
  void compute_rates() {
    if constexpr (grad_h)
      solve_smoothing_lengths();
    else
      density_pass();
    auto t0 = clock::now();
    if constexpr (corrected) cg_.template update<Kernel>(correction(), p_, box_, nl_, solve_on_ranks());
    if constexpr (has_stress) stress_pass();
    if constexpr (has_switch) switch_pass();
    if (params_.max_bin > 0 || corrected)
      force_pass<true>(neighbors::FirstN{p_.n_real});
    else
      force_pass<false>(neighbors::FirstN{p_.n_real});
    if (params_.max_bin > 0) blocks_.evaluated_all(p_, time_);
    times_.forces += seconds_since(t0);
  }

 private:
  using clock = std::chrono::steady_clock;
  static double seconds_since(clock::time_point t0) { return std::chrono::duration<double>(clock::now() - t0).count(); }
  static constexpr double kHMargin = 1.25;  // search radius over h while h is solved

  const auto& h_solver() const {
    return std::get<first_of_kind<sizeof...(Terms)>({SmoothingLengthSolver<Terms>...})>(terms_);
  }
  const auto& stress_term() const {
    return std::get<first_of_kind<sizeof...(Terms)>({StressTerm<Terms, D>...})>(terms_);
  }
  const auto& switch_term() const {
    return std::get<first_of_kind<sizeof...(Terms)>({ViscositySwitch<Terms, D>...})>(terms_);
  }
  const auto& correction() const {
    return std::get<first_of_kind<sizeof...(Terms)>({GradientCorrection<Terms>...})>(terms_);
  }
  auto& domain_to_change() requires distributed {
    return std::get<first_of_kind<sizeof...(Terms)>({DomainDecomposition<Terms, D>...})>(terms_);
  }

  /// Moves particles between ranks when the decomposition says so, weighted by their neighbour counts (when
  /// `measured`: the neighbour list is this set's), with the per-particle state a step reads before its rates
  /// are evaluated again (signal speeds, d rho/dt).
  void rebalance(bool measured = true) requires distributed {
    if (!on_many_ranks()) return;
    auto& d = domain_to_change();
    const std::size_t n = p_.n_real;
    work_.assign(n, 1.0);
    if (measured && nl_.offset.size() == n + 1)
      for (std::size_t a = 0; a < n; ++a) work_[a] += static_cast<double>(nl_.count(a));
    v_sig_.resize(n);
    drho_dt_.resize(n);
    const auto balance = [&](auto&... f) { d.balance(p_, std::span<const double>(work_), v_sig_, drho_dt_, f...); };
    const auto factors = [&] {  // the switch's factors go along: the substeps of a block read them
      if constexpr (has_switch) {
        switch_.resize(n);
        return std::tie(switch_);
      } else {
        return std::tuple<>();
      }
    };
    if constexpr (corrected) {  // psi goes along, the next solve's warm start as in one process
      if (cg_.psi.size() >= n) {
        cg_.psi.resize(n);
        std::apply([&](auto&... f) { balance(cg_.psi, f...); }, factors());
        return;
      }
    }
    std::apply(balance, factors());
  }

  /// What the consistent-gradient solve needs on many ranks (halo values, sums, gathers); empty in one process.
  physics::SolveOnRanks solve_on_ranks() const {
    if constexpr (distributed)
      if (on_many_ranks()) {
        const auto& d = domain();
        return {[&d](std::vector<double>& f) { d.refresh_halos(f); }, [&d](std::span<double> v) { d.sum_in_place(v); },
                [&d](std::vector<double>& rows, std::size_t w, bool add) { d.combine_by_name(rows, w, add); }};
      }
    return {};
  }

  /// Whether a decomposition spreads the run over more than one rank (one rank runs the serial code).
  bool on_many_ranks() const {
    if constexpr (distributed)
      return domain().ranks() > 1;
    else
      return false;
  }

  /// The remap on many ranks (regularize/remap_on_ranks.hpp).
  void remap_on_ranks() requires distributed {
    kinetic_removed_ +=
        regularize::remap_on_ranks(domain_to_change(), p_, box_, reg_, step_info(), double(Kernel::support));
  }

  /// The viscous stress of every real particle; on many ranks the halos' from their owners; then the images'.
  void stress_pass() {
    physics::loops::stress_over_rho2<LoopScheme>(p_, nl_, stress_term(), S_over_rho2_);
    if constexpr (distributed)
      if (on_many_ranks()) domain().refresh_halos(S_over_rho2_);
    physics::loops::stress_images(p_, box_, S_over_rho2_);
  }

  /// A viscosity switch's factor of every real particle from its velocity gradient (zero while the switch is
  /// off), then the ghosts'.
  void switch_pass() {
    if (switch_term().active()) physics::loops::switch_factors<LoopScheme>(p_, nl_, switch_term(), switch_);
    switch_ghosts();
  }
  /// The switch's factors on the ghosts of the moment: on many ranks the halos' from their owners, then the
  /// images'. Between the evaluations of a whole block, a particle keeps the factor of the last one. A switch
  /// that is off reads none: its zeros cost no pass and no message.
  void switch_ghosts() {
    if (!switch_term().active()) {
      switch_.assign(p_.size_with_ghosts(), 0.0);
      return;
    }
    switch_.resize(p_.size_with_ghosts());
    if constexpr (distributed)
      if (on_many_ranks()) domain().refresh_halos(switch_);
    physics::loops::scalar_images(p_, switch_);
  }

  /// After the pressure pass: the fields a later pass reads, on the halos of other ranks' particles, then on
  /// the images made of them.
  void refresh_halos() requires distributed {
    if (!on_many_ranks()) return;
    auto& d = domain_to_change();
    const auto energy = [&] {
      if constexpr (has_energy)
        return std::tie(p_.u);
      else
        return std::tuple<>();
    };
    const auto omega = [&] {
      if constexpr (grad_h)
        return std::tie(gradh_.Omega);
      else
        return std::tuple<>();
    };
    std::apply([&](auto&... f) { d.refresh_halos(f...); },
               std::tuple_cat(std::tie(p_.rho, p_.P, p_.cs, p_.h), energy(), omega()));  // one message a rank
    boundary::refresh_ghosts(p_);
    if constexpr (has_pressure)
      for (std::size_t g = p_.n_real; g < p_.size_with_ghosts(); ++g)
        P_over_rho2_[g] = p_.P[g] / (p_.rho[g] * p_.rho[g]);
  }

  /// How long until a time-based schedule fires (infinite for others, or when it is already due).
  double time_to_regularization() const {
    if constexpr (requires(const StepInfo& s) { reg_.time_until_due(s); }) {
      const double left = reg_.time_until_due(step_info());  // land on a time-based regularization exactly
      if (left > 0.0) return left;
    }
    return std::numeric_limits<double>::infinity();
  }

  /// What the schedule sees after the last step: counters, and the density pass's sums as views.
  StepInfo step_info() const {
    StepInfo s;
    s.step = step_;
    s.time = time_;
    s.steps_since_last = since_.steps;
    s.time_since_last = since_.time;
    s.neighbors = &nl_;
    if constexpr (distributed)
      if (on_many_ranks()) s.refresh_halos = [&d = domain()](std::vector<double>& f) { d.refresh_halos(f); };
    if constexpr (wants_number_density) {
      s.number_density = nd_.n;
      if (nd_.pair_kernel_full) s.pair_kernel = nd_.pair_kernel;
    }
    return s;
  }

  void count_step(double dt, std::size_t updates) {
    ++step_;
    ++since_.steps;
    since_.time += dt;
    particle_updates_ += updates;
  }

  /// After a step (or a block of them): the regularizer's turn, then the physical check.
  void finish_step() {
    const auto t0 = clock::now();
    bool due = reg_.due(p_, box_, step_info());  // an adaptive schedule's check is regularization cost too
    if constexpr (distributed) due = domain().any(due);
    times_.regularization += seconds_since(t0);
    if (due) regularize_now();
    if (params_.check_every_step) check_physical();
  }

  /// One block of individual time steps of at most `limit` (integrate/block_steps.hpp): a particle is
  /// evaluated (neighbours, density, forces) only when its step ends; at the end of the block all are
  /// synchronised, evaluated afresh, and the regularizer may act. Returns the block's length.
  /// On many ranks the particles migrate at the block's start, all being synchronised then, and every substep
  /// refreshes the halos (drifted positions, predicted velocities and densities) before its active particles'
  /// rates; the block's length and finest step are planned from the limits of all ranks' particles.
  double block_step(double limit) {
    if constexpr (distributed)
      if (on_many_ranks()) {
        rebalance();
        blocks_.evaluated_all(p_, time_);  // the arrivals' last evaluation is now too
      }
    auto t0 = clock::now();
    const auto plan = blocks_.plan(p_, v_sig_, params_, limit, time_,
                                   [this]([[maybe_unused]] double& lo, [[maybe_unused]] double& hi) {
                                     if constexpr (distributed) domain().min_max(lo, hi);
                                   });
    times_.integrate += seconds_since(t0);
    for (std::uint64_t sub = 0; sub < plan.n_sub; ++sub) {
      t0 = clock::now();
      const bool sync = sub + 1 == plan.n_sub;
      blocks_.drift(p_, box_, sub, plan.delta);
      time_ += plan.delta;
      boundary::prescribe_frozen<D>(terms_, p_, time_, plan.delta);
      times_.integrate += seconds_since(t0);
      if (sync)
        compute_rates();
      else
        compute_rates_of_active();
      t0 = clock::now();
      blocks_.closing_kicks(p_, plan.delta);
      times_.integrate += seconds_since(t0);
      count_step(plan.delta, sync ? p_.n_real : blocks_.active().size());
    }
    t0 = clock::now();
    boundary::damp_velocities<D>(terms_, p_, plan.block);  // all synchronised now
    times_.integrate += seconds_since(t0);
    finish_step();
    return plan.block;
  }

  /// Neighbours with a margin, so h may grow while it is solved; rebuilt if it outgrows the margin.
  void solve_smoothing_lengths() requires grad_h {
    for (int attempt = 0;; ++attempt) {
      build_neighbors(kHMargin);
      const auto t0 = clock::now();
      bool fits = physics::solve_density_and_h<Kernel, D>(h_solver(), p_, nl_, kHMargin, gradh_);
      if constexpr (distributed) fits = domain().all(fits);
      times_.density += seconds_since(t0);
      if (fits) break;
      if (attempt == 4)
        throw NumericalError("smoothing lengths keep outgrowing their neighbour search at t = " +
                             std::to_string(time_));
    }
    const auto t0 = clock::now();
    update_pressure();
    times_.density += seconds_since(t0);
  }

  /// Neighbours, then the density sum (eq. 2; with consistent gradients only n_a, the density being
  /// integrated) and the pressure.
  void density_pass() {
    build_neighbors(1.0);
    const auto t0 = clock::now();
    if constexpr (!corrected || wants_number_density) density_rows(neighbors::FirstN{p_.n_real});
    update_pressure();
    times_.density += seconds_since(t0);
  }

  template <class Rows>
  void density_rows(const Rows& rows) {
    physics::loops::density_rows<Kernel, D, !corrected, wants_number_density>(p_, nl_, rows, nd_);
  }

  template <bool with_drho, class Rows>
  void force_pass(const Rows& rows) {
    physics::loops::ForceFields<D> f;
    if constexpr (has_pressure) f.P_over_rho2 = P_over_rho2_;
    if constexpr (grad_h) f.Omega = gradh_.Omega;
    if constexpr (has_stress) f.S_over_rho2 = S_over_rho2_;
    if constexpr (has_switch) f.switch_factor = switch_;
    if constexpr (corrected) {
      f.psi = cg_.psi;
      f.band = cg_.band;
    }
    physics::loops::force_rows<LoopScheme, with_drho>(p_, nl_, rows, f, terms_, time_, {v_sig_, drho_dt_});
  }

  /// Rates of the particles whose step ends now (blocks_.active()): their neighbours, density and forces;
  /// every other particle's density is predicted from its last evaluation by the continuity equation.
  void compute_rates_of_active() {
    auto t0 = clock::now();
    const auto& active = blocks_.active();
    build_cells(1.0, false);
    row_.assign(p_.size_with_ghosts(), -1);
    for (std::size_t i = 0; i < active.size(); ++i) row_[active[i]] = static_cast<std::int32_t>(i);
    const neighbors::Subset rows{&active, &row_};
    neighbors::build_neighbor_list<D>(p_.x, p_.h, rows, neighbors::MeanH{Kernel::support}, cells_, nl_);
    times_.neighbors += seconds_since(t0);
    t0 = clock::now();
    blocks_.predict_density(p_, row_, time_, drho_dt_);
    density_rows(rows);
    update_pressure();
    times_.density += seconds_since(t0);
    t0 = clock::now();
    if constexpr (has_switch) switch_ghosts();  // the ghosts were made again
    force_pass<true>(rows);
    blocks_.evaluated_active(p_, time_);
    times_.forces += seconds_since(t0);
  }

  /// Ghosts out to the widest reach (times the search margin) and the cell list over all points.
  /// h_fresh: h may have changed since the last call (not so between the substeps of a block).
  void build_cells(double margin, bool h_fresh = true) {
    const std::size_t n = p_.n_real;
    if (h_fresh) {
      double h_max = 0.0;
#pragma omp parallel for schedule(static) reduction(max : h_max) if (n >= kParallelMin)
      for (std::size_t a = 0; a < n; ++a) h_max = std::max(h_max, p_.h[a]);
      if constexpr (distributed) h_max = domain().max(h_max);
      h_max_ = h_max;
      // Cells sized by the median h: particles with larger h search more cells (neighbor_list.hpp).
      h_scratch_.assign(p_.h.begin(), p_.h.begin() + static_cast<std::ptrdiff_t>(n));
      std::nth_element(h_scratch_.begin(), h_scratch_.begin() + static_cast<std::ptrdiff_t>(n / 2), h_scratch_.end());
      h_median_ = n > 0 ? h_scratch_[n / 2] : h_max;
    }
    if constexpr (distributed)
      domain_to_change().make_ghosts(p_, box_, Kernel::support * h_max_ * margin, h_max_);
    else
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

  void update_pressure() {
    physics::loops::update_pressure<D>(eos_, p_, P_over_rho2_);
    if constexpr (distributed) refresh_halos();
    if constexpr (grad_h)
      for (std::size_t g = p_.n_real; g < p_.size_with_ghosts(); ++g)
        gradh_.Omega[g] = gradh_.Omega[p_.ghost_source[g - p_.n_real]];
  }

  void validate() {
    validate_initial_particles(p_, box_, corrected);
    params_.validate();
    require(params_.max_bin == 0 || (!grad_h && !has_stress),
            "individual time steps (max_bin > 0) need fixed smoothing lengths and no viscous stress term");
    require(params_.max_bin == 0 || !corrected, "consistent gradients need one global time step (max_bin = 0)");
    validate_policy(eos_);
    validate_policy(reg_);
    std::apply([&](const auto&... term) { (validate_policy(term), ...); }, terms_);
  }

  template <class T>
  static void validate_policy(const T& t) {
    if constexpr (requires { t.validate(); }) t.validate();
  }

  void check_physical() const {
    const std::string what = unphysical_after(p_, time_, step_);
    if constexpr (distributed)  // every rank stops together
      if (domain().any(!what.empty()) && what.empty())
        throw NumericalError("a particle of another rank became unphysical at t = " + std::to_string(time_));
    if (!what.empty()) throw NumericalError(what);
  }

  Particles p_;
  Box<D> box_;
  EOS eos_;
  Reg reg_;
  TimeStepParams params_;
  std::tuple<Terms...> terms_;

  neighbors::CellList<D> cells_;
  neighbors::NeighborList nl_;
  std::vector<double> v_sig_, drho_dt_;
  std::vector<double> h_scratch_;
  std::vector<double> work_;             ///< per particle: 1 + its neighbour count, the partition's weight (decomposed)
  double h_max_ = 0.0, h_median_ = 0.0;  ///< of the real particles at the last build_cells with h_fresh
  integrate::LeapfrogWorkspace<D, has_energy> leap_;
  integrate::BlockSteps<D, has_energy> blocks_;
  std::vector<std::int32_t> row_;     ///< per point: its row among the active particles, or -1
  std::vector<double> P_over_rho2_;   ///< P / rho^2 of every point, refreshed with the pressure
  physics::loops::NumberDensity nd_;  ///< n_a of eq. (A1), only when the regularizer wants it
  [[no_unique_address]] std::conditional_t<grad_h, physics::GradHWorkspace, detail::Nothing> gradh_;
  std::vector<Mat<D>> S_over_rho2_;  ///< viscous stress / rho^2 (real and ghosts), only with a stress term
  std::vector<double> switch_;       ///< a viscosity switch's factors (real and ghosts), only with a switch
  [[no_unique_address]] std::conditional_t<corrected, physics::ConsistentGradientWorkspace<D>, detail::Nothing> cg_;
  double time_ = 0.0;
  std::uint64_t step_ = 0;
  std::uint64_t particle_updates_ = 0;
  std::uint64_t regularizations_ = 0;
  double kinetic_removed_ = 0.0;
  struct SinceLast {
    std::uint64_t steps = 0;
    double time = 0.0;
  } since_;  ///< steps and time since the last regularization (or the start)
  PhaseTimes times_;
};

}  // namespace rsph
