// rsph-planet-disk: a planet in a protoplanetary disk (§5, Figs. 12-18): log Sigma maps, the cuts at
// phi = pi and r = a, the azimuthal average, the gap depth over time and the cost of each phase.
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "planet_disk/scene.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"

#include <fmt/format.h>

#include <optional>

#include <cmath>
#include <numbers>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

/// The wake measured on the final map: its crest traced across each ring 0.6 <= r <= 1.6 outside |r - 1| < 0.1
/// (searched within 0.3 rad, paper::wake_crossings), and its rms offset from linear theory.
struct WakeFit {
  std::size_t crossings = 0;
  double rms_offset = 0.0;
};

/// The final state as the paper's figures show it, written as CSV; the wake's offset from linear theory.
/// `sigma_at` gives Sigma at a list of points (the SPH sum over the whole gas).
template <class SigmaAt>
WakeFit write_maps(const std::filesystem::path& dir, SigmaAt&& sigma_at, const scenes::PlanetDiskParams& s, double time,
                   std::size_t n_r, std::size_t n_phi) {
  const double phi_p = s.star_planet().planet_phase(time);
  const paper::PolarGrid grid{s.r_in, s.r_out, phi_p, n_r, n_phi};
  const auto sigma = sigma_at(grid.points());
  io::CsvWriter map(dir / "map.csv", {"r", "phi", "sigma_over_sigma0"});
  for (std::size_t i = 0; i < n_r; ++i)
    for (std::size_t j = 0; j < n_phi; ++j) map.row({grid.r(i), grid.phi(j), sigma[i * n_phi + j] / s.sigma0});
  map.close();

  // Fig. 13: opposite the planet; Fig. 14: along the orbit.
  const std::size_t n_cut = 4 * n_r;
  std::vector<Vec<2>> radial, azimuthal;
  for (std::size_t i = 0; i < n_cut; ++i) {
    const double r = s.r_in + (static_cast<double>(i) + 0.5) * (s.r_out - s.r_in) / double(n_cut);
    radial.emplace_back(r * std::cos(phi_p + std::numbers::pi), r * std::sin(phi_p + std::numbers::pi));
  }
  for (std::size_t j = 0; j < 2 * n_phi; ++j) {
    const double phi = phi_p - std::numbers::pi + (static_cast<double>(j) + 0.5) * std::numbers::pi / double(n_phi);
    azimuthal.emplace_back(std::cos(phi), std::sin(phi));
  }
  const auto along_r = sigma_at(radial);
  const auto along_phi = sigma_at(azimuthal);
  io::CsvWriter cut_r(dir / "cut_phi_pi.csv", {"r", "sigma_over_sigma0"});
  for (std::size_t i = 0; i < n_cut; ++i) cut_r.row({radial[i].norm(), along_r[i] / s.sigma0});
  cut_r.close();
  io::CsvWriter cut_phi(dir / "cut_r_a.csv", {"phi", "sigma_over_sigma0"});
  for (std::size_t j = 0; j < 2 * n_phi; ++j)
    cut_phi.row({-std::numbers::pi + (static_cast<double>(j) + 0.5) * std::numbers::pi / double(n_phi),
                 along_phi[j] / s.sigma0});
  cut_phi.close();

  // Fig. 15: the azimuthal average; the wake of linear theory for the map.
  const auto profile = scenes::disk_profile_from(sigma_at, s);
  io::CsvWriter prof(dir / "profile.csv", {"r", "sigma_over_sigma0"});
  for (std::size_t k = 0; k < profile.r.size(); ++k) prof.row({profile.r[k], profile.sigma[k]});
  prof.close();
  io::CsvWriter wake(dir / "wake.csv", {"r", "phi"});
  for (std::size_t i = 0; i < n_cut; ++i) {
    const double r = radial[i].norm();
    const double phi = paper::wake_azimuth(r, 1.0, s.aspect);
    wake.row({r, std::remainder(phi, 2.0 * std::numbers::pi)});  // wrapped into [-pi, pi]
  }
  wake.close();
  const auto crossings = paper::wake_crossings(grid, sigma, 1.0, s.aspect, 0.6, 1.6, 0.1, 0.3);
  io::CsvWriter crossed(dir / "wake_crossings.csv", {"r", "phi_theory", "phi_measured", "offset"});
  for (const auto& c : crossings) crossed.row({c.r, c.phi_theory, c.phi_measured, c.offset()});
  crossed.close();
  return {crossings.size(), paper::rms_offset(crossings)};
}

