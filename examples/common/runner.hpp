#pragma once
// The one run loop every example and its tests drive: a simulation stepped through a sequence of stops
// (simulated times, or regularization counts), with a hook after each step (a sensor, particles
// leaving the domain, the conservation log), a hook at the start and at each stop (snapshots, measures),
// the cost recorded the same way for all, and a progress line. The figures every summary.json carries
// are written by one function too.
#include "common/checkpoints.hpp"
#include "common/cli.hpp"
#include "common/figure.hpp"
#include "common/run_helpers.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::examples {

/// A stop at simulated time t: the last step is shortened to land on it.
struct AtTime {
  double t;
  template <class Sim>
  bool reached(const Sim& sim) const {
    return sim.time() >= t * (1.0 - 1e-14);
  }
  template <class Sim>
  double dt_limit(const Sim& sim) const {
    return t - sim.time();
  }
};

/// A stop once the simulation has regularized n times (steps are not shortened).
struct AfterRegularizations {
  std::uint64_t n;
  template <class Sim>
  bool reached(const Sim& sim) const {
    return sim.regularizations() >= n;
  }
  template <class Sim>
  double dt_limit(const Sim&) const {
    return std::numeric_limits<double>::infinity();
  }
};

/// Stops at the given times, ascending.
inline std::vector<AtTime> at_times(const std::vector<double>& times) {
  std::vector<AtTime> stops;
  for (const double t : times) stops.push_back({t});
  return stops;
}

/// n stops evenly spaced in (0, t_end], the last at t_end.
inline std::vector<AtTime> evenly(double t_end, int n) {
  std::vector<AtTime> stops;
  for (int k = 1; k <= n; ++k) stops.push_back({t_end * k / n});
  return stops;
}

/// Refuses an end time the run could never reach: more than 1e10 steps of the present time step dt (--t-end
/// 1e300 would otherwise run until stopped, writing curves all the while).
inline void check_reachable(double t_end, double time, double dt) {
  const double steps = (t_end - time) / dt;
  require(steps < 1e10, "the end time " + default_text(t_end) + " lies " + fmt::format("{:.1e}", steps) + " steps of " +
                            default_text(dt) + " away: choose a reachable end time");
}
template <class Sim, class Stop>
void check_reachable(const Sim& sim, const std::vector<Stop>& stops) {
  if constexpr (std::is_same_v<Stop, AtTime>)
    if (!stops.empty()) check_reachable(stops.back().t, sim.time(), sim.time_step());
}

/// Hooks that do nothing, for a run that needs none.
struct NoHook {
  template <class... A>
  void operator()(A&&...) const {}
};

/// Steps `sim` through `stops` in turn. after_step(sim) follows every call of step() (a block of
/// individual steps is one call; the programs update their progress line there); at_stop(sim, k) comes
/// at the start (k = -1) and at each stop k. With `checkpoints`, a checkpoint may follow each step, and a
/// resumed run restores sim and continues towards the stop it was heading for. Returns what the run cost.
template <class Sim, class Stop, class AfterStep, class AtStop>
RunCost run_stops(Sim& sim, const std::vector<Stop>& stops, AfterStep&& after_step, AtStop&& at_stop,
                  Checkpoints* checkpoints = nullptr) {
  check_reachable(sim, stops);
  RunCost cost;
  cost.begin(sim);
  const bool resume = checkpoints && checkpoints->resuming();
  const std::size_t first = resume ? checkpoints->restore(sim, cost) : 0;
  if (!resume) at_stop(sim, -1);
  for (std::size_t k = first; k < stops.size(); ++k) {
    while (!stops[k].reached(sim)) {
      const std::uint64_t steps_before = sim.steps();
      sim.step(stops[k].dt_limit(sim));
      after_step(sim);
      cost.count_steps(sim, steps_before);
      if (checkpoints) checkpoints->after_step(sim, k, cost);
    }
    at_stop(sim, static_cast<int>(k));
  }
  cost.finish(sim);
  return cost;
}

