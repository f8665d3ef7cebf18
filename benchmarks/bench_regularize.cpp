// The regularization microbenchmarks: building all Voronoi cells (local half-plane builder vs
// Boost.Polygon) and the full remap (cells, overlaps, new particles), on a jittered lattice and on a
// lattice sheared as by Keplerian rotation, and the full remap against the jitter's amplitude (the cost of
// disorder), a Keplerian disk with open edges as the planet-disk test remaps it, on the square lattice and on the
// orbit-following rings (both orders), and the remap onto a hexagonal lattice; and the second-order remap
// (remap_second/...) on the sets of remap/.... In 3D: the remap of a jittered or sheared cubic lattice (remap3d/...,
// remap3d_second/...), its Voronoi cells alone (cells_local3d/...) and, when voro++ is installed, the same cells by
// voro++ alone (cells_voro/...). items_per_second = old particles per second.
#include "rsph/rsph.hpp"

#include "bench_common.hpp"
#include "remap_sets.hpp"

#include <benchmark/benchmark.h>
#ifdef RSPH_HAVE_VORO
#include <voro++/voro++.hh>
#endif

#include <initializer_list>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

using namespace rsph;
using bench::domain;
using bench::jittered;
using bench::make_set;
using bench::sheared;
using bench::spacing_of;

namespace {

template <class Builder>
void BM_cells(benchmark::State& state) {
  bench::use_threads(state);
  const auto p = make_set(state.range(0), static_cast<int>(state.range(1)));
  Builder builder;
  double total = geometry::cell_areas(builder, p.x, domain())[0];  // untimed: fault in the builder's storage
  for (auto _ : state) {
    const auto areas = geometry::cell_areas(builder, p.x, domain());
    total = areas[0];
  }
  benchmark::DoNotOptimize(total);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.n_real));
  state.SetComplexityN(static_cast<std::int64_t>(p.n_real));
}

/// Times remaps of p0 onto `lattice` in `box`, cells closed by `region`, of the given order; returns the new
/// particle count.
template <class Order = regularize::FirstOrder, class Lattice, int D, bool E, class Region = region::Unbounded>
std::size_t time_remaps(benchmark::State& state, const ParticleSet<D, E>& p0, Lattice& lattice,
                        const Box<D>& box = domain(), const regularize::RemapParams& params = {},
                        const Region& region = {}) {
  // As in a run: the builder and the workspaces persist from remap to remap, and so does the particle
  // storage (copy-assigned, not reallocated).
  typename geometry::DefaultCellBuilder<D>::type builder;
  regularize::RemapWorkspace<D> workspace;
  typename Order::template Workspace<D> order_workspace;
  std::size_t n_after = 0;
  auto p = p0;
  auto remap = [&] { return Order{}.remap(p, box, lattice, builder, params, region, workspace, order_workspace); };
  remap();  // untimed: the first remap faults in the storage every later one reuses
  for (auto _ : state) {
    state.PauseTiming();
    p = p0;
    state.ResumeTiming();
    n_after = remap().n_after;
    benchmark::DoNotOptimize(n_after);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p0.n_real));
  state.SetComplexityN(static_cast<std::int64_t>(p0.n_real));
  return n_after;
}

template <class Order = regularize::FirstOrder>
void BM_remap(benchmark::State& state) {
  bench::use_threads(state);
  const auto p0 = make_set(state.range(0), static_cast<int>(state.range(1)));
  lattice::Square square{spacing_of(p0)};
  time_remaps<Order>(state, p0, square);
}

// Arguments: {particles, jitter in hundredths of a spacing, threads}.
void BM_remap_disorder(benchmark::State& state) {
  bench::use_threads(state);
  const auto p0 = make_set(state.range(0), jittered, static_cast<double>(state.range(1)) / 100.0);
  lattice::Square square{spacing_of(p0)};
  time_remaps(state, p0, square);
}

