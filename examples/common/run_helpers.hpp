#pragma once
// Run-loop pieces every example shares: the conservation log and snapshot times.
#include "common/ranks.hpp"
#include "rsph/core/diagnostics.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/json.hpp"
#include "rsph/kernel/cubic_spline.hpp"
#include "rsph/kernel/quintic_spline.hpp"
#include "rsph/kernel/wendland.hpp"
#include "rsph/regularize/remap_order.hpp"
#include "rsph/simulation.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace rsph::examples {

/// The remap orders a scene's RSPH method offers (`--remap`).
inline void check_remap(const std::string& remap) {
  require(remap == "first" || remap == "second", "unknown remap '" + remap + "' (first, second)");
}

/// Calls run(regularize::FirstOrder{}) or run(regularize::SecondOrder{}) as `remap` says.
template <class Run>
decltype(auto) with_remap(const std::string& remap, Run&& run) {
  if (remap == "second") return run(regularize::SecondOrder{});
  return run(regularize::FirstOrder{});
}

/// The kernels a program offers (`--kernel`): the cubic and quintic splines and Wendland's C2, C4 and C6.
inline constexpr const char* kernel_names = "cubic, quintic, wendland-c2, wendland-c4, wendland-c6";
inline void check_kernel(const std::string& name) {
  require(name == "cubic" || name == "quintic" || name == "wendland-c2" || name == "wendland" ||
              name == "wendland-c4" || name == "wendland-c6",
          "unknown kernel '" + name + "' (" + kernel_names + ")");
}

/// Calls run(K{}) with the kernel `name` names ("wendland" is Wendland C2).
template <class Run>
decltype(auto) with_kernel(const std::string& name, Run&& run) {
  check_kernel(name);
  if (name == "quintic") return run(kernel::QuinticSpline{});
  if (name == "wendland-c2" || name == "wendland") return run(kernel::WendlandC2{});
  if (name == "wendland-c4") return run(kernel::WendlandC4{});
  if (name == "wendland-c6") return run(kernel::WendlandC6{});
  return run(kernel::CubicSpline{});
}

/// conservation.csv: one row per step of the conserved totals.
template <int D>
class ConservationLog {
 public:
  explicit ConservationLog(const std::filesystem::path& path) : csv_(path, columns()) {}
  void record(double time, std::uint64_t step, const Conservation<D>& c) {
    std::array<double, 7 + D> row;  // fixed size: no reallocation for GCC 12's overflow checker to misread
    row[0] = time;
    row[1] = static_cast<double>(step);
    row[2] = c.mass;
    for (int k = 0; k < D; ++k) row[static_cast<std::size_t>(3 + k)] = c.momentum[k];
    row[3 + D] = c.angular_momentum;
    row[4 + D] = c.kinetic;
    row[5 + D] = c.thermal;
    row[6 + D] = c.total_energy();
    csv_.row(std::vector<double>(row.begin(), row.end()));
  }
  void close() { csv_.close(); }
  template <class Archive>
  void checkpoint(Archive& ar) {
    csv_.checkpoint(ar, "conservation");
  }

 private:
  static std::vector<std::string> columns() {
    std::vector<std::string> c{"time", "step", "mass"};
    const char* axis[] = {"momentum_x", "momentum_y", "momentum_z"};
    for (int k = 0; k < D; ++k) c.emplace_back(axis[k]);
    c.insert(c.end(), {"angular_momentum", "kinetic", "thermal", "total_energy"});
    return c;
  }
  io::CsvWriter csv_;
};

