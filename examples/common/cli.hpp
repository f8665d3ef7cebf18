#pragma once
// What every example shares: the common flags, the output folder, error reporting and exit codes.
#include "common/levels.hpp"
#include "common/ranks.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/io/atomic_file.hpp"

#include <fmt/format.h>
#include <boost/program_options.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace rsph::examples {

namespace po = boost::program_options;

/// The text a person writes for a default: the shortest that reads back to the same value (0.2, 4.8e-05).
template <class T>
std::string default_text(const T& v) {
  if constexpr (std::is_same_v<T, std::string>)
    return v;
  else
    return fmt::format("{}", v);
}

/// A flag bound to `field`, defaulting to the field's current value, so that a params struct's default is
/// written once (in the struct) and printed by --help as people write it.
template <class T>
po::typed_value<T>* value_of(T& field) {
  return po::value(&field)->default_value(field, default_text(field));
}

/// A number flag whose value must be finite (inf and nan are refused with the flag's name).
inline po::typed_value<double>* finite_value_of(double& field, const std::string& name) {
  return value_of(field)->notifier([name](double v) {
    if (!std::isfinite(v)) throw InputError("--" + name + " must be a finite number (got " + default_text(v) + ")");
  });
}

/// Flags every example has, and what a run records of its parameters.
struct CommonOptions {
  std::string out = "out";
  std::string preset = "paper";
  int threads = 0;
  bool quiet = false;
  bool overwrite = false;
  bool no_plot = false;           ///< no figure at the end of the run (common/figure.hpp)
  double checkpoint_every = 0.0;  ///< in the scene's unit; 0: checkpoints only at --max-wall and on signals
  double max_wall = 0.0;          ///< minutes; 0: no limit
  double stop_at = 0.0;           ///< in the scene's unit; 0: run to the end
  std::string resume;             ///< a run's folder to continue from its checkpoint
  std::string config;             ///< a params.cfg (Boost.Program_options' config-file syntax) read under the flags
  std::string command_line;       ///< as given, for summary.json
  /// Every parameter as resolved (presets applied), one `name = value` line each: params.cfg.
  std::vector<std::pair<std::string, std::string>> parameters;
  /// While the flags are parsed: each flag's name and how to print its field (see Flags, record_run).
  std::vector<std::pair<std::string, std::function<std::string()>>> bound;
};

/// Adds flags one per call, each bound to a field and defaulting to its value:
/// `flag("cells", s.cells, "lattice cells")("h-over-dx", s.h_over_dx, "h / Delta")`. A bool field is a switch, a
/// double must be finite. Each flag is also noted in `common`, so record_run can write what was resolved.
class Flags {
 public:
  Flags(po::options_description& desc, CommonOptions& common) : desc_(desc), common_(common) {}
  template <class T>
  Flags& operator()(const char* name, T& field, const char* help) {
    if constexpr (std::is_same_v<T, bool>)
      desc_.add_options()(name, po::bool_switch(&field), help);
    else if constexpr (std::is_same_v<T, double>)
      desc_.add_options()(name, finite_value_of(field, name), help);
    else
      desc_.add_options()(name, value_of(field), help);
    common_.bound.emplace_back(name, [&field] { return default_text(field); });
    return *this;
  }
  po::options_description& description() { return desc_; }

 private:
  po::options_description& desc_;
  CommonOptions& common_;
};

/// --remap: the order of an RSPH scene's remap, bound to its params field.
inline void add_remap_flag(Flags& flag, std::string& remap) {
  flag("remap", remap,
       "RSPH: the remap's order, first (the paper's eqs. 6-9) or second (limited linear reconstruction)");
}

