// rsph-drifting-pulse: the numerical diffusion of regularization alone (§2.1, Fig. 2 of the paper).
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "drifting_pulse/scene.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"

#include <fmt/format.h>

#include <optional>

#include <sstream>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

struct Options {
  scenes::DriftingPulseParams base;
  ex::CommonOptions common;
  std::string shifts_text = "0.01,0.1,0.5,1.0";
  std::string counts_text = "0,100,200,300,400";
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [base, common, shifts_text, counts_text] = opt;
  ex::po::options_description desc("rsph-drifting-pulse options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common, "--counts 0,10,20,30,40");
  flag("shifts", shifts_text, "cases: T_reg v_d / Delta, comma separated");
  flag("counts", counts_text, "regularization counts to record");
  flag("cells", base.cells, "lattice sites on the periodic line");
  flag("pulse-width", base.pulse_width, "pulse width in spacings");
  flag("contrast", base.contrast, "pulse density over the background");
  flag("h-over-dx", base.h_over_dx, "h / Delta");
  ex::add_remap_flag(flag, base.remap);
  ex::po::variables_map vm;
  if (!ex::parse(
          argc, argv, desc, vm,
          "rsph-drifting-pulse: a square pulse drifting through a periodic 1D lattice, regularized every T_reg.\n"
          "Usage: rsph-drifting-pulse [--shifts 0.01,0.1,0.5,1.0] [--counts 0,100,...] [--out DIR]"))
    return std::nullopt;
  if (ex::quick_preset(common)) {
    if (vm["counts"].defaulted()) counts_text = "0,10,20,30,40";
  }
  ex::record_run(common, argc, argv);
  return opt;
}

/// One shift's figures, as summary.json reports them.
struct PulseCase {
  std::vector<double> widths;  ///< at each count reached so far
  double mass_error = 0.0, kinetic = 0.0;
  std::uint64_t regularizations = 0;
};

std::string shift_tag(double shift) { return fmt::format("{:g}", shift); }

int run(Options opt) {
  auto& [base, common, shifts_text, counts_text] = opt;
  ex::apply_threads(common.threads);
  const auto shifts = ex::parse_numbers(shifts_text, "--shifts");
  std::vector<int> counts;
  for (double c : ex::parse_numbers(counts_text, "--counts")) {
    require(c >= 0 && c == std::floor(c), "--counts: regularization counts must be whole numbers >= 0");
    counts.push_back(static_cast<int>(c));
  }
  std::sort(counts.begin(), counts.end());
  base.validate();
  const auto dir = ex::prepare_output(common);
  const auto wall0 = std::chrono::steady_clock::now();
  io::Json summary, cases;
  summary.set("test", "drifting_pulse").set("cells", base.cells).set("h_over_dx", base.h_over_dx);
  summary.set("remap", base.remap);
  std::uint64_t steps = 0, updates = 0;
  double reg_seconds = 0.0;
  io::CsvWriter widths(dir / "widths.csv", {"shift", "regularizations", "width_mass"});
  std::vector<PulseCase> results;  // one per shift begun
  ex::Checkpoints checkpoints(common, dir, "rsph-drifting-pulse");
  const auto part = checkpoints.add("program", [&](io::Archive& ar) {
    widths.checkpoint(ar, "widths");
    ar("steps", steps);
    ar("updates", updates);
    ar("regularization_seconds", reg_seconds);
    ar.records("cases", results, [](io::Archive& a, PulseCase& c) {
      a("widths", c.widths);
      a("mass_error", c.mass_error);
      a("kinetic_energy_dissipated", c.kinetic);
      a("regularizations", c.regularizations);
    });
  });
  std::size_t resumed_case = 0;  // on --resume, the shift the run had got to
  checkpoints.read_ahead("program/cases/count", resumed_case);
  for (std::size_t i = resumed_case > 0 ? resumed_case - 1 : 0; i < shifts.size(); ++i) {
    auto s = base;
    s.shift = shifts[i];
    ex::with_remap(s.remap, [&](auto order) {
      auto sim = scenes::make_drifting_pulse(s, order);
      const double m0 = sim.totals().mass;
      const auto case_dir = dir / ("shift_" + shift_tag(shifts[i]));
      io::ensure_directory(case_dir);
      results.emplace_back();
      std::vector<ex::AfterRegularizations> stops;
      for (const int c : counts) stops.push_back({static_cast<std::uint64_t>(c)});
      ex::Snapshots snapshots(case_dir);
      const auto case_part = checkpoints.add("case", [&](io::Archive& ar) { snapshots.checkpoint(ar); });
      const auto cost = ex::run_stops(
          sim, stops, ex::NoHook{},
          [&](const auto& sm, int k) {
            if (k < 0) return;
            const int count = counts[static_cast<std::size_t>(k)];
            const auto x = scenes::comoving_positions(sm, s.v_drift);
            const auto& p = sm.particles();
            io::CsvWriter csv(case_dir / fmt::format("profile_{}.csv", count), {"x", "rho", "m"});
            for (std::size_t a = 0; a < p.n_real; ++a) csv.row({x[a] / s.spacing(), p.rho[a], p.m[a]});
            csv.close();
            snapshots.write(sm);
            const double w = scenes::pulse_width_mass(sm, s);
            results.back().widths.push_back(w);
            widths.row({shifts[i], static_cast<double>(count), w});
          },
          &checkpoints);
      auto& result = results.back();
      result.mass_error = ex::relative_change(sim.totals().mass, m0);
      result.regularizations = sim.regularizations();
      result.kinetic = sim.kinetic_energy_removed();
      steps += cost.steps;
      updates += cost.updates;
      reg_seconds += cost.phases.regularization;
      fmt::print("shift {:>5}: width after {} regularizations = {:.4f} Delta; mass error {:.1e}\n",
                 shift_tag(shifts[i]), counts.back(), scenes::pulse_width_mass(sim, s), result.mass_error);
    });
  }
  for (std::size_t i = 0; i < shifts.size(); ++i) {
    io::Json width_json, c;
    for (std::size_t k = 0; k < counts.size(); ++k) width_json.set(std::to_string(counts[k]), results[i].widths[k]);
    c.set("width_mass", width_json).set("mass_error", results[i].mass_error);
    c.set("regularizations", results[i].regularizations);
    c.set("kinetic_energy_dissipated", results[i].kinetic);
    cases.set(shift_tag(shifts[i]), c);
  }
  widths.close();
  const double wall = ex::seconds_since(wall0);
  summary.set("cases", cases).set("wall_seconds", wall).set("steps", steps);
  summary.set("particle_updates_per_second", static_cast<double>(updates) / wall);
  summary.set("regularization_seconds", reg_seconds);
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "drifting_pulse");
  fmt::print("output: {}\n", dir.string());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-drifting-pulse", argc, argv, parse_options, run); }