struct Options {
  scenes::PlanetDiskParams s;
  ex::CommonOptions common;
  std::string resolution = "low";
  double snapshot_every = 10.0;
  std::size_t map_nr = 210;
  std::size_t map_nphi = 256;
  std::string kernel = "cubic";
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [s, common, resolution, snapshot_every, map_nr, map_nphi, kernel] = opt;
  ex::po::options_description desc("rsph-planet-disk options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common,
                         "--particles 8000 --orbits 10 --snapshot-every 5; in 3D --particles 20000 --orbits 2 "
                         "--snapshot-every 1",
                         "orbits");
  flag("dim", s.dim,
       "2: the paper's disk; 3: a vertically isothermal disk of the same Sigma (H = 0.05 r), RSPH on the cubic "
       "lattice inside |z| <= surface H");
  flag("surface", s.surface, "3D: the disk's surface, and the lattice's reach, in scale heights");
  flag("method", s.method, "rsph: regularized SPH without artificial viscosity; sph: grad-h SPH with viscosity");
  ex::add_remap_flag(flag, s.remap);
  flag("eos", s.eos, "isothermal (c_s / v_K fixed) or polytropic (eq. 21)");
  flag("q", s.q, "M_p / (M_* + M_p): 1e-3 Jupiter, 1e-4 Neptune");
  flag("resolution", resolution,
       "low (48 000 particles), med (108 000) or high (191 000); in 3D 200 000, 450 000, 800 000");
  flag("h-over-dx", s.h_over_dx, "RSPH: h / Delta; SPH: eta (3D: 1.2 unless given)");
  flag("kernel", kernel, ex::kernel_names);
  flag("lattice", s.lattice,
       "square, hexagonal or rings (orbit-following: rings of width Delta turned with their gas at every "
       "remap): the start and RSPH's regularization lattice (the same particle count)");
  flag("orbits", s.orbits, "planet orbits to run");
  flag("zone-width", s.zone_width, "width of the boundary zones on fixed orbits at both edges");
  flag("keep-zone-members", s.keep_zone_members,
       "the zones keep the members chosen at the start through every remap, instead of deciding membership by "
       "radius after each (the paper's)");
  flag("damping-width", s.damping_width,
       "width of wave-damping zones just inside the fixed ones, where the velocity relaxes toward the circular "
       "orbit (de Val-Borro et al. 2006; 0: none, the paper's set-up)");
  flag("damping-tau", s.damping_tau, "the damping zones' time scale, in orbital periods at their edges");
  flag("courant", s.courant, "time-step Courant factor");
  flag("force", s.force, "time-step force factor");
  flag("max-bin", s.max_bin,
       "RSPH: individual time steps in power-of-two bins, the shortest 2^-max-bin of the longest (0: one "
       "global step; SPH always steps globally)");
  flag("alpha", s.alpha, "SPH artificial viscosity alpha");
  flag("beta", s.beta, "SPH artificial viscosity beta");
  flag("rsph-alpha", s.rsph_alpha,
       "2D RSPH: artificial viscosity alpha, scaled by Balsara's switch (0: none, the paper's RSPH)");
  flag("rsph-beta", s.rsph_beta, "2D RSPH: the switched viscosity's beta (with --rsph-alpha 1, 2 as SPH's)");
  flag("n-min", s.N_min, "Appendix A: N_min");
  flag("n-max", s.N_max, "Appendix A: N_max");
  flag("dn-max", s.dN_max, "Appendix A: delta N_max");
  flag("max-steps", s.max_steps, "Appendix A: most steps between regularizations");
  flag("measure-every", s.measure_every, "orbits between measurements (mass, gap depth)");
  flag("snapshot-every", snapshot_every, "orbits between snapshots");
  flag("map-nr", map_nr, "radial cells of the Sigma map");
  flag("map-nphi", map_nphi, "azimuthal cells of the Sigma map");
  // no default (--resolution and the preset decide), but the resolved count goes to params.cfg like every flag's,
  // so that --config and --resume take it
  desc.add_options()("particles", ex::po::value(&s.particles), "particle count over the disk (overrides --resolution)");
  common.bound.emplace_back("particles", [&s] { return ex::default_text(s.particles); });
  ex::po::variables_map vm;
  if (!ex::parse(argc, argv, desc, vm,
                 "rsph-planet-disk: planet-disk interaction of §5 (de Val-Borro et al. 2006 set-up).\n"
                 "Usage: rsph-planet-disk [--method rsph] [--eos isothermal] [--q 1e-3] [--resolution low] "
                 "[--out DIR]"))
    return std::nullopt;
  if (s.dim == 3 && vm["h-over-dx"].defaulted()) s.h_over_dx = scenes::PlanetDiskParams::h_over_dx_3d;
  if (!vm.count("particles")) {
    const bool flat = s.dim == 2;
    if (resolution == "low")
      s.particles = flat ? 48000 : 200000;
    else if (resolution == "med")
      s.particles = flat ? 108000 : 450000;
    else if (resolution == "high")
      s.particles = flat ? 191000 : 800000;
    else
      throw InputError("unknown resolution '" + resolution + "' (low, med, high)");
  }
  if (ex::quick_preset(common)) {
    if (!vm.count("particles")) s.particles = s.dim == 3 ? 20000 : 8000;
    if (vm["orbits"].defaulted()) s.orbits = s.dim == 3 ? 2.0 : 10.0;
    if (vm["snapshot-every"].defaulted()) snapshot_every = s.dim == 3 ? 1.0 : 5.0;
  }
  s.validate();
  ex::check_kernel(kernel);
  require(snapshot_every > 0.0, "--snapshot-every must be positive");
  require(map_nr >= 2 && map_nphi >= 4, "the Sigma map needs at least 2 x 4 cells");
  ex::record_run(common, argc, argv);
  return opt;
}