/// --help, --out, --preset, --threads, --quiet, --overwrite, --no-plot, --config and the checkpoint flags; `quick` says
/// what the quick preset changes (flags given keep their values), `unit` the unit of --checkpoint-every.
inline void add_common_options(Flags& flag, CommonOptions& common, const std::string& quick,
                               const std::string& unit = "simulated time") {
  const std::string preset = "paper: the paper's setup; quick: a small run in seconds (" + quick + ")";
  auto& desc = flag.description();
  desc.add_options()("help,h", "show this help and exit");
  desc.add_options()("out", value_of(common.out), "output folder (created if missing)");
  desc.add_options()("config", po::value(&common.config),
                     "read parameters from FILE (name = value lines, as a run's params.cfg); flags given win");
  desc.add_options()("overwrite", po::bool_switch(&common.overwrite),
                     "reuse an output folder that holds an earlier run, removing that run's files first");
  desc.add_options()("no-plot", po::bool_switch(&common.no_plot),
                     "draw no figure at the end of the run (RSPH_NO_PLOT=1 does the same)");
  flag("preset", common.preset, preset.c_str());
  flag("threads", common.threads, "OpenMP threads (0: all cores)");
  flag("quiet", common.quiet, "no progress line");
  const std::string every =
      "write DIR/checkpoint.h5 every so much " + unit + " (0: only at --max-wall and on SIGINT or SIGTERM)";
  flag("checkpoint-every", common.checkpoint_every, every.c_str());
  flag("max-wall", common.max_wall, "stop with a checkpoint after this many wall-clock minutes (0: no limit)");
  const std::string stop_at = "stop with a checkpoint once the run passes this many " + unit +
                              " (0: run to the end); resume it on any number of ranks";
  flag("stop-at", common.stop_at, stop_at.c_str());
  desc.add_options()("resume", po::value(&common.resume),
                     "continue the run in folder DIR from its checkpoint, with its params.cfg (flags given win)");
}

/// --levels, --block-cells, --refine-above, --coarsen-below and --h-ramp, defaulting to c's values; `who`
/// starts each help line, `levels_help` says what --levels means in the scene.
inline void add_level_options(Flags& flag, DensityJumpLevels& c, const std::string& who,
                              const std::string& levels_help) {
  flag("levels", c.levels, (who + ": " + levels_help).c_str());
  flag("block-cells", c.block_cells, (who + ": level-0 cells per block").c_str());
  flag("refine-above", c.refine_above,
       (who + ": relative density jump between level-0 cells that refines a block").c_str());
  flag("coarsen-below", c.coarsen_below, (who + ": jump below which a block returns to level 0").c_str());
  flag("h-ramp", c.h_ramp,
       (who + ": coarser spacings over which h rises towards a coarser block (0: h jumps)").c_str());
}

/// The folder of a run to resume: it must hold its checkpoint. `tidy`: files a killed run left half-written go.
inline std::filesystem::path resume_output(const std::filesystem::path& dir, bool tidy = true) {
  if (!std::filesystem::is_regular_file(dir / "checkpoint.h5"))
    throw InputError("--resume: no checkpoint in '" + dir.string() +
                     "' (write one with --checkpoint-every or --max-wall)");
  if (!tidy) return dir;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.size() > 8 && name.rfind(".partial") == name.size() - 8) std::filesystem::remove(e.path());
  }
  return dir;
}

/// Parses argv; returns false when --help was shown. Unknown flags throw with their name.
/// How to run a program on many ranks, for --help.
inline std::string many_ranks_help(const std::string& program) {
#ifdef RSPH_WITH_MPI
  return "On many ranks: mpiexec -n 4 " + program +
         " [options] (the same answers as one rank; threads beside ranks need mpiexec --bind-to none).";
#else
  return "On many ranks: mpiexec -n 4 " + program +
         " [options], in a build with MPI and Zoltan (scripts/setup-deps.sh installs them); this one runs in one "
         "process.";
#endif
}

inline bool parse(int argc, char** argv, const po::options_description& desc, po::variables_map& vm,
                  const std::string& usage) {
  po::store(po::parse_command_line(argc, argv, desc), vm);
  if (vm.count("resume") && (vm.count("config") || !vm["out"].defaulted()))
    throw InputError("--resume DIR reads DIR/params.cfg and writes to DIR: leave out --config and --out");
  if (vm.count("resume") && !vm.count("help"))
    resume_output(vm["resume"].as<std::string>(), false);                 // refuses a folder without a checkpoint first
  if ((vm.count("config") || vm.count("resume")) && !vm.count("help")) {  // under the command line: flags win
    const std::string file = vm.count("config")
                                 ? vm["config"].as<std::string>()
                                 : (std::filesystem::path(vm["resume"].as<std::string>()) / "params.cfg").string();
    if (!std::filesystem::is_regular_file(file)) throw InputError("--config: no file '" + file + "'");
    po::store(po::parse_config_file<char>(file.c_str(), desc), vm);
  }
  if (vm.count("help")) {
    fmt::print(
        "{}\n\n{}\n{}\n", usage,
        [&] {
          std::ostringstream s;
          s << desc;
          return s.str();
        }(),
        many_ranks_help(std::filesystem::path(argv[0]).filename().string()));
    return false;
  }
  po::notify(vm);
  return true;
}

