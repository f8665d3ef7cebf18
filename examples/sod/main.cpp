// rsph-sod: Sod's shock tube in 1D or as a 2D strip, plain SPH or RSPH (uniform or multi-level lattice),
// against the exact Riemann solution.
#include "common/cli.hpp"
#include "common/runner.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/io/progress.hpp"
#include "sod/scene.hpp"

#include <fmt/format.h>

#include <array>

using namespace rsph;
namespace ex = rsph::examples;

namespace {

struct Options {
  scenes::SodParams sod;
  scenes::RsphSodParams rsph;
  std::string method = "sph";
  int dim = 1;
  std::string kernel = "cubic";
  int snapshots = 5;
  bool consistent_gradient = false;
  physics::ConsistentGradient gradient;
  ex::CommonOptions common;
};

template <int D, class Kernel, class Sim>
int run(const Options& opt, Sim sim) {
  const auto dir = ex::prepare_output(opt.common);
  const analysis::ExactRiemann exact(opt.sod.left, opt.sod.right, opt.sod.gamma);
  const auto start = sim.totals();
  ex::ConservationLog<D> log(dir / "conservation.csv");
  log.record(sim.time(), sim.steps(), start);
  ex::Snapshots snapshots(dir);
  io::Progress progress(fmt::format("rsph-sod {}D {}", D, opt.method), opt.sod.t_end);
  ex::Checkpoints checkpoints(opt.common, dir, "rsph-sod");
  const auto part = checkpoints.add("program", [&](io::Archive& ar) {
    log.checkpoint(ar);
    snapshots.checkpoint(ar);
  });
  const auto cost = ex::run_stops(
      sim, ex::evenly(opt.sod.t_end, opt.snapshots),
      [&](const auto& s) {
        log.record(s.time(), s.steps(), s.totals());
        if (!opt.common.quiet) progress.update(s.time(), s.steps());
      },
      [&](const auto& s, int) { snapshots.write(s); }, &checkpoints);
  progress.finish();
  log.close();

  decltype(auto) p = ex::particles_on_root(sim);  // the whole tube, on rank 0 (none on the others)
  io::CsvWriter parts(dir / "particles.csv", {"x", "y", "rho", "v", "P", "u"});
  for (std::size_t a = 0; a < p.n_real; ++a)
    parts.row({p.x[a][0], D > 1 ? p.x[a][D - 1] : 0.0, p.rho[a], p.v[a][0], p.P[a], p.u[a]});
  parts.close();
  io::CsvWriter ex_csv(dir / "exact.csv", {"x", "rho", "v", "P"});
  for (int i = 0; i <= 2000; ++i) {
    const double x = i / 2000.0;
    const auto q = exact.sample((x - 0.5) / sim.time());
    ex_csv.row({x, q.rho, q.v, q.P});
  }
  ex_csv.close();

  const auto e = ex::measured_on_root(sim, p, [&](const auto& all) {
    const auto tube = analysis::shock_tube_errors(all, exact, sim.time(), 0.5);
    return std::array{tube.L1_rho, tube.L1_v, tube.L1_P};
  });
  const analysis::ShockTubeErrors err{e[0], e[1], e[2]};
  const std::uint64_t particles = ex::count_over_ranks(sim, sim.particles().n_real);
  const auto end = sim.totals();
  io::Json summary;
  summary.set("test", "sod")
      .set("method", opt.method)
      .set("dim", D)
      .set("kernel", opt.kernel)
      .set("particles", particles);
  summary.set("time", sim.time()).set("L1_rho", err.L1_rho).set("L1_v", err.L1_v).set("L1_P", err.L1_P);
  summary.set("energy_error", ex::relative_change(end.total_energy(), start.total_energy()));
  summary.set("mass_error", ex::relative_change(end.mass, start.mass));
  summary.set("p_star_exact", exact.p_star()).set("v_star_exact", exact.v_star());
  ex::write_cost(summary, cost);
  ex::write_scheme(summary, sim);
  if constexpr (D < 3 && requires { sim.regularizer().log(); })
    summary.set("max_level", opt.rsph.refinement.levels).set("cycle", static_cast<std::uint64_t>(opt.rsph.cycle));
  ex::write_run_record(summary, opt.common);
  summary.write(dir / "summary.json");
  ex::draw_figure(opt.common, dir, "sod");
  fmt::print(
      "rsph-sod {}D: {} particles, {} steps, {:.2f} s; L1(rho) = {:.4g}, L1(v) = {:.4g}, L1(P) = {:.4g}; "
      "energy error {:.2e}\n  output: {}\n",
      D, particles, sim.steps(), cost.wall_seconds, err.L1_rho, err.L1_v, err.L1_P,
      ex::relative_change(end.total_energy(), start.total_energy()), dir.string());
  return 0;
}

/// Both methods run on the ranks of mpiexec where built with MPI (ex::with_ranks), RSPH's multi-level lattices
/// and consistent gradients too.
template <int D, class Kernel>
int run_method(const Options& opt) {
  if (opt.method == "sph")
    return ex::with_ranks<D>(
        [&](auto... domain) { return run<D, Kernel>(opt, scenes::make_sod<D, Kernel>(opt.sod, domain...)); });
  if (opt.method == "rsph")
    return ex::with_remap(opt.rsph.remap, [&](auto order) {
      using Order = decltype(order);
      if constexpr (D == 3) {
        return ex::with_ranks<D>([&](auto... domain) {
          return run<D, Kernel>(opt, scenes::make_rsph_sod3<Kernel, Order>(opt.sod, opt.rsph, domain...));
        });
      } else {
        return ex::with_ranks<D>([&](auto... domain) {
          if (opt.consistent_gradient)
            return run<D, Kernel>(opt,
                                  scenes::make_rsph_sod<D, Kernel, Order>(opt.sod, opt.rsph, opt.gradient, domain...));
          return run<D, Kernel>(opt, scenes::make_rsph_sod<D, Kernel, Order>(opt.sod, opt.rsph, domain...));
        });
      }
    });
  throw InputError("unknown method '" + opt.method + "' (sph, rsph)");
}

template <int D>
int run_kernel(const Options& opt) {
  return ex::with_kernel(opt.kernel, [&](auto k) { return run_method<D, decltype(k)>(opt); });
}

}  // namespace

