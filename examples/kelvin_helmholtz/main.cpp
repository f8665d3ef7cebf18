// rsph-kelvin-helmholtz: KH growth at density ratio 10 (§3.3, Fig. 5), RSPH or plain SPH, +- conductivity.
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "kelvin_helmholtz/scene.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"

#include <fmt/format.h>

#include <optional>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

struct Options {
  scenes::KelvinHelmholtzParams s;
  ex::CommonOptions common;
  std::string method = "rsph";
  int dim = 2;
  std::string kernel = "cubic";
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [s, common, method, dim, kernel] = opt;
  ex::po::options_description desc("rsph-kelvin-helmholtz options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common, "--cells 64");
  flag("dim", dim, "2, or 3 for the layer extruded along z (periodic)");
  flag("depth", s.depth, "3D: the box's depth along z in lattice spacings");
  flag("method", method, "rsph or sph");
  flag("conductivity", s.alpha_u, "artificial conductivity alpha_u (0: off)");
  flag("cells", s.cells, "1 / Delta");
  flag("h-over-dx", s.h_over_dx, "h / Delta (SPH: eta)");
  flag("kernel", kernel, ex::kernel_names);
  flag("reg-steps", s.reg_steps, "RSPH: steps between regularizations");
  ex::add_remap_flag(flag, s.remap);
  flag("t-end", s.t_end, "end time (0: tau_KH = 0.58)");
  flag("courant", s.courant, "Courant factor");
  flag("density-ratio", s.chi, "density ratio chi of the upper to the lower gas");
  flag("seed-amplitude", s.A, "A of the seeded v_y (0: an unseeded shear layer)");
  flag("wavelengths", s.wavelengths,
       "box width in wavelengths of the seeded mode (6: the paper's box; 1: one wavelength, periodic)");
  ex::po::variables_map vm;
  if (!ex::parse(argc, argv, desc, vm,
                 "rsph-kelvin-helmholtz: Kelvin-Helmholtz instability at density ratio 10.\n"
                 "Usage: rsph-kelvin-helmholtz --method rsph|sph [--dim 2|3] [--conductivity 1] [--out DIR]"))
    return std::nullopt;
  if (ex::quick_preset(common)) {
    if (vm["cells"].defaulted()) s.cells = 64;
  }
  if (method != "rsph" && method != "sph") throw InputError("unknown method '" + method + "' (rsph, sph)");
  if (dim != 2 && dim != 3) throw InputError("--dim must be 2 or 3 (got " + std::to_string(dim) + ")");
  ex::check_kernel(kernel);
  s.validate();
  ex::record_run(common, argc, argv);
  return opt;
}

template <int D, class Kernel>
int run_dim(Options opt) {
  auto& [s, common, method, dim, kernel] = opt;
  const auto dir = ex::prepare_output(common);
  io::Progress progress("rsph-kelvin-helmholtz " + method, s.end_time());
  auto on_step = [&](const auto& sim) {
    if (!common.quiet) progress.update(sim.time(), sim.steps());
  };
  io::Json scheme;
  auto on_end = [&](const auto& sim) {
    ex::write_snapshot(dir / io::snapshot_name(1), sim, "dimensionless code units");
    ex::write_scheme(scheme, sim);
  };
  {
    // the initial state, for the record
    const auto p0 =
        method == "rsph" ? scenes::kh_lattice<D, Kernel>(s, s.h_over_dx) : scenes::kh_equal_mass<D, Kernel>(s);
    io::write_snapshot(dir / io::snapshot_name(0), p0, 0.0, 0,
                       io::describe_run(s.box<D>(), eos::IdealGas{s.gamma}, "dimensionless code units"));
  }
  ex::Checkpoints checkpoints(common, dir, "rsph-kelvin-helmholtz");
  const auto r = scenes::run_kelvin_helmholtz<D, Kernel>(method == "rsph", s, on_step, on_end, &checkpoints);
  progress.finish();
  io::CsvWriter csv(dir / "amplitude.csv", {"time", "amplitude"});
  for (std::size_t i = 0; i < r.t.size(); ++i) csv.row({r.t[i], r.amplitude[i]});
  csv.close();
  io::CsvWriter layer(dir / "shear_layer.csv", {"time", "momentum_thickness"});
  for (std::size_t i = 0; i < r.t.size(); ++i) layer.row({r.t[i], r.thickness[i]});
  layer.close();
  io::Json summary;
  summary.set("test", "kelvin_helmholtz")
      .set("method", method)
      .set("kernel", kernel)
      .set("alpha_u", s.alpha_u)
      .set("cells", s.cells);
  summary.set("h_over_dx", s.h_over_dx).set("courant", s.courant).set("wavelengths", s.wavelengths);
  summary.set("density_ratio", s.chi).set("seed_amplitude", s.A);
  if (D == 3) summary.set("dim", D).set("depth", s.depth);
  if (method == "rsph") summary.set("reg_steps", s.reg_steps);
  summary.set("particles", r.particles_final).set("tau_KH", s.tau_KH()).set("time", r.t.back());
  summary.set("amplitude_seed", r.seed).set("amplitude_final", r.amplitude_final);
  summary.set("amplification", r.amplitude_final / r.seed).set("growth_rate", r.growth_rate);
  summary.set("growth_rate_incompressible", 2.0 * std::numbers::pi / s.tau_KH());
  summary.set("momentum_thickness_final", r.thickness.back());
  if (r.folds)
    summary.set("overturned_fraction", r.folds->overturned_fraction)
        .set("interface_crossings", r.folds->mean_crossings);
  summary.set("mixed_area_fraction", r.contact.mixed_area).set("pressure_error", r.contact.pressure_error);
  summary.set("energy_error", r.energy_error);
  ex::write_cost(summary, r);
  summary.merge(scheme);
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "kelvin_helmholtz");
  std::string line = fmt::format(
      "rsph-kelvin-helmholtz {} alpha_u = {}: {} particles, {} steps, {:.1f} s; amplitude "
      "{:.4f} -> {:.4f}",
      method, s.alpha_u, r.particles_final, r.steps, r.wall_seconds, r.seed, r.amplitude_final);
  if (r.seed > 0.0) line += fmt::format(" (x{:.1f})", r.amplitude_final / r.seed);
  line +=
      fmt::format(", growth rate {:.2f} (linear theory {:.2f})", r.growth_rate, 2.0 * std::numbers::pi / s.tau_KH());
  if (r.folds)
    line += fmt::format("; interface overturned over {:.0f} % of the width", 100.0 * r.folds->overturned_fraction);
  fmt::print("{}; shear-layer momentum thickness {:.2e}; energy error {:.1e}\n", line, r.thickness.back(),
             r.energy_error);
  return 0;
}

int run(Options opt) {
  ex::apply_threads(opt.common.threads);
  return ex::with_kernel(opt.kernel, [&](auto k) {
    using Kernel = decltype(k);
    return opt.dim == 3 ? run_dim<3, Kernel>(std::move(opt)) : run_dim<2, Kernel>(std::move(opt));
  });
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-kelvin-helmholtz", argc, argv, parse_options, run); }