/// Checks what the checkpoint flags were given.
inline void check_checkpoint_flags(const CommonOptions& common) {
  require(common.checkpoint_every >= 0.0,
          "--checkpoint-every must be 0 or positive (got " + default_text(common.checkpoint_every) + ")");
  require(common.stop_at >= 0.0,
          "--stop-at must be 0 or a positive simulated time (got " + default_text(common.stop_at) + ")");
  require(common.max_wall >= 0.0,
          "--max-wall must be 0 or a positive number of minutes (got " + default_text(common.max_wall) + ")");
}

/// A comma-separated list of finite numbers given to flag `what`; anything else is an input error.
inline std::vector<double> parse_numbers(const std::string& text, const char* what) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double x = 0.0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || item.find_first_not_of(" ", used) != std::string::npos || !std::isfinite(x))
      throw InputError(std::string(what) + ": '" + item + "' is not a finite number");
    out.push_back(x);
  }
  require(!out.empty(), std::string(what) + ": the list is empty");
  return out;
}

/// Whether --preset asked for the quick run; an unknown preset is an input error.
inline bool quick_preset(const CommonOptions& common) {
  if (common.preset != "quick" && common.preset != "paper")
    throw InputError("unknown preset '" + common.preset + "' (quick, paper)");
  return common.preset == "quick";
}

inline void apply_threads(int threads) {
  require(threads >= 0, "--threads must be 0 (all cores) or a positive count (got " + std::to_string(threads) + ")");
#ifdef _OPENMP
  if (threads > 0) omp_set_num_threads(threads);
#else
  (void)threads;
#endif
}

/// After the presets: every bound flag's resolved value (out, config and overwrite aside: they say where, not
/// what) and the command line, into `common` for params.cfg and summary.json.
inline void record_run(CommonOptions& common, int argc, char** argv) {
  common.parameters.clear();
  for (const auto& [name, text] : common.bound) common.parameters.emplace_back(name, text());
  common.bound.clear();  // they refer to the fields being parsed
  common.command_line.clear();
  for (int i = 0; i < argc; ++i) common.command_line += (i ? " " : "") + std::string(argv[i]);
}

/// Whether a file or folder in an output folder is one a run of these programs writes.
inline bool run_output(const std::filesystem::path& entry) {
  const std::string name = entry.filename().string();
  const std::string ext = entry.extension().string();
  if (std::filesystem::is_directory(entry)) return name.rfind("shift_", 0) == 0;  // the drifting pulse's cases
  return name.rfind("snap_", 0) == 0 || ext == ".csv" || ext == ".h5" || ext == ".xmf" || ext == ".png" ||
         name == "summary.json" || name == "params.cfg" ||
         (name.size() > 8 && name.rfind(".partial") == name.size() - 8);
}

/// The output folder of a run. A run that fails before writing anything but params.cfg (bad input found once
/// the simulation is built) leaves nothing behind: params.cfg goes, and the folder too when this run made it.
class OutputFolder : public std::filesystem::path {
 public:
  OutputFolder(std::filesystem::path dir, bool made, bool resumed, bool scratch = false)
      : std::filesystem::path(std::move(dir)), made_(made), resumed_(resumed), scratch_(scratch) {}
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder() {
    if (scratch_) {
      std::error_code ec;
      std::filesystem::remove_all(*this, ec);
      return;
    }
    if (resumed_ || std::uncaught_exceptions() <= exceptions_) return;
    std::error_code ec;
    std::size_t others = 0;
    for (const auto& e : std::filesystem::directory_iterator(*this, ec)) others += e.path().filename() != "params.cfg";
    if (ec || others > 0) return;
    std::filesystem::remove(*this / "params.cfg", ec);
    if (made_) std::filesystem::remove(*this, ec);
  }

 private:
  bool made_, resumed_, scratch_;
  int exceptions_ = std::uncaught_exceptions();
};