/// What a run measured at its end, beside the scene's DiskRun.
struct FinalFigures {
  WakeFit wake;
  double thickness_initial = 0.0, thickness_final = 0.0;  ///< 3D only
};

/// summary.json's figures (the run record aside).
io::Json disk_summary(const Options& opt, const scenes::DiskRun& r, const FinalFigures& f) {
  const auto& s = opt.s;
  io::Json phases = ex::phase_json(r.phases);
  phases.set("measurement_and_output", r.output_seconds);
  std::vector<io::Json> mass_over_time;
  for (const auto& d : r.samples) {
    io::Json j;
    j.set("orbit", d.orbit).set("mass", d.mass).set("mass_removed", d.mass_removed).set("gap_depth", d.gap_depth);
    mass_over_time.push_back(j);
  }
  io::Json summary;
  summary.set("test", "planet_disk")
      .set("dim", s.dim)
      .set("kernel", opt.kernel)
      .set("method", s.method)
      .set("eos", s.eos)
      .set("q", s.q);
  if (s.rsph()) summary.set("remap", s.remap);
  if (s.rsph() && s.dim == 2)  // Appendix A's schedule
    summary.set("N_min", s.N_min).set("N_max", s.N_max).set("dN_max", s.dN_max).set("max_steps", s.max_steps);
  summary.set("max_bin", s.rsph() ? s.max_bin : 0);
  summary.set("h_over_dx", s.h_over_dx).set("spacing", s.spacing()).set("h", s.h()).set("orbits", s.orbits);
  summary.set("lattice", s.dim == 3 ? (s.rsph() ? "cubic" : "columns") : s.lattice);
  summary.set("damping_width", s.damping_width);
  if (s.damping_width > 0.0) summary.set("damping_tau", s.damping_tau);
  if (s.dim == 2 && s.rsph()) summary.set("rsph_alpha", s.rsph_alpha).set("rsph_beta", s.rsph_beta);
  if (s.dim == 3) summary.set("surface_in_H", s.surface);
  summary.set("particles_initial", r.particles_initial).set("particles_final", r.particles_final);
  summary.set("particles_mean", r.mean_particles).set("particles_removed", r.particles_removed);
  summary.set("mass_initial", r.mass_initial).set("mass_final", r.mass_final).set("mass_removed", r.mass_removed);
  summary.set("mass_error", r.max_mass_error).set("gap_depth", r.samples.back().gap_depth);
  summary.set("wake_rms_offset", f.wake.rms_offset).set("wake_crossings", static_cast<std::uint64_t>(f.wake.crossings));
  summary.set("wall_seconds_per_orbit", r.wall_seconds / s.orbits);
  if (s.dim == 3) summary.set("thickness_initial", f.thickness_initial).set("thickness_final", f.thickness_final);
  ex::write_cost(summary, r);
  summary.set("cpu_seconds", ex::cpu_seconds()).set("remap_seconds", r.remap_seconds);
  summary.set("phase_seconds", phases).set("timeline", mass_over_time);
  return summary;
}

