#pragma once
// A program's checkpoints: when one is written (every so much simulated time in the scene's unit, at
// --max-wall, on SIGINT or SIGTERM), what it holds (the simulation, the run loop's place and cost, and each
// part of the program's own state: counters, samples, curves written so far), and the resume that continues
// from it bit for bit. DIR/checkpoint.h5 is replaced whole each time (io::Archive). On many ranks every rank
// writes its own particles into the one file, in turn, and decides with the others when to write and stop; a
// resume on any rank count shares the file's particles out again (Simulation::checkpoint).
#include "common/cli.hpp"
#include "common/run_helpers.hpp"
#include "rsph/io/checkpoint.hpp"
#ifdef RSPH_WITH_MPI
#include "rsph/mpi/file_turns.hpp"
#endif

#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <functional>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsph::examples {

namespace detail {
/// The signal that asked the run to stop (0: none). A signal handler reaches only variables of static
/// storage; this is the programs' one such variable.
inline volatile std::sig_atomic_t stop_signal = 0;
inline void on_stop_signal(int sig) {
  stop_signal = sig;
  std::signal(sig, SIG_DFL);  // a second signal ends the program at once
}
}  // namespace detail

/// The parameters that must match between a run and its resume (how many threads, the progress line and
/// when to checkpoint may change).
inline std::string resumable_parameters(const CommonOptions& common) {
  std::string text;
  for (const auto& [name, value] : common.parameters)
    if (name != "threads" && name != "quiet" && name != "checkpoint-every" && name != "max-wall" && name != "stop-at")
      text += name + " = " + value + "\n";
  return text;
}

/// What the checkpoints read of a simulation, its type erased so that their code is compiled once and not once
/// per simulation type: its clock, its own fields (Simulation::checkpoint, for saving and restoring) and, on many
/// ranks, the communicator through which the ranks decide together and write in turns.
struct Checkpointed {
  double time = 0.0;
  std::uint64_t steps = 0;
  std::function<void(io::Archive&)> fields;
  const RankComm* comm = nullptr;  ///< on more than one rank
};

template <class Sim>
Checkpointed checkpointed(Sim& sim) {
  return {sim.time(), sim.steps(), [&sim](io::Archive& ar) { sim.checkpoint(ar); }, comm_of_ranks(sim)};
}

class Checkpoints;

/// checkpoints->add(name, fields) where there are checkpoints; nothing otherwise.
template <class Fields>
auto add_part(Checkpoints* checkpoints, const std::string& name, Fields&& fields);

