// rsph-sedov: the Sedov-Taylor blast in 3D (or 2D) against its self-similar solution, RSPH or plain SPH.
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"
#include "sedov/scene.hpp"

#include <fmt/format.h>

#include <optional>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

struct Options {
  scenes::SedovParams s;
  ex::CommonOptions common;
  std::string method = "rsph", kernel = "cubic";
  int dim = 3;
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [s, common, method, kernel, dim] = opt;
  ex::po::options_description desc("rsph-sedov options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common, "--n 16 in 3D, 48 in 2D");
  flag("dim", dim, "3, or 2 for the cylindrical blast");
  flag("method", method, "rsph or sph");
  flag("kernel", kernel, ex::kernel_names);
  ex::add_remap_flag(flag, s.remap);
  flag("n", s.n, "particles along each side of the unit box (0: 32 in 3D, 128 in 2D)");
  flag("energy", s.E, "the blast's energy E (in 2D per unit length)");
  flag("pressure", s.P0, "the ambient pressure");
  flag("gamma", s.gamma, "adiabatic index");
  flag("r-end", s.r_end, "the exact shock radius at the end, in box lengths");
  flag("h-over-dx", s.h_over_dx, "SPH: eta of h = eta (m / rho)^(1/D); RSPH: h / Delta");
  flag("injection", s.injection, "the energy goes to the particles within this many h of the centre");
  flag("alpha", s.alpha, "artificial viscosity alpha");
  flag("beta", s.beta, "artificial viscosity beta");
  flag("courant", s.courant, "Courant factor");
  flag("max-bin", s.max_bin, "individual time steps in power-of-two bins down to 2^-max-bin (0: global)");
  flag("h-min", s.h_min, "RSPH, Appendix A: regularize where the local h / Delta falls below this");
  flag("h-max", s.h_max, "RSPH, Appendix A: ... or rises above this");
  flag("dn-max", s.dN_max, "RSPH, Appendix A: delta N_max");
  flag("max-steps", s.max_steps, "RSPH, Appendix A: most steps between regularizations");
  flag("bins", s.bins,
       "radial bins of the profile inside the exact shock radius R, half as many beyond (0: about one per lattice "
       "spacing)");
  ex::po::variables_map vm;
  if (!ex::parse(argc, argv, desc, vm,
                 "rsph-sedov: energy E = 1 at the centre of a uniform gas (rho = 1, P = 1e-5, gamma = 5/3) in a\n"
                 "periodic unit box, until the shock reaches 0.35 (Sedov-Taylor).\n"
                 "Usage: rsph-sedov [--dim 3|2] [--method rsph|sph] [--remap first|second] [--out DIR]"))
    return std::nullopt;
  if (dim != 2 && dim != 3) throw InputError("--dim must be 2 or 3 (got " + std::to_string(dim) + ")");
  if (ex::quick_preset(common) && vm["n"].defaulted()) s.n = dim == 3 ? 16 : 48;
  if (method != "rsph" && method != "sph") throw InputError("unknown method '" + method + "' (rsph, sph)");
  ex::check_kernel(kernel);
  s.validate();
  ex::record_run(common, argc, argv);
  return opt;
}

void write_profile(const std::filesystem::path& path, const scenes::SedovRun& r) {
  io::CsvWriter csv(path, {"r", "rho", "rho_exact", "v", "v_exact", "P", "P_exact"});
  for (std::size_t b = 0; b < r.r.size(); ++b)
    csv.row({r.r[b], r.rho[b], r.rho_exact[b], r.v[b], r.v_exact[b], r.P[b], r.P_exact[b]});
  csv.close();
}

/// Runs `sim` to the end: conservation.csv every step, a snapshot at the start and the end.
template <int D, class Sim>
scenes::SedovRun run_sim(const Options& opt, const std::filesystem::path& dir, io::Json& scheme, Sim sim) {
  ex::ConservationLog<D> log(dir / "conservation.csv");
  log.record(sim.time(), sim.steps(), sim.totals());
  ex::Snapshots snapshots(dir);
  io::Progress progress(fmt::format("rsph-sedov {} {}D", opt.method, D), scenes::sedov_end_time(opt.s, D));
  ex::Checkpoints checkpoints(opt.common, dir, "rsph-sedov");
  const auto part = checkpoints.add("program", [&](io::Archive& ar) {
    log.checkpoint(ar);
    snapshots.checkpoint(ar);
  });
  if (!checkpoints.resuming()) snapshots.write(sim);
  const auto r = scenes::run_sedov(
      std::move(sim), opt.s,
      [&](const auto& s) {
        log.record(s.time(), s.steps(), s.totals());
        if (!opt.common.quiet) progress.update(s.time(), s.steps());
      },
      [&](const auto& s) {
        snapshots.write(s);
        ex::write_scheme(scheme, s);
      },
      &checkpoints);
  progress.finish();
  log.close();
  return r;
}

/// Either method, on the ranks of mpiexec where built with MPI (ex::with_ranks).
template <int D, class Kernel>
scenes::SedovRun run_method(const Options& opt, const std::filesystem::path& dir, io::Json& scheme) {
  return ex::with_ranks<D>([&](auto... domain) {
    if (opt.method == "sph")
      return run_sim<D>(opt, dir, scheme, scenes::make_sph_sedov<D, Kernel>(opt.s, std::move(domain)...));
    return ex::with_remap(opt.s.remap, [&](auto order) {
      return run_sim<D>(opt, dir, scheme, scenes::make_rsph_sedov<D, Kernel>(opt.s, order, std::move(domain)...));
    });
  });
}

int run(Options opt) {
  auto& [s, common, method, kernel, dim] = opt;
  ex::apply_threads(common.threads);
  const auto dir = ex::prepare_output(common);
  io::Json scheme;
  const scenes::SedovRun r = ex::with_kernel(kernel, [&](auto k) {
    using K = decltype(k);
    return dim == 3 ? run_method<3, K>(opt, dir, scheme) : run_method<2, K>(opt, dir, scheme);
  });
  write_profile(dir / "profile.csv", r);
  io::Json summary;
  summary.set("test", "sedov").set("method", method).set("dim", static_cast<std::uint64_t>(dim));
  summary.set("kernel", kernel).set("n", static_cast<std::uint64_t>(s.side(dim)));
  summary.set("particles", r.particles_final).set("time", r.time).set("gamma", s.gamma).set("energy", s.E);
  summary.set("xi0", r.xi0);
  summary.set("shock_radius", r.radius).set("shock_radius_exact", r.radius_exact);
  summary.set("shock_radius_error", (r.radius - r.radius_exact) / r.radius_exact);
  summary.set("peak_density", r.peak_density).set("peak_density_binned_exact", r.peak_exact);
  summary.set("peak_density_jump", r.jump);
  summary.set("central_pressure_ratio", r.central_pressure);
  summary.set("L1_rho", r.L1_rho).set("energy_error", r.energy_error).set("momentum_imbalance", r.momentum);
  ex::write_cost(summary, r);
  summary.merge(scheme);
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "sedov");
  fmt::print(
      "rsph-sedov {} {}D ({}): {} particles, {} steps, {} regularizations, {:.1f} s\n"
      "  t = {:.4g}: shock at {:.4f} (exact {:.4f}, {:+.1f} %), peak rho {:.3f} (jump {:.3f}), L1(rho) = {:.4g}, "
      "centre's P / exact {:.2f}, energy error {:.2e}\n",
      method, dim, kernel, r.particles_final, r.steps, r.regularizations, r.wall_seconds, r.time, r.radius,
      r.radius_exact, 100.0 * (r.radius - r.radius_exact) / r.radius_exact, r.peak_density, r.jump, r.L1_rho,
      r.central_pressure, r.energy_error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-sedov", argc, argv, parse_options, run); }
