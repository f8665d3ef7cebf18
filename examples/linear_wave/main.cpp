// rsph-linear-wave: damping and phase error of an isothermal sound wave, RSPH against SPH (§3.1, Fig. 3).
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "linear_wave/scene.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"

#include <fmt/format.h>

using namespace rsph;
namespace ex = rsph::examples;

int main(int argc, char** argv) {
  return ex::program_main("rsph-linear-wave", argc, argv, [&] {
    scenes::LinearWaveParams s;
    ex::CommonOptions common;
    std::string kernel_name = "quintic";
    ex::po::options_description desc("rsph-linear-wave options");
    ex::Flags flag(desc, common);
    ex::add_common_options(flag, common, "--periods 20 --wavelength 12");
    flag("wavelength", s.wavelength_cells, "lambda / Delta (even)");
    flag("r", s.r, "RSPH: regularization period over wave period (0: plain SPH)");
    ex::add_remap_flag(flag, s.remap);
    flag("alpha", s.alpha, "plain SPH (r = 0): artificial viscosity alpha; beta = 2 alpha");
    flag("h-over-dx", s.h_over_dx, "h / Delta");
    flag("periods", s.periods, "wave periods to run (N of eq. 11)");
    flag("amplitude", s.amplitude, "density amplitude delta rho / rho");
    flag("jitter", s.jitter, "random initial displacement in Delta (seeds instabilities)");
    flag("courant", s.courant, "Courant factor");
    flag("kernel", kernel_name, "quintic (the paper's), cubic, wendland-c2, wendland-c4 or wendland-c6");
    ex::po::variables_map vm;
    if (!ex::parse(argc, argv, desc, vm,
                   "rsph-linear-wave: an isothermal sound wave in a periodic 2 x 0.5 wavelength box.\n"
                   "Usage: rsph-linear-wave [--wavelength 24] [--r 4.25 | --r 0 --alpha 0.1] [--out DIR]"))
      return 0;
    if (ex::quick_preset(common)) {
      if (vm["periods"].defaulted()) s.periods = 20;
      if (vm["wavelength"].defaulted()) s.wavelength_cells = 12;
    }
    s.validate();
    ex::check_kernel(kernel_name);
    ex::record_run(common, argc, argv);
    ex::apply_threads(common.threads);
    const auto dir = ex::prepare_output(common);
    io::Progress progress("rsph-linear-wave", s.periods * s.period());
    auto on_step = [&](const auto& sim) {
      if (!common.quiet) progress.update(sim.time(), sim.steps());
    };
    ex::Snapshots snapshots(dir);  // the initial and the final state
    auto at_stop = [&](const auto& sim, int) { snapshots.write(sim); };
    ex::Checkpoints checkpoints(common, dir, "rsph-linear-wave");
    const auto part = checkpoints.add("program", [&](io::Archive& ar) { snapshots.checkpoint(ar); });
    scenes::LinearWaveResult res;
    res = ex::with_kernel(
        kernel_name, [&](auto k) { return scenes::run_linear_wave<decltype(k)>(s, on_step, at_stop, &checkpoints); });
    progress.finish();
    io::CsvWriter csv(dir / "sensor.csv", {"time", "delta_rho"});
    for (std::size_t i = 0; i < res.t.size(); ++i) csv.row({res.t[i], res.delta_rho[i]});
    csv.close();
    io::Json summary;
    summary.set("test", "linear_wave").set("method", s.r > 0 ? "rsph" : "sph").set("kernel", kernel_name);
    if (s.r > 0) summary.set("remap", s.remap);
    summary.set("wavelength_cells", s.wavelength_cells).set("r", s.r).set("alpha", s.alpha).set("beta", 2 * s.alpha);
    summary.set("h_over_dx", s.h_over_dx).set("periods", s.periods).set("jitter", s.jitter);
    summary.set("particles", 2 * s.wavelength_cells * (s.wavelength_cells / 2));
    summary.set("gamma", res.gamma).set("phase_error", res.phase_error).set("amplitude_growth", res.amplitude_growth);
    summary.set("velocity_noise_initial", res.noise_initial).set("velocity_noise_final", res.noise_final);
    summary.set("velocity_noise_growth", res.noise_initial > 0 ? res.noise_final / res.noise_initial : 0.0);
    ex::write_cost(summary, res);
    summary.set("cpu_seconds", ex::cpu_seconds());
    summary.set("kinetic_energy_dissipated", res.dissipated);
    ex::write_run_record(summary, common);
    summary.write(dir / "summary.json");
    ex::draw_figure(common, dir, "linear_wave");
    fmt::print(
        "rsph-linear-wave {} lambda = {} Delta, {}: gamma = {:.3e}, phase error = {:.2e}, amplitude x{:.4f}, "
        "transverse noise {:.1e} -> {:.1e}; {} steps, {:.1f} s\n",
        s.r > 0 ? "RSPH" : "SPH", s.wavelength_cells,
        s.r > 0 ? fmt::format("r = {}", s.r) : fmt::format("alpha = {}", s.alpha), res.gamma, res.phase_error,
        res.amplitude_growth, res.noise_initial, res.noise_final, res.steps, res.wall_seconds);
    return 0;
  });
}
