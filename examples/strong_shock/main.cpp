// rsph-strong-shock: the Xiao (2004) tube with pressure ratio 1e10 (§3.2, Fig. 4), RSPH or plain SPH.
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"
#include "strong_shock/scene.hpp"

#include <fmt/format.h>

#include <optional>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

struct Options {
  scenes::StrongShockParams s;
  ex::CommonOptions common;
  std::string method = "rsph";
  std::string kernel = "cubic";
};

/// The options from the command line, or none when --help was asked for.
std::optional<Options> parse_options(int argc, char** argv) {
  Options opt;
  auto& [s, common, method, kernel] = opt;
  ex::po::options_description desc("rsph-strong-shock options");
  ex::Flags flag(desc, common);
  ex::add_common_options(flag, common,
                         "RSPH --nx 256 --ny 6, rounded up to whole blocks on --levels; SPH 400 x 16 | 50 x 2");
  flag("method", method, "rsph or sph");
  flag("alpha", s.alpha, "artificial viscosity alpha");
  flag("beta", s.beta, "artificial viscosity beta");
  flag("nx", s.nx, "RSPH: lattice cells along x");
  flag("ny", s.ny, "RSPH: lattice rows across the strip");
  flag("h-over-dx", s.h_over_dx, "RSPH: h / Delta");
  flag("max-steps", s.max_steps, "RSPH: most steps between regularizations");
  ex::add_remap_flag(flag, s.remap);
  flag("sph-left", s.sph_nx_left, "SPH: particles along x, left half");
  flag("sph-left-rows", s.sph_ny_left, "SPH: rows, left half");
  flag("sph-right", s.sph_nx_right, "SPH: particles along x, right half");
  flag("sph-right-rows", s.sph_ny_right, "SPH: rows, right half");
  flag("eta", s.eta, "SPH: h = eta (m / rho)^(1/2)");
  flag("kernel", kernel, ex::kernel_names);
  flag("t-end", s.t_end, "end time");
  flag("courant", s.courant, "Courant factor");
  ex::add_level_options(flag, s.refinement, "RSPH",
                        "finest level of a lattice in factors of two (0: uniform); nx, ny count finest cells");
  ex::po::variables_map vm;
  if (!ex::parse(argc, argv, desc, vm,
                 "rsph-strong-shock: (rho, v, P) = (1, 0, 1e10) | (0.125, 0, 0.1), gamma = 1.4, t = 2.5e-6.\n"
                 "Usage: rsph-strong-shock --method rsph|sph [--alpha 2 --beta 4] [--out DIR]"))
    return std::nullopt;
  if (ex::quick_preset(common)) {
    // on levels, the quick lattice is rounded up to whole blocks of finest cells
    const auto blocks = [&](int n) {
      const auto fine = static_cast<int>(s.refinement.fine_cells_per_block());
      return s.refinement.levels > 0 ? (n + fine - 1) / fine * fine : n;
    };
    if (vm["nx"].defaulted()) s.nx = blocks(256);
    if (vm["ny"].defaulted()) s.ny = blocks(6);
    if (vm["sph-left"].defaulted()) s.sph_nx_left = 400;
    if (vm["sph-left-rows"].defaulted()) s.sph_ny_left = 16;
    if (vm["sph-right"].defaulted()) s.sph_nx_right = 50;
    if (vm["sph-right-rows"].defaulted()) s.sph_ny_right = 2;
  }
  if (method != "rsph" && method != "sph") throw InputError("unknown method '" + method + "' (rsph, sph)");
  ex::check_kernel(kernel);
  s.validate();
  ex::record_run(common, argc, argv);
  return opt;
}

int run(Options opt) {
  auto& [s, common, method, kernel] = opt;
  ex::apply_threads(common.threads);
  const auto dir = ex::prepare_output(common);
  io::Progress progress("rsph-strong-shock " + method, s.t_end);
  auto on_step = [&](const auto& sim) {
    if (!common.quiet) progress.update(sim.time(), sim.steps());
  };
  io::Json scheme;
  auto on_end = [&](const auto& sim) {
    ex::write_snapshot(dir / io::snapshot_name(0), sim, "dimensionless code units");
    ex::write_scheme(scheme, sim);
  };
  ex::Checkpoints checkpoints(common, dir, "rsph-strong-shock");
  const auto r = ex::with_kernel(kernel, [&](auto k) {
    using Kernel = decltype(k);
    // every method on the ranks of mpiexec where built with MPI (ex::with_ranks)
    return ex::with_ranks<2>([&](auto... domain) {
      if (method == "rsph" && s.refinement.levels > 0)
        return ex::with_remap(s.remap, [&](auto order) {
          return scenes::run_shock(scenes::make_rsph_levels_shock<Kernel>(s, order, domain...), s, on_step, on_end,
                                   &checkpoints);
        });
      if (method == "rsph")
        return ex::with_remap(s.remap, [&](auto order) {
          return scenes::run_shock(scenes::make_rsph_shock<Kernel>(s, order, domain...), s, on_step, on_end,
                                   &checkpoints);
        });
      // sph (parse_options refused the rest)
      return scenes::run_shock(scenes::make_sph_shock<Kernel>(s, domain...), s, on_step, on_end, &checkpoints);
    });
  });
  progress.finish();

  io::CsvWriter parts(dir / "particles.csv", {"x", "y", "rho", "v", "P", "u"});
  for (std::size_t a = 0; a < r.x.size(); ++a) parts.row({r.x[a], r.y[a], r.rho[a], r.v[a], r.P[a], r.u[a]});
  parts.close();
  const analysis::ExactRiemann exact(s.left, s.right, s.gamma);
  io::CsvWriter ex_csv(dir / "exact.csv", {"x", "rho", "v", "P"});
  for (int i = 0; i <= 4000; ++i) {
    const double x = i / 4000.0;
    const auto q = exact.sample((x - 0.5) / s.t_end);
    ex_csv.row({x, q.rho, q.v, q.P});
  }
  ex_csv.close();
  io::Json summary;
  summary.set("test", "strong_shock").set("method", method).set("kernel", kernel);
  summary.set("alpha", s.alpha).set("beta", s.beta);
  summary.set("particles", r.particles_final);
  summary.set("L1_rho", r.errors.L1_rho).set("L1_v", r.errors.L1_v).set("L1_P", r.errors.L1_P);
  summary.set("shock_position", r.shock_position).set("shock_position_exact", r.shock_position_exact);
  summary.set("contact_position_exact", r.contact_exact).set("penetration_fraction", r.penetration);
  summary.set("energy_error", r.energy_error);
  ex::write_cost(summary, r);
  summary.merge(scheme);
  if (method == "rsph") summary.set("max_level", static_cast<std::uint64_t>(s.refinement.levels));
  ex::write_run_record(summary, common);
  summary.write(dir / "summary.json");
  ex::draw_figure(common, dir, "strong_shock");
  fmt::print(
      "rsph-strong-shock {} (alpha {}, beta {}): {} particles, {} steps, {} regularizations, {:.1f} s\n"
      "  L1(rho) = {:.4g}, L1(v) = {:.4g}; shock at {:.4f} (exact {:.4f}); penetration {:.3f}; energy error {:.2e}\n",
      method, s.alpha, s.beta, r.particles_final, r.steps, r.regularizations, r.wall_seconds, r.errors.L1_rho,
      r.errors.L1_v, r.shock_position, r.shock_position_exact, r.penetration, r.energy_error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return ex::run_program("rsph-strong-shock", argc, argv, parse_options, run); }