int run(Options opt) {
  auto& [s, common, resolution, snapshot_every, map_nr, map_nphi, kernel] = opt;
  ex::apply_threads(common.threads);
  const auto dir = ex::prepare_output(common);
  const double period = s.period();
  io::Progress progress(fmt::format("rsph-planet-disk {}D {} {}", s.dim, s.method, s.eos), s.orbits * period);
  io::CsvWriter timeline(dir / "timeline.csv", {"orbit", "time", "mass", "mass_removed", "gap_depth", "particles",
                                                "steps", "regularizations", "wall_seconds"});
  std::size_t snapshots = 0;
  double next_snapshot = 0.0;
  WakeFit wake;
  double thickness_initial = 0.0, thickness_final = 0.0;
  auto on_step = [&](const auto& sim) {
    if (!common.quiet) progress.update(sim.time(), sim.steps());
  };
  auto on_sample = [&](const auto& sim, const scenes::DiskSample& d) {
    timeline.row({d.orbit, d.time, d.mass, d.mass_removed, d.gap_depth, static_cast<double>(d.particles),
                  static_cast<double>(d.steps), static_cast<double>(d.regularizations), d.wall_seconds});
    const bool last = d.orbit >= s.orbits * (1.0 - 1e-12);
    if constexpr (std::decay_t<decltype(sim)>::dim == 3) {
      // between the zones: the disk whose gas moves freely
      const double thickness =
          scenes::thickness_ratio(sim.particles(), s.vertical(), s.zones().inner, s.zones().outer,
                                  [&](std::vector<double>& sums) { ex::sum_over_ranks(sim, sums); });
      if (d.steps == 0) thickness_initial = thickness;
      thickness_final = thickness;
    }
    if (d.orbit >= next_snapshot * (1.0 - 1e-12) || last) {
      const Vec<2> star = s.star_planet().star_position(sim.time()),
                   planet = s.star_planet().planet_position(sim.time());
      ex::write_snapshot(dir / io::snapshot_name(snapshots++), sim,
                         "G = 1, M_* = 1, planet orbit radius a = 1 (an orbit takes 2 pi / sqrt(1 + M_p))",
                         {{"star", {star.x(), star.y()}}, {"planet", {planet.x(), planet.y()}}});
      next_snapshot += snapshot_every;
    }
    if (last) {  // every rank's own particles, their sums added over the ranks
      const auto& own = scenes::seen_from_above(sim.particles());
      wake = write_maps(dir, ex::density_over_ranks<kernel::CubicSpline>(sim, own), s, sim.time(), map_nr, map_nphi);
    }
  };
  ex::Checkpoints checkpoints(common, dir, "rsph-planet-disk", period);
  const auto part = checkpoints.add("program", [&](io::Archive& ar) {
    timeline.checkpoint(ar, "timeline");
    ar("snapshots", snapshots);
    ar("next_snapshot", next_snapshot);
    ar("thickness_initial", thickness_initial);
  });
  const auto r = ex::with_kernel(
      kernel, [&](auto k) { return scenes::run_planet_disk<decltype(k)>(s, on_step, on_sample, &checkpoints); });
  progress.finish();
  timeline.close();

  auto summary = disk_summary(opt, r, {wake, thickness_initial, thickness_final});
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "planet_disk");
  fmt::print(
      "rsph-planet-disk {}D {} {} q = {}: {} particles, {} steps, {} regularizations, {:.1f} s ({:.2f} M updates/s); "
      "gap depth {:.3f}, mass removed {:.2e} of {:.3e}, mass error {:.1e}\n",
      s.dim, s.method, s.eos, s.q, r.particles_initial, r.steps, r.regularizations, r.wall_seconds,
      static_cast<double>(r.updates) / r.wall_seconds * 1e-6, r.samples.back().gap_depth, r.mass_removed,
      r.mass_initial, r.max_mass_error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-planet-disk", argc, argv, parse_options, run); }
