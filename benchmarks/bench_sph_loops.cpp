// Density (eq. 2) and force (eqs. 3-4) loops on a jittered 2D or 3D lattice, fixed h as on an RSPH lattice.
// Reported as particle updates per second (items_per_second), serial and with all threads.
#include "rsph/rsph.hpp"

#include "bench_common.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

using namespace rsph;

namespace {

template <int D>
using Sim = Simulation<D, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::ArtificialViscosity>;

/// About n_particles on a periodic unit lattice (n^D sites), jittered by 0.05 of the spacing, random velocities.
template <int D>
std::unique_ptr<Sim<D>> make_lattice(std::int64_t n_particles, double h_over_dx) {
  const int n = static_cast<int>(std::lround(std::pow(static_cast<double>(n_particles), 1.0 / D)));
  const double dx = 1.0 / n;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  ParticleSet<D, true> p;
  const int nz = D == 3 ? n : 1;
  p.reserve(static_cast<std::size_t>(n) * n * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int index[3] = {i, j, k};
        Vec<D> x, v;
        for (int c = 0; c < D; ++c) {
          x[c] = (index[c] + 0.5 + u(rng)) * dx;
          v[c] = u(rng);
        }
        p.add(std::pow(dx, D), x, v, h_over_dx * dx, 1.0);
      }
  Box<D> box;
  for (int c = 0; c < D; ++c) box.edge[static_cast<std::size_t>(c)] = Edge::periodic;
  return std::make_unique<Sim<D>>(std::move(p), box, eos::IdealGas{1.4}, regularize::None{}, TimeStepParams{},
                                  physics::ArtificialViscosity{1.0, 2.0});
}

// The passes alone (physics/loops/), over the particles, ghosts and neighbour lists the simulation set up.
template <int D, bool Forces>
void BM_loop(benchmark::State& state) {
  const double h_over_dx = static_cast<double>(state.range(1)) / 10.0;
  const int threads = bench::use_threads(state);
  auto sim = make_lattice<D>(state.range(0), h_over_dx);
  auto p = sim->particles();
  const auto& nl = sim->neighbor_list();
  const neighbors::FirstN rows{p.n_real};
  const auto terms = std::tuple{physics::ArtificialViscosity{1.0, 2.0}};
  std::vector<double> P_over_rho2, v_sig, drho_dt;
  physics::loops::NumberDensity unused;
  physics::loops::update_pressure<D>(sim->eos(), p, P_over_rho2);
  for (auto _ : state) {
    if constexpr (Forces) {
      physics::loops::ForceFields<D> fields;
      fields.P_over_rho2 = P_over_rho2;
      physics::loops::force_rows<typename Sim<D>::LoopScheme, false>(p, nl, rows, fields, terms, 0.0, {v_sig, drho_dt});
    } else {
      physics::loops::density_rows<typename Sim<D>::KernelType, D, true, false>(p, nl, rows, unused);
      physics::loops::update_pressure<D>(sim->eos(), p, P_over_rho2);
    }
    benchmark::DoNotOptimize(p.rho.data());
  }
  const auto n = static_cast<std::int64_t>(p.n_real);
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["threads"] = threads;
  state.counters["neighbours"] = static_cast<double>(sim->neighbor_list().pairs()) / static_cast<double>(n);
}

void BM_density(benchmark::State& s) { BM_loop<2, false>(s); }
void BM_forces(benchmark::State& s) { BM_loop<2, true>(s); }
void BM_density3d(benchmark::State& s) { BM_loop<3, false>(s); }
void BM_forces3d(benchmark::State& s) { BM_loop<3, true>(s); }

template <int D>
void all_rates(benchmark::State& state) {
  const int threads = bench::use_threads(state);
  auto sim = make_lattice<D>(state.range(0), static_cast<double>(state.range(1)) / 10.0);
  for (auto _ : state) sim->compute_rates();  // ghosts, cell list, neighbour lists, density and forces
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(sim->particles().n_real));
  state.counters["threads"] = threads;
}
void BM_all_rates(benchmark::State& s) { all_rates<2>(s); }
void BM_all_rates3d(benchmark::State& s) { all_rates<3>(s); }

// {particles, 10 h/dx, threads (0: all)}
void sizes(benchmark::internal::Benchmark* b) {
  for (std::int64_t n : {10000, 100000, 1000000})
    for (std::int64_t h : {12, 14})
      for (std::int64_t t : {1, 0}) b->Args({n, h, t});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK(BM_density)->Apply(sizes);
BENCHMARK(BM_forces)->Apply(sizes);
BENCHMARK(BM_all_rates)->Apply(sizes);
BENCHMARK(BM_density3d)->Apply(sizes);
BENCHMARK(BM_forces3d)->Apply(sizes);
BENCHMARK(BM_all_rates3d)->Apply(sizes);
BENCHMARK_MAIN();