/// How a decomposed run shared its work (on more than one rank): ranks, the halos' sizes against the particles'
/// (and how often the remap by owners gathered farther), the bytes the ranks sent each other per step, the most
/// wall seconds a rank spent communicating (or waiting for the others), the ranks a rank messaged per exchange, and
/// the exchanges and the reductions per step (each a message latency). `n_own`: this rank's particles.
template <class Domain>
void write_ranks(io::Json& summary, const Domain& d, std::size_t n_own, std::uint64_t steps_taken) {
  const auto& c = d.counts();
  const double particles = static_cast<double>(d.sum(n_own));
  summary.set("ranks", static_cast<std::uint64_t>(d.ranks()));
  if (d.ranks() == 1) return;  // one rank sends nothing
  summary.set("halo_fraction", static_cast<double>(d.sum(c.halo_points)) / particles);
  summary.set("remap_halo_fraction", static_cast<double>(d.sum(c.remap_halo_points)) / particles);
  summary.set("remap_halo_widenings", c.remap_widenings);  // alike on every rank
  const double steps = std::max<double>(1, static_cast<double>(steps_taken));
  summary.set("bytes_sent_per_step", static_cast<double>(d.sum(c.bytes_sent)) / steps);
  summary.set("particles_migrated", d.sum(c.migrated)).set("partitions", c.partitions);
  summary.set("communication_seconds", d.max(d.communication_seconds()));
  // the ranks a rank sent to in an exchange, on average (an exchange messages only those it has data for)
  summary.set("messages_per_exchange",
              static_cast<double>(d.sum(d.comm().messages())) /
                  static_cast<double>(std::max<std::uint64_t>(1, d.sum(d.comm().exchanges()))));
  // exchanges are collective: every rank counts the same, each paying a message latency per neighbour rank
  summary.set("exchanges_per_step", static_cast<double>(d.comm().exchanges()) / steps);
  summary.set("collectives_per_step", static_cast<double>(d.comm().collectives()) / steps);
}

/// What a run cost, recorded the same way by every scene's run loop: begin(), count_steps() after each
/// call of step(), finish().
struct RunCost {
  double wall_seconds = 0.0, mean_particles = 0.0;
  std::size_t particles_initial = 0, particles_final = 0;
  std::uint64_t steps = 0, updates = 0, regularizations = 0;
  PhaseTimes phases;
  io::Json ranks;  ///< how the ranks shared the work (write_ranks; empty in a build without MPI)

  template <class Sim>
  void begin(const Sim& sim) {
    started_ = std::chrono::steady_clock::now();
    particles_initial = count_over_ranks(sim, sim.particles().n_real);
  }
  /// Wall seconds of the run so far, those before a resume included.
  double elapsed() const {
    return earlier_seconds_ + std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  }
  /// Saves or restores the figures that accumulate (a checkpoint archive, io/checkpoint.hpp).
  template <class Archive>
  void checkpoint(Archive& ar) {
    const auto scope = ar.scope("cost");
    double seconds = elapsed();
    ar("wall_seconds", seconds);
    ar.total("particle_steps", particle_steps_);  // of this rank's particles
    if (!ar.saving()) {
      earlier_seconds_ = seconds;
      started_ = std::chrono::steady_clock::now();
    }
  }
  /// After a call of step() that began at steps_before: a block of individual steps counts each.
  template <class Sim>
  void count_steps(const Sim& sim, std::uint64_t steps_before) {
    particle_steps_ += static_cast<double>(sim.particles().n_real) * static_cast<double>(sim.steps() - steps_before);
  }
  template <class Sim>
  void finish(const Sim& sim) {
    wall_seconds = elapsed();
    particles_final = count_over_ranks(sim, sim.particles().n_real);
    steps = sim.steps();
    updates = count_over_ranks(sim, sim.particle_updates());
    std::array<double, 1> particle_steps{particle_steps_};  // of this rank's particles
    sum_over_ranks(sim, particle_steps);
    mean_particles = steps > 0 ? particle_steps[0] / static_cast<double>(steps) : 0.0;
    regularizations = sim.regularizations();
    phases = sim.phase_times();
    if constexpr (Sim::distributed) write_ranks(ranks, sim.domain(), sim.particles().n_real, sim.steps());
  }

 private:
  std::chrono::steady_clock::time_point started_;
  double earlier_seconds_ = 0.0;  ///< before a resume
  double particle_steps_ = 0.0;
};