// A disk as the planet-disk test remaps it: the annulus 0.4 <= r <= 2.5 filled from the square lattice (or
// the rings lattice's unturned sites, `Rings`), rotated at the Keplerian angular velocity r^-1.5 for
// `range(1)` tenths of a time unit (at the test's usual interval of about one unit, neighbouring rows have
// slid by 1.5 spacings), isothermal, open edges, cells closed at 0.75 spacings (and by the annulus on the
// square lattice), remapped onto the lattice it started on. Arguments: {particles, rotation time in tenths,
// threads}.
template <class Lattice, class Order = regularize::FirstOrder>
void BM_remap_disk(benchmark::State& state) {
  bench::use_threads(state);
  constexpr double r_in = 0.4, r_out = 2.5, h_over_dx = 1.4;
  double dx = std::sqrt(std::numbers::pi * (r_out * r_out - r_in * r_in) / static_cast<double>(state.range(0)));
  const double t = static_cast<double>(state.range(1)) / 10.0;
  std::vector<Vec<2>> sites;
  if constexpr (std::is_same_v<Lattice, lattice::Rings>) {
    dx = (r_out - r_in) / std::round((r_out - r_in) / dx);
    const auto s = lattice::Rings{dx, r_in, r_out}.sites(0, std::numeric_limits<std::int64_t>::max());
    for (std::size_t c = 0; c < s.n_cells; ++c) sites.push_back(s.site(c));
  } else {
    const auto n_side = static_cast<int>(std::ceil(r_out / dx));
    for (int j = -n_side; j < n_side; ++j)
      for (int i = -n_side; i < n_side; ++i)
        if (const Vec<2> x((i + 0.5) * dx, (j + 0.5) * dx); x.norm() >= r_in && x.norm() <= r_out) sites.push_back(x);
  }
  ParticleSet<2, false> p0;
  for (const Vec<2>& x : sites) {
    const double omega = std::pow(x.norm(), -1.5), phi = omega * t;
    const Vec<2> rotated(std::cos(phi) * x.x() - std::sin(phi) * x.y(), std::sin(phi) * x.x() + std::cos(phi) * x.y());
    p0.add(dx * dx, rotated, omega * Vec<2>(-rotated.y(), rotated.x()), h_over_dx * dx);
  }
  Box<2> open;
  open.edge = {Edge::open, Edge::open};
  const regularize::RemapParams params{h_over_dx, 0.5, 0.75 / h_over_dx, 1e-6};
  std::size_t n_after = 0;
  if constexpr (std::is_same_v<Lattice, lattice::Rings>) {
    lattice::Rings rings{dx, r_in, r_out};
    n_after = time_remaps<Order>(state, p0, rings, open, params);
  } else {
    lattice::Square square{dx};
    n_after = time_remaps<Order>(state, p0, square, open, params, region::Annulus{r_in, r_out});
  }
  state.counters["new_particles"] = static_cast<double>(n_after);
}

// The same remap onto a two-level lattice: level-0 spacing 2 Delta, the left half refined to Delta, so the
// overlaps are taken on the finest lattice everywhere and summed into the coarse cells.
void BM_remap_two_levels(benchmark::State& state) {
  bench::use_threads(state);
  const auto p0 = make_set(state.range(0), static_cast<int>(state.range(1)));
  auto left_half = refine::region<2>([](const Vec<2>& lo, const Vec<2>&) { return lo[0] < 0.5; }, 1);
  lattice::MultiLevel<2, decltype(left_half)> ml(2.0 * spacing_of(p0), 1, 1, left_half);
  state.counters["new_particles"] = static_cast<double>(time_remaps(state, p0, ml));
}

/// A hexagonal lattice of about n_particles (nearest-neighbour distance Delta = 1 / columns, an even number of
/// rows so that y could be periodic), jittered by up to +-0.3 Delta per axis or sheared as make_set does.
struct HexagonalSet {
  ParticleSet<2, true> p;
  Box<2> box;
  double spacing;
};
HexagonalSet make_hexagonal_set(std::int64_t n_particles, int layout) {
  const double pitch = std::sqrt(3.0) / 2.0;
  const int columns = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n_particles) * pitch)));
  const int rows = 2 * static_cast<int>(std::lround(0.5 * static_cast<double>(n_particles) / columns));
  HexagonalSet s;
  s.spacing = 1.0 / columns;
  s.box = domain();
  s.box.hi[1] = rows * pitch * s.spacing;
  const lattice::Hexagonal hexagonal{s.spacing};
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.3, 0.3), unit(-1.0, 1.0);
  s.p.reserve(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows));
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      Vec<2> x = hexagonal.site(s.box, {i, j});
      x[0] += layout == sheared ? 7.3 * x[1] * x[1] : 0.3 * unit(rng) * s.spacing;
      if (layout == jittered) x[1] = std::clamp(x[1] + 0.3 * unit(rng) * s.spacing, 0.0, s.box.hi[1]);
      x[0] -= std::floor(x[0]);
      s.p.add(hexagonal.cell_volume(), x, Vec<2>(u(rng), u(rng)), 1.2 * s.spacing, 1.0);
    }
  return s;
}

// The remap of a hexagonal lattice onto a hexagonal lattice: cells that are not rectangles take the general
// overlap path (each old cell clipped by the hexagons its bounds meet).
void BM_remap_hexagonal(benchmark::State& state) {
  bench::use_threads(state);
  const auto s = make_hexagonal_set(state.range(0), static_cast<int>(state.range(1)));
  lattice::Hexagonal hexagonal{s.spacing};
  time_remaps(state, s.p, hexagonal, s.box);
}

// 3D: the remap of a cubic lattice, jittered or sheared (remap_sets.hpp), onto a cubic lattice.
template <class Order = regularize::FirstOrder>
void BM_remap3d(benchmark::State& state) {
  bench::use_threads(state);
  const auto p0 = bench::make_set3(state.range(0), static_cast<int>(state.range(1)));
  lattice::Cubic cubic{spacing_of(p0)};
  time_remaps<Order>(state, p0, cubic, bench::domain3());
}