int main(int argc, char** argv) {
  return ex::program_main("rsph-sod", argc, argv, [&] {
    Options opt;
    ex::po::options_description desc("rsph-sod options");
    ex::Flags flag(desc, opt.common);
    ex::add_common_options(flag, opt.common, "--n-left 200 --snapshots 2; in 3D --n-left 100 --ny-left 4");
    flag("dim", opt.dim, "1, 2 for a strip periodic in y, or 3 for a tube periodic in y and z");
    flag("n-left", opt.sod.n_left, "particles across the left half");
    flag("ny-left", opt.sod.ny_left, "2D, 3D: particles across the strip (tube) along y (and z), left state");
    flag("h-over-dx", opt.sod.h_over_dx, "h / particle spacing");
    flag("alpha", opt.sod.alpha, "artificial viscosity alpha");
    flag("beta", opt.sod.beta, "artificial viscosity beta");
    flag("t-end", opt.sod.t_end, "end time");
    flag("courant", opt.sod.courant, "Courant factor");
    flag("gamma", opt.sod.gamma, "ratio of specific heats");
    flag("kernel", opt.kernel, ex::kernel_names);
    flag("snapshots", opt.snapshots, "HDF5 snapshots after the initial one");
    flag("method", opt.method, "sph: equal masses, grad-h; rsph: lattice regularization, levels in factors of two");
    flag("cycle", opt.rsph.cycle, "rsph: steps between regularizations");
    ex::add_remap_flag(flag, opt.rsph.remap);
    flag("consistent-gradient", opt.consistent_gradient,
         "rsph: continuity density and pair gradients corrected so that level faces keep uniform states exact");
    flag("gradient-tolerance", opt.gradient.tolerance, "rsph: relative residual of the consistent-gradient solve");
    flag("max-bin", opt.rsph.max_bin,
         "rsph: individual time steps in power-of-two bins down to 2^-max-bin of the longest (0: global)");
    ex::add_level_options(flag, opt.rsph.refinement, "rsph",
                          "finest level L (0: uniform); the finest spacing is 0.5 / n-left");
    ex::po::variables_map vm;
    if (!ex::parse(argc, argv, desc, vm,
                   "rsph-sod: Sod's shock tube, plain SPH or RSPH, against the exact solution.\n"
                   "Usage: rsph-sod [--dim 1|2|3] [--method sph|rsph] [--preset quick|paper] [--out DIR] ..."))
      return 0;
    if (ex::quick_preset(opt.common)) {
      if (vm["n-left"].defaulted()) opt.sod.n_left = opt.dim == 3 ? 100 : 200;
      if (vm["ny-left"].defaulted() && opt.dim == 3) opt.sod.ny_left = 4;
      if (vm["snapshots"].defaulted()) opt.snapshots = 2;
    }
    require(opt.snapshots >= 1, "--snapshots must be at least 1 (got " + std::to_string(opt.snapshots) + ")");
    ex::record_run(opt.common, argc, argv);
    ex::apply_threads(opt.common.threads);
    if (opt.dim == 1) return run_kernel<1>(opt);
    if (opt.dim == 2) return run_kernel<2>(opt);
    if (opt.dim == 3) {
      require(opt.method != "rsph" || (vm["levels"].defaulted() && !opt.consistent_gradient),
              "3D RSPH runs on the uniform cubic lattice: --levels and --consistent-gradient are 1D and 2D only");
      return run_kernel<3>(opt);
    }
    throw InputError("--dim must be 1, 2 or 3 (got " + std::to_string(opt.dim) + ")");
  });
}