/// Removes the real particles at positions where gone(x) holds and recomputes the rates if any went;
/// returns their mass and adds their number to `removed`.
template <class Sim, class Gone>
double remove_particles(Sim& sim, Gone&& gone, std::size_t& removed) {
  auto& p = sim.particles();
  bool any = false;
  for (std::size_t a = 0; a < p.n_real && !any; ++a) any = gone(p.x[a]);
  if constexpr (Sim::distributed)
    any = std::as_const(sim).domain().any(any);  // every rank recomputes the rates, or none
  if (!any) return 0.0;
  std::array<double, 2> gone_here{};  // mass, count
  gone_here[1] = static_cast<double>(p.erase_if([&](std::size_t a) {
    const bool out = gone(p.x[a]);
    if (out) gone_here[0] += p.m[a];
    return out;
  }));
  if constexpr (Sim::distributed) std::as_const(sim).domain().sum_in_place(gone_here);
  removed += static_cast<std::size_t>(gone_here[1]);
  sim.compute_rates();
  return gone_here[0];
}

/// Relative change of a conserved quantity, guarded against a zero reference.
inline double relative_change(double now, double start) {
  return std::abs(now - start) / std::max(std::abs(start), 1e-300);
}

/// The phase timings as a JSON object.
template <class Times>
io::Json phase_json(const Times& t) {
  io::Json j;
  j.set("neighbors", t.neighbors).set("density", t.density).set("forces", t.forces);
  j.set("integrate", t.integrate).set("regularization", t.regularization);
  return j;
}

/// The psi solves of consistent gradients (physics::ConsistentGradient) and their conjugate-gradient
/// iterations, taken from a simulation that has them; written to summary.json only then.
struct GradientSolves {
  bool present = false;
  std::uint64_t solves = 0, iterations = 0;

  template <class Sim>
  static GradientSolves of(const Sim& sim) {
    if constexpr (requires { sim.gradient_solves(); })
      return {true, sim.gradient_solves(), sim.gradient_solve_iterations()};
    else
      return {};
  }
  void write_to(io::Json& j) const {
    if (present) j.set("gradient_solves", solves).set("gradient_solve_iterations", iterations);
  }
};

/// Particles per resolution level from a regularization log: the counts the last regularization left
/// and their average over steps (each regularization's counts weighted by the steps until the next).
/// On many ranks, every rank's log is the whole run's.
template <class Log>
io::Json level_counts(const Log& log, std::uint64_t total_steps) {
  io::Json j;
  if (log.empty()) return j;
  const std::size_t n_levels = log.back().stats.per_level.size();
  std::vector<double> mean(n_levels, 0.0), last(n_levels, 0.0);  // [0, n): the time average; then the last
  for (std::size_t k = 0; k < log.size(); ++k) {
    const std::uint64_t until = k + 1 < log.size() ? log[k + 1].step : total_steps;
    const auto steps = static_cast<double>(until - log[k].step);
    for (std::size_t l = 0; l < std::min(mean.size(), log[k].stats.per_level.size()); ++l)
      mean[l] += steps * static_cast<double>(log[k].stats.per_level[l]);
  }
  for (std::size_t l = 0; l < n_levels; ++l) last[l] = static_cast<double>(log.back().stats.per_level[l]);
  const double span = static_cast<double>(std::max<std::uint64_t>(total_steps - log.front().step, 1));
  std::vector<io::Json> per_level;
  for (std::size_t l = 0; l < mean.size(); ++l) {
    io::Json e;
    e.set("level", static_cast<std::uint64_t>(l))
        .set("final", static_cast<std::uint64_t>(std::llround(last[l])))
        .set("time_average", mean[l] / span);
    per_level.push_back(e);
  }
  j.set("per_level", per_level);
  std::size_t capped = 0;
  for (const auto& r : log) capped += r.stats.capped_blocks;
  j.set("capped_blocks", static_cast<std::uint64_t>(capped));
  return j;
}

}  // namespace rsph::examples