// 3D: all Voronoi cells of the same sets by LocalVoronoi3 (cells and volumes, no lattice).
void BM_cells_local3d(benchmark::State& state) {
  bench::use_threads(state);
  const auto p = bench::make_set3(state.range(0), static_cast<int>(state.range(1)));
  geometry::LocalVoronoi3 builder;
  double total = geometry::cell_volumes(builder, p.x, bench::domain3())[0];  // untimed: fault in the storage
  for (auto _ : state) total = geometry::cell_volumes(builder, p.x, bench::domain3())[0];
  benchmark::DoNotOptimize(total);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.n_real));
  state.SetComplexityN(static_cast<std::int64_t>(p.n_real));
}

#ifdef RSPH_HAVE_VORO
// 3D: the same sets' Voronoi cells by voro++ alone (a container periodic in x and y, walled in z, about five
// particles per block as its documentation advises; every cell computed and its volume taken). voro++ 0.4.6
// runs on one thread.
void BM_cells_voro(benchmark::State& state) {
  const auto p = bench::make_set3(state.range(0), static_cast<int>(state.range(1)));
  const int blocks = std::max(1, static_cast<int>(std::lround(std::cbrt(static_cast<double>(p.n_real) / 5.0))));
  double total = 0.0;
  for (auto _ : state) {
    voro::container con(0.0, 1.0, 0.0, 1.0, 0.0, 1.0, blocks, blocks, blocks, true, true, false, 8);
    for (std::size_t a = 0; a < p.n_real; ++a) con.put(static_cast<int>(a), p.x[a][0], p.x[a][1], p.x[a][2]);
    voro::c_loop_all loop(con);
    voro::voronoicell cell;
    total = 0.0;
    if (loop.start()) do
        if (con.compute_cell(cell, loop)) total += cell.volume();
      while (loop.inc());
    benchmark::DoNotOptimize(total);
  }
  state.counters["volume"] = total;
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.n_real));
  state.SetComplexityN(static_cast<std::int64_t>(p.n_real));
}
#endif

// One family per (layout, threads), so each complexity fit sees one scaling curve in N.
// Arguments: {particles, layout (0 jittered, 1 sheared), threads (0: all)}.
template <class Fn>
void register_family(const std::string& name, Fn fn,
                     std::initializer_list<std::int64_t> sizes = {1000, 10000, 100000, 1000000},
                     std::initializer_list<int> threads = {1, 0}) {
  for (int layout : {jittered, sheared})
    for (int t : threads) {
      const std::string family =
          name + (layout == jittered ? "/jittered" : "/sheared") + (t == 1 ? "/1thread" : "/allthreads");
      auto* b = benchmark::RegisterBenchmark(family.c_str(), fn);
      for (std::int64_t n : sizes) b->Args({n, layout, t});
      b->Unit(benchmark::kMillisecond)->UseRealTime()->Complexity(benchmark::oN);
    }
}

}  // namespace

int main(int argc, char** argv) {
  register_family("cells_local", BM_cells<geometry::LocalVoronoi>);
  register_family("cells_boost_polygon", BM_cells<geometry::BoostVoronoi>);
  register_family("remap", BM_remap<>);
  register_family("remap_second", BM_remap<regularize::SecondOrder>);
  register_family("remap_two_levels", BM_remap_two_levels);
  register_family("remap_hexagonal", BM_remap_hexagonal);
  register_family("remap3d", BM_remap3d<>, {10000, 100000, 1000000});
  register_family("remap3d_second", BM_remap3d<regularize::SecondOrder>, {10000, 100000, 1000000});
  register_family("cells_local3d", BM_cells_local3d, {10000, 100000, 1000000});
#ifdef RSPH_HAVE_VORO
  register_family("cells_voro", BM_cells_voro, {10000, 100000, 1000000}, {1});
#endif
  for (int t : {1, 0}) {
    auto* b = benchmark::RegisterBenchmark(t == 1 ? "remap_disorder/1thread" : "remap_disorder/allthreads",
                                           BM_remap_disorder);
    for (std::int64_t jitter : {0, 5, 10, 15, 20, 30, 40}) b->Args({100000, jitter, t});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
  }
  auto disk = [](const std::string& name, auto fn) {
    for (int t : {1, 0}) {
      auto* b = benchmark::RegisterBenchmark((name + (t == 1 ? "/1thread" : "/allthreads")).c_str(), fn);
      for (std::int64_t n : {10000, 100000, 1000000}) b->Args({n, 10, t});
      b->Unit(benchmark::kMillisecond)->UseRealTime()->Complexity(benchmark::oN);
    }
  };
  disk("remap_disk", BM_remap_disk<lattice::Square>);
  disk("remap_disk_rings", BM_remap_disk<lattice::Rings>);
  disk("remap_disk_second", BM_remap_disk<lattice::Square, regularize::SecondOrder>);
  disk("remap_disk_rings_second", BM_remap_disk<lattice::Rings, regularize::SecondOrder>);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