/// Prepares the output folder: refuses one that holds an earlier run's files unless --overwrite, which removes
/// those files first (and nothing else); then writes params.cfg, every resolved parameter, so that
/// `--config DIR/params.cfg` repeats the run.
inline OutputFolder prepare_output(const CommonOptions& common) {
  check_checkpoint_flags(common);
  if (!on_root()) {  // the other ranks' copies of the small files go to a folder of their own, removed after
    const auto scratch = std::filesystem::temp_directory_path() /
                         ("rsph-rank" + std::to_string(this_rank()) + "-" + std::to_string(::getpid()));
    io::ensure_directory(scratch);
    return {scratch, true, false, true};
  }
  if (!common.resume.empty()) return {resume_output(common.resume), false, true};
  const std::filesystem::path dir(common.out);
  const bool made = !std::filesystem::exists(dir);
  if (std::filesystem::is_directory(dir)) {
    std::vector<std::filesystem::path> earlier;
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (run_output(e.path())) earlier.push_back(e.path());
    if (!earlier.empty() && !common.overwrite)
      throw InputError("the output folder '" + dir.string() + "' holds an earlier run (" +
                       earlier.front().filename().string() + " and " + std::to_string(earlier.size() - 1) +
                       " more): choose another --out, or pass --overwrite to replace it");
    for (const auto& e : earlier) std::filesystem::remove_all(e);
  }
  io::ensure_directory(dir);
  std::string cfg = "# " + common.command_line + "\n";
  for (const auto& [name, value] : common.parameters) cfg += name + " = " + value + "\n";
  io::write_text_file(dir / "params.cfg", cfg);
  return {dir, made, false};
}

/// A run that stopped early with a checkpoint written (--max-wall, --stop-at, SIGINT, SIGTERM): exit code 5.
struct Stopped : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// OpenMP threads that wait at a barrier sleep instead of spinning: a thread that spins while its partner waits
/// for a core another process holds makes every parallel region wait a time slice, and a run on two threads
/// then takes 1.7x as long as on one (docs/performance.md). The OpenMP runtime reads OMP_WAIT_POLICY when it
/// loads, before main, so the program starts itself again with it set, unless it was set (by the user, or by
/// this) already.
inline void wait_passively() {
  if (std::getenv("OMP_WAIT_POLICY")) return;
  setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> args;
  for (std::string a; std::getline(in, a, '\0');) args.push_back(a);
  if (args.empty()) return;
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv("/proc/self/exe", argv.data());  // returns only on failure: then run as we are
}

/// Runs body() and turns errors into one message and an exit code: 2 bad input, 3 numerical failure,
/// 4 anything else, 5 stopped early with a checkpoint.
inline int guarded_main(const char* program, const std::function<int()>& body) {
  wait_passively();
  try {
#ifndef RSPH_WITH_MPI  // a program built for one process, started as one of many, would run many times over
    require(!started_as_one_of_many(), std::string(program) +
                                           " was built without MPI and runs in one process: start it without mpiexec "
                                           "(or with -n 1), or build with MPI and Zoltan (scripts/setup-deps.sh)");
#endif
    return body();
  } catch (const po::error& e) {
    fmt::print(stderr, "{}: error: {} (see --help)\n", program, e.what());
    return 2;
  } catch (const InputError& e) {
    fmt::print(stderr, "{}: invalid input: {}\n", program, e.what());
    return 2;
  } catch (const NumericalError& e) {
    fmt::print(stderr, "{}: the run failed: {}\n", program, e.what());
    return 3;
  } catch (const Stopped& e) {  // on many ranks every rank stops at the same step: rank 0 says so
    if (on_root()) fmt::print(stderr, "{}: {}\n", program, e.what());
    return 5;
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}: error: {}\n", program, e.what());
    return 4;
  }
}

/// A program's main: parse(argc, argv) gives the options, or none after --help; run(options) does the work.
/// A program's body under MPI where built with it: rank 0 reports, and an error on any rank ends them all
/// with its exit code (guarded_main); a stop at a checkpoint, which the ranks decide together, ends each alike.
template <class Body>
int program_main(const char* program, int& argc, char**& argv, Body&& body) {
  wait_passively();  // before MPI starts
  MpiSession mpi(argc, argv);
  if (!on_root() && !std::freopen("/dev/null", "w", stdout)) return 4;  // rank 0 reports
  const int code = guarded_main(program, body);
  if (code != 0 && code != 5) mpi.abort_all(code);  // 5: a stop with a checkpoint, which every rank makes
  return code;
}

/// Errors become one message and an exit code (guarded_main).
template <class Parse, class Run>
int run_program(const char* program, int argc, char** argv, Parse&& parse, Run&& run) {
  return program_main(program, argc, argv, [&] {
    const auto options = parse(argc, argv);
    return options ? run(*options) : 0;
  });
}

/// CPU seconds used by this process so far (all threads): robust against other load on the machine.
inline double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace rsph::examples