namespace detail {
/// The particles `p` at `path`, described by `info`; with `comm`, every rank writes its own into the one file.
/// A template of the particle set alone, so that simulations of one set share its code.
template <class Particles>
void write_particles(const std::filesystem::path& path, const Particles& p, double time, std::uint64_t step,
                     const io::SnapshotInfo& info, [[maybe_unused]] const RankComm* comm) {
#ifdef RSPH_WITH_MPI
  if (comm) {
    io::write_snapshot(comm->broadcast(path.string()), p, time, step, info, mpi::FileTurns(*comm));
    return;
  }
#endif
  io::write_snapshot(path, p, time, step, info);
}
}  // namespace detail

/// A snapshot of `sim` at `path` with the positions of `objects` (io::write_snapshot); on many ranks every rank
/// writes its own particles into the one file, together through parallel HDF5 or in turns (mpi::FileTurns).
template <class Sim>
void write_snapshot(const std::filesystem::path& path, const Sim& sim, const std::string& units,
                    std::vector<std::pair<std::string, std::vector<double>>> objects = {}) {
  auto info = io::describe_run(sim.box(), sim.eos(), units);
  info.objects = std::move(objects);
  detail::write_particles(path, sim.particles(), sim.time(), sim.steps(), info, comm_of_ranks(sim));
}

/// The snapshots of a run in `dir`: snap_00000.h5, snap_00001.h5, ... in the order written.
class Snapshots {
 public:
  /// `units`: the scene's unit system, in words, for the snapshots' `units` attribute.
  explicit Snapshots(std::filesystem::path dir, std::string units = "dimensionless code units")
      : dir_(std::move(dir)), units_(std::move(units)) {}
  /// On many ranks every rank adds its own particles to the one file.
  template <class Sim>
  void write(const Sim& sim) {
    write_snapshot(dir_ / io::snapshot_name(next_++), sim, units_);
  }
  template <class Archive>
  void checkpoint(Archive& ar) {
    ar("snapshots_written", next_);
  }

 private:
  std::filesystem::path dir_;
  std::string units_;
  std::size_t next_ = 0;
};

/// The figures of a run's cost that every summary.json carries: wall seconds, steps, particle updates per
/// second, the mean particle count, regularizations and their seconds, seconds per phase; on many ranks how they
/// shared the work (write_ranks).
inline void write_cost(io::Json& summary, const RunCost& cost) {
  summary.set("wall_seconds", cost.wall_seconds).set("steps", cost.steps);
  summary.set("particle_updates_per_second", static_cast<double>(cost.updates) / cost.wall_seconds);
  summary.set("mean_particles", cost.mean_particles);
  summary.set("regularizations", cost.regularizations).set("regularization_seconds", cost.phases.regularization);
  summary.set("phase_seconds", phase_json(cost.phases));
  summary.merge(cost.ranks);
}

/// What describes the run: every resolved parameter, the command line and the version of rsph.
inline void write_run_record(io::Json& summary, const CommonOptions& common) {
  io::Json parameters;
  for (const auto& [name, value] : common.parameters) parameters.set(name, value);
  summary.set("parameters", parameters).set("command_line", common.command_line).set("version", RSPH_VERSION);
}

/// What the scheme of `sim` did, where it has it: the remap's order (and, for the second, how often the limiter
/// cut a gradient and how many old cells the thermal floor sent back to first order), the level counts of a
/// multi-level lattice and the consistent-gradient solves.
template <class Sim>
void write_scheme(io::Json& summary, const Sim& sim) {
  if constexpr (requires { sim.regularizer().remap_order(); }) {
    summary.set("remap", sim.regularizer().remap_order());
    sim.regularizer().order_figures([&](const char* name, auto value) { summary.set(name, value); });
  }
  if constexpr (requires { sim.regularizer().lattice().max_level; })
    summary.set("levels", level_counts(sim.regularizer().log(), sim.steps()));
  GradientSolves::of(sim).write_to(summary);
}

}  // namespace rsph::examples
