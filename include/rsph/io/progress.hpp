#pragma once
// One status line with an ETA on a terminal; silent when stderr is not a terminal.
#include <fmt/format.h>

#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

namespace rsph::io {

class Progress {
 public:
  explicit Progress(std::string label, double t_end)
      : label_(std::move(label)), t_end_(t_end), start_(clock::now()), last_(start_), enabled_(isatty(2) != 0) {}

  void update(double t, std::uint64_t step) {
    if (!enabled_) return;
    if (!t_first_) t_first_ = t;  // a resumed run starts part of the way: its ETA counts from there
    const auto now = clock::now();
    if (now - last_ < std::chrono::milliseconds(250)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double frac = t_end_ > 0 ? std::min(1.0, t / t_end_) : 1.0;
    const double done = t - *t_first_, left = t_end_ - t;
    const double eta = done > 0 && left > 0 ? elapsed * left / done : 0.0;
    fmt::print(stderr, "\r{} {:5.1f}%  t={:.4g}  step {}  elapsed {}  ETA {}   ", label_, 100.0 * frac, t, step,
               clock_text(elapsed), clock_text(eta));
    std::fflush(stderr);
    shown_ = true;
  }
  /// Clears the line (the summary printed next starts on a clean one).
  void finish() {
    if (shown_) fmt::print(stderr, "\r\033[K");
    std::fflush(stderr);
    shown_ = false;
  }
  ~Progress() { finish(); }

  static std::string clock_text(double s) {
    const long t = static_cast<long>(s + 0.5);
    if (t >= 3600) return fmt::format("{}h{:02}m", t / 3600, (t / 60) % 60);
    if (t >= 60) return fmt::format("{}m{:02}s", t / 60, t % 60);
    return fmt::format("{}s", t);
  }

 private:
  using clock = std::chrono::steady_clock;
  std::string label_;
  double t_end_;
  clock::time_point start_, last_;
  bool enabled_;
  bool shown_ = false;
  std::optional<double> t_first_;  ///< the time of the first update
};

}  // namespace rsph::io
