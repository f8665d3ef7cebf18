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
  int dim = 1;
  std::string kernel = "cubic";
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [base, common, shifts_text, counts_text, dim, kernel] = opt;
  ex::po::options_description desc("rsph-drifting-pulse options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common, "--counts 0,10,20,30,40; in 3D --cells 16");
  flag("dim", dim, "1; 2 or 3 for a square or a cube drifting along the box's diagonal");
  flag("shifts", shifts_text, "cases: T_reg v_d / Delta, comma separated");
  flag("counts", counts_text, "regularization counts to record");
  flag("cells", base.cells, "lattice sites along each side (default 128 in 1D, 64 in 2D, 32 in 3D)");
  flag("pulse-width", base.pulse_width, "pulse width in spacings");
  flag("contrast", base.contrast, "pulse density over the background");
  flag("h-over-dx", base.h_over_dx, "h / Delta");
  flag("kernel", kernel, ex::kernel_names);
  ex::add_remap_flag(flag, base.remap);
  ex::po::variables_map vm;
  if (!ex::parse(
          argc, argv, desc, vm,
          "rsph-drifting-pulse: a square pulse drifting through a periodic lattice, regularized every T_reg.\n"
          "Usage: rsph-drifting-pulse [--dim 1|2|3] [--shifts 0.01,0.1,0.5,1.0] [--counts 0,100,...] [--out DIR]"))
    return std::nullopt;
  if (dim < 1 || dim > 3) throw InputError("--dim must be 1, 2 or 3 (got " + std::to_string(dim) + ")");
  ex::check_kernel(kernel);
  if (vm["cells"].defaulted()) base.cells = dim == 1 ? 128 : (dim == 2 ? 64 : 32);
  if (ex::quick_preset(common)) {
    if (vm["counts"].defaulted()) counts_text = "0,10,20,30,40";
    if (vm["cells"].defaulted() && dim == 3) base.cells = 16;
  }
  ex::record_run(common, argc, argv);
  return opt;
}

/// One shift's figures, as summary.json reports them.
struct PulseCase {
  std::vector<double> widths;  ///< at each count reached so far (in 2D and 3D the rms over axes)
  std::vector<double> axes;    ///< 2D, 3D: the widths along each axis at each count, one count after another
  double mass_error = 0.0, kinetic = 0.0;
  std::uint64_t regularizations = 0;
};

std::string shift_tag(double shift) { return fmt::format("{:g}", shift); }

/// What every shift's run adds to: the curves, the checkpoint's parts, the cost.
struct PulseRun {
  io::CsvWriter widths;
  std::vector<PulseCase> results;  // one per shift begun
  std::uint64_t steps = 0, updates = 0;
  double reg_seconds = 0.0;
  io::Json ranks;  ///< how the ranks shared the last shift's work (on many ranks)
};

/// One shift: the pulse regularized through every count, its profile, snapshot and widths at each.
template <int D, class Kernel>
void run_case(scenes::DriftingPulseParams s, const std::vector<int>& counts, const std::filesystem::path& dir,
              ex::Checkpoints& checkpoints, PulseRun& run) {
  ex::with_ranks<D>([&](auto... domain) {
    ex::with_remap(s.remap, [&](auto order) {
      auto sim = scenes::make_drifting_pulse<D, Kernel>(s, order, domain...);
      const double m0 = sim.totals().mass;
      const auto case_dir = dir / ("shift_" + shift_tag(s.shift));
      io::ensure_directory(case_dir);
      run.results.emplace_back();
      std::vector<ex::AfterRegularizations> stops;
      for (const int c : counts) stops.push_back({static_cast<std::uint64_t>(c)});
      ex::Snapshots snapshots(case_dir);
      const auto case_part = checkpoints.add("case", [&](io::Archive& ar) { snapshots.checkpoint(ar); });
      const auto cost = ex::run_stops(
          sim, stops, ex::NoHook{},
          [&](const auto& sm, int k) {
            if (k < 0) return;
            const int count = counts[static_cast<std::size_t>(k)];
            decltype(auto) p = ex::particles_on_root(sm);  // the whole profile on rank 0, none on the others
            const auto x = scenes::comoving_positions(p, sm.time(), s.v_drift);
            io::CsvWriter csv(case_dir / fmt::format("profile_{}.csv", count), {"x", "rho", "m"});
            for (std::size_t a = 0; a < p.n_real; ++a) csv.row({x[a] / s.spacing(), p.rho[a], p.m[a]});
            csv.close();
            snapshots.write(sm);
            const auto [axes, w] = scenes::measure_widths(sm, p, s);
            run.results.back().widths.push_back(w);
            std::vector<double> row{s.shift, static_cast<double>(count), w};
            if constexpr (D > 1) {
              auto& all = run.results.back().axes;
              all.insert(all.end(), axes.begin(), axes.end());
              row.insert(row.end(), axes.begin(), axes.end());
            }
            run.widths.row(row);
          },
          &checkpoints);
      auto& result = run.results.back();
      result.mass_error = ex::relative_change(sim.totals().mass, m0);
      result.regularizations = sim.regularizations();
      result.kinetic = sim.kinetic_energy_removed();
      run.steps += cost.steps;
      run.updates += cost.updates;
      run.reg_seconds += cost.phases.regularization;
      run.ranks = cost.ranks;
      fmt::print("shift {:>5}: width after {} regularizations = {:.4f} Delta; mass error {:.1e}\n", shift_tag(s.shift),
                 counts.back(), result.widths.back(), result.mass_error);
    });
  });
}

