// rsph-viscous-ring: the viscously spreading ring (§4, Figs. 6-11) and the effective viscosity nu_eff
// that regularization adds to the prescribed nu_s.
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"
#include "viscous_ring/scene.hpp"

#include <fmt/format.h>

#include <optional>

#include <sstream>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

struct Options {
  scenes::ViscousRingParams s;
  ex::CommonOptions common;
  std::string taus = "0.054,0.090,0.126,0.162,0.198";
  std::string kernel = "cubic";
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [s, common, taus, kernel] = opt;
  ex::po::options_description desc("rsph-viscous-ring options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common, "--nu 4.8e-4 --h 0.04 --bin-width 0.02");
  flag("nu", s.nu, "prescribed kinematic viscosity nu_s");
  flag("h", s.h, "smoothing length (R_0)");
  flag("h-over-dx", s.h_over_dx, "h / Delta");
  flag("kernel", kernel, ex::kernel_names);
  flag("cycle", s.cycle, "regularization cycle c_r in units of --cycle-unit steps (0: never regularize)");
  ex::add_remap_flag(flag, s.remap);
  flag("cycle-unit", s.cycle_unit, "steps per unit of c_r");
  flag("viscosity", s.viscosity,
       "mg: Monaghan-Gingold with alpha from nu_s (the paper); ns: Navier-Stokes stress tensor");
  flag("lattice", s.lattice,
       "regularization lattice: square (the paper's), hexagonal (Delta the nearest-neighbour distance) or rings "
       "(orbit-following: rings of width Delta from the accretion radius, turned with their gas at every remap)");
  flag("taus", taus, "snapshot times tau* (comma separated)");
  flag("sigma-floor", s.sigma_floor, "initial annulus: where Sigma exceeds this fraction of its peak");
  flag("inner-radius", s.inner_radius, "accretion radius (R_0)");
  flag("bin-width", s.bin_width, "radial bin width (R_0)");
  flag("force", s.force, "time-step force factor");
  flag("max-bin", s.max_bin,
       "individual time steps in power-of-two bins down to 2^-max-bin of the longest (0: one global step)");
  ex::po::variables_map vm;
  if (!ex::parse(argc, argv, desc, vm,
                 "rsph-viscous-ring: the viscously spreading ring of §4 and its effective viscosity.\n"
                 "Usage: rsph-viscous-ring [--cycle 4] [--h-over-dx 1.6] [--h 0.02] [--out DIR]"))
    return std::nullopt;
  if (ex::quick_preset(common)) {
    // a tenfold viscosity reaches the same tau* in a tenth of the time; a coarser lattice
    if (vm["nu"].defaulted()) s.nu = 4.8e-4;
    if (vm["h"].defaulted()) s.h = 0.04;
    if (vm["bin-width"].defaulted()) s.bin_width = 0.02;
  }
  s.taus = ex::parse_numbers(taus, "--taus");
  s.validate();
  ex::check_kernel(kernel);
  ex::record_run(common, argc, argv);
  return opt;
}

int run(Options opt) {
  auto& [s, common, taus, kernel] = opt;
  ex::apply_threads(common.threads);
  const auto dir = ex::prepare_output(common);
  const double t_end = s.time_of(s.taus.back());
  io::Progress progress("rsph-viscous-ring c_r=" + std::to_string(s.cycle), t_end);
  ex::ConservationLog<2> conservation(dir / "conservation.csv");
  auto on_step = [&](const auto& sim) {
    if (!common.quiet) progress.update(sim.time(), sim.steps());
    if (sim.steps() % static_cast<std::uint64_t>(s.cycle_unit) == 0)
      conservation.record(sim.time(), sim.steps(), sim.totals());
  };
  auto on_snapshot = [&](const auto& sim, int k) {
    ex::write_snapshot(dir / io::snapshot_name(k + 1), sim, "G M_* = 1, ring radius R_0 = 1", {{"star", {0.0, 0.0}}});
    if (k < 0) conservation.record(sim.time(), sim.steps(), sim.totals());
  };
  ex::Checkpoints checkpoints(common, dir, "rsph-viscous-ring");
  const auto part = checkpoints.add("program", [&](io::Archive& ar) { conservation.checkpoint(ar); });
  const auto r = ex::with_kernel(
      kernel, [&](auto k) { return scenes::run_viscous_ring<decltype(k)>(s, on_step, on_snapshot, &checkpoints); });
  progress.finish();
  conservation.close();

  const auto ring = s.ring();
  io::CsvWriter table(dir / "snapshots.csv",
                      {"tau", "time", "tau_fit", "nu_eff", "nu_eff_over_nu_s", "noise_error", "mass", "particles"});
  std::vector<io::Json> snaps;
  for (std::size_t k = 0; k < r.snapshots.size(); ++k) {
    const auto& sn = r.snapshots[k];
    table.row({sn.tau, sn.time, sn.tau_fit, sn.nu_eff, sn.nu_eff / s.nu, sn.noise, sn.mass,
               static_cast<double>(sn.particles)});
    io::CsvWriter prof(dir / fmt::format("profile_{}.csv", k + 1),
                       {"x", "sigma_mean", "sigma_min", "sigma_max", "sigma_exact", "sigma_fit"});
    for (std::size_t i = 0; i < sn.profile.x.size(); ++i) {
      const double x = sn.profile.x[i];
      prof.row({x, sn.profile.mean[i], sn.profile.min[i], sn.profile.max[i], ring.sigma(sn.tau, x),
                ring.sigma(sn.tau_fit, x)});
    }
    prof.close();
    io::Json j;
    j.set("tau", sn.tau).set("time", sn.time).set("tau_fit", sn.tau_fit).set("nu_eff", sn.nu_eff);
    j.set("noise_error", sn.noise).set("particles", sn.particles);
    snaps.push_back(j);
  }
  table.close();

  io::Json summary;
  summary.set("test", "viscous_ring")
      .set("kernel", kernel)
      .set("viscosity", s.viscosity)
      .set("nu_s", s.nu)
      .set("h", s.h);
  summary.set("h_over_dx", s.h_over_dx).set("cycle", s.cycle).set("cycle_unit", s.cycle_unit);
  summary.set("max_bin", s.max_bin).set("lattice", s.lattice);
  if (s.cycle > 0) summary.set("remap", s.remap);
  summary.set("nu_eff", r.nu_eff).set("nu_eff_over_nu_s", r.nu_eff / s.nu);
  summary.set("nu_eff_min", r.nu_eff_min).set("nu_eff_max", r.nu_eff_max).set("noise_error", r.noise_error);
  summary.set("mass_initial", r.mass_initial).set("mass_final", r.mass_final);
  summary.set("mass_accreted", r.mass_accreted).set("particles_accreted", r.particles_accreted);
  summary.set("mass_error", r.max_mass_error);
  summary.set("particles_initial", r.particles_initial).set("particles_final", r.particles_final);
  summary.set("particles_mean", r.mean_particles);
  ex::write_cost(summary, r);
  summary.set("cpu_seconds", ex::cpu_seconds()).set("snapshots", snaps);
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "viscous_ring");
  fmt::print(
      "rsph-viscous-ring c_r = {} x {}, h/Delta = {}, h = {}: {} particles, {} steps, {} regularizations, {:.1f} s; "
      "nu_eff / nu_s = {:.3f} [{:.3f}, {:.3f}], noise {:.3e}, mass error {:.1e}\n",
      s.cycle, s.cycle_unit, s.h_over_dx, s.h, r.particles_initial, r.steps, r.regularizations, r.wall_seconds,
      r.nu_eff / s.nu, r.nu_eff_min / s.nu, r.nu_eff_max / s.nu, r.noise_error, r.max_mass_error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-viscous-ring", argc, argv, parse_options, run); }
