#pragma once
// The figure each example draws at the end of a run: scripts/plot_<test>.py over the run's folder, written to
// <folder>/<test>.png, when Debian's python3 with matplotlib and the script are there. --no-plot (or
// RSPH_NO_PLOT=1 in the environment, for batch jobs) skips it. A figure that cannot be drawn is reported on
// stderr and leaves the run's result and exit code as they are.
#include "common/cli.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

extern char** environ;

namespace rsph::examples {

#ifndef RSPH_SCRIPTS_DIR
#define RSPH_SCRIPTS_DIR ""
#endif

/// Runs `args` (args[0] an absolute path) and waits; stdout goes to /dev/null when `silent`, stderr too when
/// `quiet_errors`. Returns the exit status, or -1 when the process could not start or did not exit.
inline int run_process(const std::vector<std::string>& args, bool silent, bool quiet_errors) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (silent) posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  if (quiet_errors) posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int started = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (started != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

/// Draws the run's figure (see the header comment); `test` names the script, plot_<test>.py.
inline void draw_figure(const CommonOptions& common, const std::filesystem::path& dir, const std::string& test) {
  const char* off = std::getenv("RSPH_NO_PLOT");
  if (common.no_plot || (off && std::string(off) == "1") || !on_root()) return;
  if (std::string(RSPH_SCRIPTS_DIR).empty()) return;  // built without the scripts' folder: not the cwd's files
  const std::string python = "/usr/bin/python3";
  const auto script = std::filesystem::path(RSPH_SCRIPTS_DIR) / ("plot_" + test + ".py");
  if (!std::filesystem::exists(python) || !std::filesystem::exists(script)) return;
  if (run_process({python, "-c", "import matplotlib"}, true, true) != 0) return;  // no matplotlib: no figure
  const auto png = dir / (test + ".png");
  const int status = run_process({python, script.string(), dir.string(), "--png", png.string()}, true, false);
  if (status != 0)
    fmt::print(stderr, "no figure drawn: {} exited with {} (the run's results stand)\n", script.string(), status);
  else if (!common.quiet)
    fmt::print("figure: {}\n", png.string());
}

}  // namespace rsph::examples