std::vector<std::string> width_columns(int dim) {
  std::vector<std::string> c{"shift", "regularizations", "width_mass"};
  const char* axis[] = {"width_x", "width_y", "width_z"};
  for (int k = 0; dim > 1 && k < dim; ++k) c.emplace_back(axis[k]);
  return c;
}

template <int D, class Kernel>
int run_dim(Options opt) {
  auto& [base, common, shifts_text, counts_text, dim, kernel] = opt;
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
  summary.set("remap", base.remap).set("kernel", kernel);
  if (D > 1) summary.set("dim", D);
  PulseRun run{io::CsvWriter(dir / "widths.csv", width_columns(D)), {}, 0, 0, 0.0, {}};
  ex::Checkpoints checkpoints(common, dir, "rsph-drifting-pulse");
  const auto part = checkpoints.add("program", [&](io::Archive& ar) {
    run.widths.checkpoint(ar, "widths");
    ar("steps", run.steps);
    ar("updates", run.updates);
    ar("regularization_seconds", run.reg_seconds);
    ar.records("cases", run.results, [](io::Archive& a, PulseCase& c) {
      a("widths", c.widths);
      a("widths_along_axes", c.axes);
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
    run_case<D, Kernel>(s, counts, dir, checkpoints, run);
  }
  for (std::size_t i = 0; i < shifts.size(); ++i) {
    io::Json width_json, c;
    for (std::size_t k = 0; k < counts.size(); ++k) width_json.set(std::to_string(counts[k]), run.results[i].widths[k]);
    c.set("width_mass", width_json).set("mass_error", run.results[i].mass_error);
    if (D > 1) {
      io::Json axes_json;
      const auto& all = run.results[i].axes;
      for (std::size_t k = 0; k < counts.size(); ++k)
        axes_json.set(std::to_string(counts[k]),
                      std::vector<double>(all.begin() + static_cast<std::ptrdiff_t>(D * k),
                                          all.begin() + static_cast<std::ptrdiff_t>(D * k + D)));
      c.set("width_mass_axes", axes_json);
    }
    c.set("regularizations", run.results[i].regularizations);
    c.set("kinetic_energy_dissipated", run.results[i].kinetic);
    cases.set(shift_tag(shifts[i]), c);
  }
  run.widths.close();
  const double wall = ex::seconds_since(wall0);
  summary.set("cases", cases).set("wall_seconds", wall).set("steps", run.steps);
  summary.set("particle_updates_per_second", static_cast<double>(run.updates) / wall);
  summary.set("regularization_seconds", run.reg_seconds);
  summary.merge(run.ranks);
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "drifting_pulse");
  fmt::print("output: {}\n", dir.string());
  return 0;
}

int run(Options opt) {
  ex::apply_threads(opt.common.threads);
  return ex::with_kernel(opt.kernel, [&](auto k) {
    using Kernel = decltype(k);
    if (opt.dim == 3) return run_dim<3, Kernel>(std::move(opt));
    if (opt.dim == 2) return run_dim<2, Kernel>(std::move(opt));
    return run_dim<1, Kernel>(std::move(opt));
  });
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-drifting-pulse", argc, argv, parse_options, run); }