class Checkpoints {
 public:
  /// `unit`: simulated time per unit of --checkpoint-every (an orbit, or 1); `unit_name` names it in messages.
  /// `dir`: the run's output folder (on ranks other than 0 their private one; the checkpoint is in the run's).
  Checkpoints(const CommonOptions& common, const std::filesystem::path& dir, std::string program, double unit = 1.0)
      : file_(run_folder(common, dir) / "checkpoint.h5"),
        program_(std::move(program)),
        parameters_(resumable_parameters(common)),
        every_(common.checkpoint_every * unit),
        max_wall_(common.max_wall * 60.0),
        max_wall_text_(default_text(common.max_wall)),
        stop_at_(common.stop_at * unit),
        stop_at_text_(default_text(common.stop_at)),
        resume_(!common.resume.empty()),
        command_(program_ + " --resume " + run_folder(common, dir).string()) {
    detail::stop_signal = 0;
    std::signal(SIGINT, detail::on_stop_signal);
    std::signal(SIGTERM, detail::on_stop_signal);
  }
  ~Checkpoints() {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
  Checkpoints(const Checkpoints&) = delete;
  Checkpoints& operator=(const Checkpoints&) = delete;

  /// A part of the program's own state, listed once by fields(ar) for saving and restoring, while the
  /// returned Part lives (fields usually refers to the caller's locals).
  class Part {
   public:
    Part(Checkpoints* owner, std::string name) : owner_(owner), name_(std::move(name)) {}
    ~Part() {
      if (owner_) std::erase_if(owner_->parts_, [&](const auto& p) { return p.first == name_; });
    }
    Part(const Part&) = delete;
    Part& operator=(const Part&) = delete;

   private:
    Checkpoints* owner_;
    std::string name_;
  };
  [[nodiscard]] Part add(const std::string& name, std::function<void(io::Archive&)> fields) {
    parts_.emplace_back(name, std::move(fields));
    return Part(this, name);
  }
  const std::filesystem::path& file() const { return file_; }
  bool resuming() const { return resume_; }

  /// On --resume: restores sim, the run's cost so far and every part; returns the stop the run was heading
  /// for.
  template <class Sim>
  std::size_t restore(Sim& sim, RunCost& cost) {
    const std::size_t stop = load(checkpointed(sim), cost);
    last_ = index_of(sim.time());
    seen_ = sim.time();  // a resume from --stop-at goes on past it
    return stop;
  }

  /// On --resume, `value` as the checkpoint holds it under `key` (a part's field, for a program that must
  /// know before its run where the run had got to); otherwise nothing.
  template <class T>
  void read_ahead(const std::string& key, T& value) const {
    if (!resume_) return;
    auto ar = io::Archive::load(file_);
    ar(key, value);
  }

  /// After each step on the way to stop k: writes a checkpoint when --checkpoint-every says; on --max-wall,
  /// --stop-at or a signal writes one and throws Stopped.
  template <class Sim>
  void after_step(Sim& sim, std::size_t k, RunCost& cost) {
    at_step(checkpointed(sim), k, cost);
  }

 private:
  /// The run's output folder, on every rank.
  static std::filesystem::path run_folder(const CommonOptions& common, const std::filesystem::path& dir) {
    if (on_root()) return dir;
    return common.resume.empty() ? std::filesystem::path(common.out) : std::filesystem::path(common.resume);
  }

  double index_of(double time) const { return every_ > 0.0 ? std::floor(time / every_ * (1.0 + 1e-12)) : 0.0; }

  /// Reads the checkpoint into sim, the cost and every part; returns the stop the run was heading for.
  std::size_t load(const Checkpointed& sim, RunCost& cost) {
    const io::Share share{std::size_t(this_rank()), std::size_t(rank_count())};
#ifdef RSPH_WITH_MPI
    if (sim.comm) {  // every rank reads its share, together where the ranks write together
      const mpi::FileTurns turns(*sim.comm);
      auto ar = io::Archive::load(file_, share, turns.reading());
      return load_from(ar, sim, cost);
    }
#endif
    auto ar = io::Archive::load(file_, share);
    return load_from(ar, sim, cost);
  }
  std::size_t load_from(io::Archive& ar, const Checkpointed& sim, RunCost& cost) {
    std::string program, parameters;
    ar("run/program", program);
    ar("run/parameters", parameters);
    require(program == program_, "the checkpoint " + file_.string() + " was written by " + program);
    if (parameters != parameters_)
      throw InputError("the checkpoint " + file_.string() + " was written with other parameters: " +
                       first_difference(parameters, parameters_) + "; resume takes the run's own params.cfg");
    std::size_t stop = 0;
    ar("run/stop", stop);
    state(ar, sim, cost);
    resume_ = false;  // later runs of the same program (the next case of a sweep) start afresh
    return stop;
  }

  void at_step(const Checkpointed& sim, std::size_t k, RunCost& cost) {
    const double index = index_of(sim.time);
    bool wall = max_wall_ > 0.0 && seconds_since(started_) >= max_wall_;  // this process's time
    int signal = detail::stop_signal;
#ifdef RSPH_WITH_MPI
    if (sim.comm) {  // every rank writes and stops when one of them would
      std::array<double, 2> ask{double(wall), double(signal)};
      sim.comm->reduce_in_place(std::span<double>(ask), MPI_MAX);
      wall = ask[0] > 0.0;
      signal = static_cast<int>(ask[1]);
    }
#endif
    const double mark = stop_at_ * (1.0 - 1e-12);  // --stop-at: this step passed it (the same on every rank)
    const bool at = stop_at_ > 0.0 && seen_ < mark && sim.time >= mark;
    seen_ = sim.time;
    if (index > last_ || wall || signal || at) {
      write(sim, k, cost);
      last_ = index;
    }
    if (!wall && !signal && !at) return;
    const std::string why = signal == SIGINT    ? "SIGINT"
                            : signal == SIGTERM ? "SIGTERM"
                            : wall              ? "--max-wall " + max_wall_text_ + " minutes"
                                                : "--stop-at " + stop_at_text_;
    throw Stopped("stopped by " + why + " at t = " + default_text(sim.time) + " (step " + std::to_string(sim.steps) +
                  "); checkpoint written to " + file_.string() + "; continue with `" + command_ + "`");
  }

  void write(const Checkpointed& sim, std::size_t k, RunCost& cost) {
    auto ar = io::Archive::for_saving();
    ar("run/program", program_);
    ar("run/parameters", parameters_);
    ar("run/stop", k);
    state(ar, sim, cost);
#ifdef RSPH_WITH_MPI
    if (sim.comm) return ar.write(file_, mpi::FileTurns(*sim.comm));
#endif
    ar.write(file_);
  }

  /// The state itself, the same list for saving and restoring: the simulation, the cost and every part.
  void state(io::Archive& ar, const Checkpointed& sim, RunCost& cost) {
    sim.fields(ar);
    cost.checkpoint(ar);
    for (auto& [name, fields] : parts_) {
      const auto scope = ar.scope(name);
      fields(ar);
    }
  }

  static std::string first_difference(const std::string& a, const std::string& b) {
    std::size_t i = 0;
    while (i < a.size() && i < b.size() && a[i] == b[i]) ++i;
    auto line_at = [i](const std::string& s) {
      const auto from = s.rfind('\n', i == 0 ? 0 : i - 1);
      const auto begin = from == std::string::npos || i == 0 ? 0 : from + 1;
      return s.substr(begin, s.find('\n', begin) - begin);
    };
    return "'" + line_at(a) + "' against '" + line_at(b) + "'";
  }

  std::filesystem::path file_;
  std::string program_, parameters_;
  double every_, max_wall_;
  std::string max_wall_text_;
  double stop_at_;
  std::string stop_at_text_;
  double seen_ = -std::numeric_limits<double>::infinity();  ///< the simulated time after the last step
  bool resume_;
  std::string command_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  double last_ = 0.0;  ///< the index floor(t / every) of the last checkpoint (or of the start)
  std::vector<std::pair<std::string, std::function<void(io::Archive&)>>> parts_;
};

template <class Fields>
auto add_part(Checkpoints* checkpoints, const std::string& name, Fields&& fields) {
  if (!checkpoints) return Checkpoints::Part(nullptr, name);
  return checkpoints->add(name, std::forward<Fields>(fields));
}

}  // namespace rsph::examples
