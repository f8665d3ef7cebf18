#pragma once
// A program's checkpoints: when one is written (every so much simulated time in the scene's unit, at
// --max-wall, on SIGINT or SIGTERM), what it holds (the simulation, the run loop's place and cost, and each
// part of the program's own state: counters, samples, curves written so far), and the resume that continues
// from it bit for bit. DIR/checkpoint.h5 is replaced whole each time (io::Archive).
#include "common/cli.hpp"
#include "common/run_helpers.hpp"
#include "rsph/io/checkpoint.hpp"

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <functional>
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
    if (name != "threads" && name != "quiet" && name != "checkpoint-every" && name != "max-wall")
      text += name + " = " + value + "\n";
  return text;
}

class Checkpoints;

/// checkpoints->add(name, fields) where there are checkpoints; nothing otherwise.
template <class Fields>
auto add_part(Checkpoints* checkpoints, const std::string& name, Fields&& fields);

class Checkpoints {
 public:
  /// `unit`: simulated time per unit of --checkpoint-every (an orbit, or 1); `unit_name` names it in messages.
  Checkpoints(const CommonOptions& common, const std::filesystem::path& dir, std::string program, double unit = 1.0)
      : file_(dir / "checkpoint.h5"),
        program_(std::move(program)),
        parameters_(resumable_parameters(common)),
        every_(common.checkpoint_every * unit),
        max_wall_(common.max_wall * 60.0),
        max_wall_text_(default_text(common.max_wall)),
        resume_(!common.resume.empty()),
        command_(program_ + " --resume " + dir.string()) {
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
    auto ar = io::Archive::load(file_);
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
    last_ = index_of(sim.time());
    resume_ = false;  // later runs of the same program (the next case of a sweep) start afresh
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

  /// After each step on the way to stop k: writes a checkpoint when --checkpoint-every says; on --max-wall
  /// or a signal writes one and throws Stopped.
  template <class Sim>
  void after_step(Sim& sim, std::size_t k, RunCost& cost) {
    const double index = index_of(sim.time());
    const bool wall = max_wall_ > 0.0 && seconds_since(started_) >= max_wall_;  // this process's time
    const int signal = detail::stop_signal;
    if (index > last_ || wall || signal) {
      write(sim, k, cost);
      last_ = index;
    }
    if (!wall && !signal) return;
    const std::string why = signal == SIGINT    ? "SIGINT"
                            : signal == SIGTERM ? "SIGTERM"
                                                : "--max-wall " + max_wall_text_ + " minutes";
    throw Stopped("stopped by " + why + " at t = " + default_text(sim.time()) + " (step " +
                  std::to_string(sim.steps()) + "); checkpoint written to " + file_.string() + "; continue with `" +
                  command_ + "`");
  }

 private:
  double index_of(double time) const { return every_ > 0.0 ? std::floor(time / every_ * (1.0 + 1e-12)) : 0.0; }

  template <class Sim>
  void write(Sim& sim, std::size_t k, RunCost& cost) {
    auto ar = io::Archive::for_saving();
    ar("run/program", program_);
    ar("run/parameters", parameters_);
    ar("run/stop", k);
    state(ar, sim, cost);
    ar.write(file_);
  }

  /// The state itself, the same list for saving and restoring: the simulation, the cost and every part.
  template <class Sim>
  void state(io::Archive& ar, Sim& sim, RunCost& cost) {
    sim.checkpoint(ar);
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
