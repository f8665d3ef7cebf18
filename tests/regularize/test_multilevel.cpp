#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <numbers>
#include <random>

#include "conservation_check.hpp"
#include "particle_sets.hpp"

using namespace rsph;
using regularize::remap_onto_lattice;
using regularize::RemapParams;
using test::box_with;
using test::jittered_gas;

namespace {

/// x < x_split refined to `level`.
auto left_of(double x_split, int level) {
  return refine::region<2>([=](const Vec<2>& lo, const Vec<2>&) { return lo[0] < x_split; }, level);
}

/// Remaps p onto `lattice` with the remap of order `Order` and checks that it conserves, and that every new
/// particle is counted on a level.
template <class Order = regularize::FirstOrder, int D, class Lattice>
regularize::RemapStats conserving_remap(ParticleSet<D, true>& p, const Box<D>& box, Lattice& lattice,
                                        RemapParams params = {}) {
  geometry::LocalVoronoi builder;
  regularize::RemapWorkspace<D> ws;
  typename Order::template Workspace<D> w2;
  const auto stats = test::check_conserved(
      p,
      [&](ParticleSet<D, true>& q) {
        return Order{}.remap(q, box, lattice, builder, params, region::Unbounded{}, ws, w2);
      },
      Order::heats_only);
  std::size_t sum = 0;
  for (auto n : stats.per_level) sum += n;
  CHECK(sum == p.n_real);
  return stats;
}

/// Largest level difference between neighbouring blocks (diagonals included, periodic images when
/// `periodic`).
template <class ML>
int worst_level_step(const ML& ml, std::int64_t nx, std::int64_t ny, bool periodic = true) {
  int worst = 0;
  for (const auto& [b, l] : ml.levels())
    for (std::int64_t dj = -1; dj <= 1; ++dj)
      for (std::int64_t di = -1; di <= 1; ++di) {
        std::array<std::int64_t, 2> nb{b[0] + di, b[1] + dj};
        if (periodic)
          nb = {(nb[0] % nx + nx) % nx, (nb[1] % ny + ny) % ny};
        else if (nb[0] < 0 || nb[0] >= nx || nb[1] < 0 || nb[1] >= ny)
          continue;
        worst = std::max(worst, std::abs(ml.levels().at(nb) - l));
      }
  return worst;
}

}  // namespace

TEST_CASE("multi-level remap: a level-0 lattice reproduces the uniform remap exactly", "[regularize][multilevel]") {
  auto p = jittered_gas(32, 0.4, 1);
  auto q = p;
  const auto box = box_with(Edge::periodic, Edge::reflecting);
  geometry::LocalVoronoi builder;
  remap_onto_lattice(p, box, lattice::Square{1.0 / 16}, builder, RemapParams{1.6});
  lattice::MultiLevel<2, refine::Region<2, decltype(left_of(0.0, 0).meets)>> ml{1.0 / 16, 0, 4, left_of(0.5, 0)};
  remap_onto_lattice(q, box, ml, builder, RemapParams{1.6});
  REQUIRE(q.n_real == p.n_real);
  // same cells, block order instead of row order: compare as sets keyed by site
  std::map<std::pair<long, long>, std::size_t> at;
  for (std::size_t a = 0; a < p.n_real; ++a) at[{std::lround(p.x[a][0] * 32), std::lround(p.x[a][1] * 32)}] = a;
  for (std::size_t b = 0; b < q.n_real; ++b) {
    const auto a = at.at({std::lround(q.x[b][0] * 32), std::lround(q.x[b][1] * 32)});
    CHECK((q.x[b] - p.x[a]).norm() < 1e-14);
    CHECK(q.m[b] == Approx(p.m[a]).epsilon(1e-12));
    CHECK((q.v[b] - p.v[a]).norm() < 1e-11);
    CHECK(q.h[b] == p.h[a]);
  }
}

TEMPLATE_TEST_CASE("multi-level remap conserves mass, momentum and energy while levels change",
                   "[regularize][multilevel]", regularize::FirstOrder, regularize::SecondOrder) {
  for (auto box : {box_with(Edge::periodic, Edge::periodic), box_with(Edge::reflecting, Edge::reflecting)}) {
    auto p = jittered_gas(48, 0.45, 2);
    using Crit = refine::Region<2, std::function<bool(const Vec<2>&, const Vec<2>&)>>;
    lattice::MultiLevel<2, Crit> ml{1.0 / 16, 2, 2,
                                    Crit{[](const Vec<2>& lo, const Vec<2>&) { return lo[0] < 0.25; }, 2}};
    auto stats = conserving_remap<TestType>(p, box, ml, RemapParams{1.4});
    // blocks of 2 level-0 cells (1/8): x < 0.25 on level 2, the next block column on level 1 (2:1; with
    // periodic x also the last column), the rest on level 0
    const bool periodic = box.periodic(0);
    CHECK(stats.per_level[2] == 2 * 8 * 64);
    CHECK(stats.per_level[1] == (periodic ? 2 : 1) * 8 * 16);
    CHECK(stats.per_level[0] == (periodic ? 4 : 5) * 8 * 4);
    // h follows the level
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const double x = p.x[a][0];
      const double dx = x < 0.25 ? 1.0 / 64 : (x < 0.375 || (periodic && x > 0.875) ? 1.0 / 32 : 1.0 / 16);
      REQUIRE(p.h[a] == Approx(1.4 * dx));
    }
    // move the refined region: levels go up on the right and down on the left, still exactly conservative
    ml.criterion.meets = [](const Vec<2>&, const Vec<2>& hi) { return hi[0] > 0.75; };
    for (auto& v : p.v) v += Vec<2>(0.3, -0.1);
    stats = conserving_remap<TestType>(p, box, ml, RemapParams{1.4});
    CHECK(stats.per_level[2] == 2 * 8 * 64);
    CHECK(worst_level_step(ml, 8, 8, periodic) == 1);
  }
}

TEMPLATE_TEST_CASE("multi-level remap with an open edge: closed cells meet the face cells, still exactly conservative",
                   "[regularize][multilevel]", regularize::FirstOrder, regularize::SecondOrder) {
  auto p = jittered_gas(32, 0.4, 3);
  const auto box = box_with(Edge::open, Edge::reflecting);
  using Crit = refine::Region<2, std::function<bool(const Vec<2>&, const Vec<2>&)>>;
  lattice::MultiLevel<2, Crit> ml{1.0 / 16, 2, 1, Crit{[](const Vec<2>& lo, const Vec<2>&) { return lo[0] < 0.5; }, 1}};
  auto stats = conserving_remap<TestType>(p, box, ml, RemapParams{1.4});
  CHECK(stats.per_level[1] > 0);
  CHECK(stats.per_level[0] > 0);
  for (auto& v : p.v) v += Vec<2>(0.2, 0.1);
  for (auto& x : p.x) x[0] += 0.013;  // off the lattice, so the second remap cuts every cell anew
  stats = conserving_remap<TestType>(p, box, ml, RemapParams{1.4});
  CHECK(stats.per_level[1] > 0);
}

TEST_CASE("2:1 balance holds and a criterion beyond the finest level is capped", "[regularize][multilevel]") {
  auto p = jittered_gas(40, 0.3, 3);
  const auto box = box_with(Edge::periodic, Edge::periodic);
  using Crit = refine::Region<2, std::function<bool(const Vec<2>&, const Vec<2>&)>>;
  // one block in a corner asks for level 5; the lattice stops at 3
  lattice::MultiLevel<2, Crit> ml{
      1.0 / 20, 3, 1, Crit{[](const Vec<2>& lo, const Vec<2>&) { return lo[0] < 1e-9 && lo[1] < 1e-9; }, 5}};
  const auto stats = conserving_remap(p, box, ml);
  CHECK(stats.capped_blocks == 1);
  CHECK(stats.requested_level == 5);
  CHECK(ml.levels().at({0, 0}) == 3);
  CHECK(worst_level_step(ml, 20, 20) == 1);
  // the periodic neighbours across the corner are balanced too
  CHECK(ml.levels().at({19, 19}) == 2);
  CHECK(ml.levels().at({18, 0}) == 1);
  CHECK(ml.levels().at({3, 3}) == 0);
  CHECK(stats.per_level[3] == 64);
}

TEST_CASE(
    "levels chosen over a window L + 1 blocks round a part are the whole set's on the part and one block round it; "
    "without the margin they are not",
    "[regularize][multilevel]") {
  constexpr int L = 3;
  const lattice::MultiLevel<2, refine::TargetMass> ml(1.0, L, 2, refine::TargetMass{1.0, 0.25});
  refine::BlockField<2> whole;
  whole.origin = Vec<2>::Zero();
  whole.spacing = 1.0;
  whole.cells_per_block = 2;
  whole.blocks = {24, 20};
  const std::int64_t nx = 48, ny = 40;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  whole.volume.assign(static_cast<std::size_t>(nx * ny), 1.0);
  whole.mass.resize(whole.volume.size());
  for (auto& m : whole.mass)  // mostly levels 0-1, a few blocks asking for up to L + 1
    m = u(rng) < 0.03 ? std::pow(4.0, 2.0 + L * u(rng)) : 0.5 + 2.0 * u(rng);
  const std::map<std::array<std::int64_t, 2>, int> none;
  regularize::RemapStats stats;
  const auto all = [](const std::array<std::int64_t, 2>&) { return true; };
  const auto levels = regularize::detail::choose_levels(ml, whole, {0, 0}, none, all, stats);
  REQUIRE(stats.requested_level == L + 1);
  // the levels over the window of part [a, b] (blocks), grown by `margin`, differ from the whole's on the part
  // grown by one in this many blocks
  auto differing = [&](std::array<std::int64_t, 2> a, std::array<std::int64_t, 2> b, std::int64_t margin) {
    std::array<std::int64_t, 2> lo, hi;
    for (std::size_t k = 0; k < 2; ++k) {
      lo[k] = std::max<std::int64_t>(0, a[k] - margin);
      hi[k] = std::min<std::int64_t>(whole.blocks[k] - 1, b[k] + margin);
    }
    refine::BlockField<2> window = whole;
    window.blocks = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1};
    window.first_block = lo;
    const std::int64_t wx = 2 * window.blocks[0], wy = 2 * window.blocks[1];
    window.mass.assign(static_cast<std::size_t>(wx * wy), 0.0);
    window.volume = window.mass;
    for (std::int64_t j = 0; j < wy; ++j)
      for (std::int64_t i = 0; i < wx; ++i) {
        const auto from = static_cast<std::size_t>((2 * lo[1] + j) * nx + 2 * lo[0] + i);
        window.mass[static_cast<std::size_t>(j * wx + i)] = whole.mass[from];
        window.volume[static_cast<std::size_t>(j * wx + i)] = whole.volume[from];
      }
    regularize::RemapStats s;
    const auto mine = regularize::detail::choose_levels(ml, window, lo, none, all, s);
    int differ = 0;
    for (std::int64_t j = std::max<std::int64_t>(0, a[1] - 1); j <= std::min<std::int64_t>(19, b[1] + 1); ++j)
      for (std::int64_t i = std::max<std::int64_t>(0, a[0] - 1); i <= std::min<std::int64_t>(23, b[0] + 1); ++i)
        differ += mine[static_cast<std::size_t>((j - lo[1]) * window.blocks[0] + i - lo[0])] !=
                  levels[static_cast<std::size_t>(j * 24 + i)];
    return differ;
  };
  int without_margin = 0;
  for (int trial = 0; trial < 40; ++trial) {
    std::array<std::int64_t, 2> a{}, b{};
    for (std::size_t k = 0; k < 2; ++k) {
      const auto n = static_cast<double>(whole.blocks[k]);
      a[k] = static_cast<std::int64_t>(u(rng) * n);
      b[k] = std::min<std::int64_t>(whole.blocks[k] - 1, a[k] + static_cast<std::int64_t>(u(rng) * 6.0));
    }
    CHECK(differing(a, b, L + 1) == 0);
    without_margin += differing(a, b, 1);
  }
  CHECK(without_margin > 0);  // the balance carries levels farther than a block
}

TEST_CASE("target-mass criterion: levels follow the density, with hysteresis", "[regularize][multilevel]") {
  // density 1 on the left half, 16 on the right: with the target mass equal to a level-0 particle of the
  // light gas, the dense half goes to level 2 (mass 16 / 16 per particle)
  ParticleSet<2, true> p;
  const int n = 32;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double rho = i < n / 2 ? 1.0 : 16.0;
      p.add(rho * dx * dx, Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), 1.2 * dx, 1.0);
    }
  const auto box = box_with(Edge::reflecting, Edge::periodic);
  lattice::MultiLevel<2, refine::TargetMass> ml{1.0 / 16, 3, 2, refine::TargetMass{1.0 / 256, 0.25}};
  auto q = p;
  conserving_remap(q, box, ml);
  CHECK(ml.levels().at({0, 0}) == 0);
  CHECK(ml.levels().at({7, 3}) == 2);
  CHECK(ml.levels().at({4, 3}) == 2);
  CHECK(ml.levels().at({3, 3}) == 1);  // the 2:1 buffer next to the dense gas
  // the dense gas thins to 2^1.8 = 3.48: it asks for level 0.9, which the hysteresis band (0.75, 2.25]
  // of level 2 keeps on level 2, while a lattice without history rounds up to level 1
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (p.x[a][0] > 0.5) p.m[a] *= std::pow(2.0, 1.8) / 16.0;
  q = p;
  conserving_remap(q, box, ml);
  CHECK(ml.levels().at({7, 3}) == 2);
  lattice::MultiLevel<2, refine::TargetMass> fresh{1.0 / 16, 3, 2, refine::TargetMass{1.0 / 256, 0.25}};
  q = p;
  conserving_remap(q, box, fresh);
  CHECK(fresh.levels().at({7, 3}) == 1);
  // thinning on to level 0.7 leaves the band: level 1 then
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (p.x[a][0] > 0.5) p.m[a] *= std::pow(2.0, -0.4);
  q = p;
  conserving_remap(q, box, ml);
  CHECK(ml.levels().at({7, 3}) == 1);
}

TEST_CASE("density-jump criterion refines a front and its hysteresis band", "[regularize][multilevel]") {
  ParticleSet<2, true> p;
  const int n = 64;
  const double dx = 1.0 / n;
  for (int j = 0; j < n / 4; ++j)
    for (int i = 0; i < n; ++i) {
      const double rho = i < n / 2 ? 1.0 : 0.125;
      p.add(rho * dx * dx, Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), 1.2 * dx, 1.0);
    }
  Box<2> box = box_with(Edge::reflecting, Edge::periodic);
  box.hi[1] = 0.25;
  lattice::MultiLevel<2, refine::DensityJump> ml{1.0 / 32, 1, 4, refine::DensityJump{0.5, 0.1, 1}};
  conserving_remap(p, box, ml);
  // blocks of 4/32 = 1/8: the jump at x = 0.5 lies between blocks 3 and 4, each sees it through its halo
  for (std::int64_t b = 0; b < 8; ++b) CHECK(ml.levels().at({b, 0}) == (b == 3 || b == 4 ? 1 : 0));
}

TEMPLATE_TEST_CASE("1D multi-level remap conserves and lays levels out in factors of two", "[regularize][multilevel]",
                   regularize::FirstOrder, regularize::SecondOrder) {
  ParticleSet<1, true> p;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  const int n = 200;
  for (int i = 0; i < n; ++i) p.add(1.0 / n, Vec<1>((i + 0.5 + u(rng)) / n), Vec<1>(u(rng)), 1.2 / n, 1.0 + u(rng));
  Box<1> box;
  box.edge = {Edge::reflecting};
  auto middle = refine::region<1>([](const Vec<1>& lo, const Vec<1>& hi) { return lo[0] < 0.6 && hi[0] > 0.4; }, 2);
  lattice::MultiLevel<1, decltype(middle)> ml{1.0 / 50, 2, 5, middle};
  const auto stats = conserving_remap<TestType>(p, box, ml, RemapParams{2.0});
  // blocks of 0.1: [0.4, 0.6] on level 2 (spacing 1/200), one level-1 block either side
  CHECK(stats.per_level[2] == 40);
  CHECK(stats.per_level[1] == 20);
  CHECK(stats.per_level[0] == 30);
  for (std::size_t a = 1; a < p.n_real; ++a) REQUIRE(p.x[a][0] > p.x[a - 1][0]);  // lattice order
}

TEST_CASE("1D: a set on three levels remaps onto itself; face cells are the intervals between midpoints",
          "[regularize][multilevel]") {
  ParticleSet<1, true> p;
  const int n = 200;
  for (int i = 0; i < n; ++i) p.add(1.0 / n, Vec<1>((i + 0.5) / n), Vec<1>::Zero(), 1.2 / n, 1.0);
  Box<1> box;
  box.edge = {Edge::periodic};
  auto middle = refine::region<1>([](const Vec<1>& lo, const Vec<1>& hi) { return lo[0] < 0.6 && hi[0] > 0.4; }, 2);
  lattice::MultiLevel<1, decltype(middle)> ml{1.0 / 50, 2, 5, middle};
  conserving_remap(p, box, ml, RemapParams{2.0});
  // a uniform state: rho = 1 everywhere, masses equal to the Voronoi intervals
  for (std::size_t a = 0; a < p.n_real; ++a) CHECK(p.rho[a] == Approx(1.0).epsilon(1e-12));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    p.v[a] = Vec<1>(U(rng));
    p.u[a] = 1.0 + 0.5 * U(rng);
  }
  const auto before = p;
  conserving_remap(p, box, ml, RemapParams{2.0});
  REQUIRE(p.n_real == before.n_real);
  double worst = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    worst = std::max(worst, std::abs(p.x[a][0] - before.x[a][0]) * n);
    worst = std::max(worst, std::abs(p.m[a] - before.m[a]) / before.m[a]);
    worst = std::max(worst, std::abs(p.v[a][0] - before.v[a][0]));
    worst = std::max(worst, std::abs(p.u[a] - before.u[a]));
  }
  CHECK(worst < 1e-10);
}

namespace {

struct TwoLevelRun {
  double drho = 0.0, v_over_cs = 0.0, mass_error = 0.0, momentum = 0.0, energy_error = 0.0;
  std::uint64_t regularizations = 0;
  std::size_t n_real = 0;
};

/// rho = 1, P = 1 and velocity v(x) in a box periodic in x and along y as `y_edge` says, left half on
/// level 1, regularized every 33 steps; `steps` steps. drho and v_over_cs measure the departure from rho = 1
/// and from v(x).
template <class Velocity, class... Terms>
TwoLevelRun run_on_two_levels(Edge y_edge, Velocity&& v_of_x, int steps, Terms... terms) {
  const double h_over_dx = 1.6;
  const eos::IdealGas gas{5.0 / 3.0};
  ParticleSet<2, true> p;
  const int n = 64;
  const double dx = 1.0 / n;
  for (int j = 0; j < n / 4; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec<2> x((i + 0.5) * dx, (j + 0.5) * dx);
      p.add(dx * dx, x, v_of_x(x), h_over_dx * dx, gas.internal_energy(1.0, 1.0));
    }
  Box<2> box;
  box.hi = Vec<2>(1.0, 0.25);
  box.edge = {Edge::periodic, y_edge};
  using Crit = refine::Region<2, std::function<bool(const Vec<2>&, const Vec<2>&)>>;
  using ML = lattice::MultiLevel<2, Crit>;
  using Reg = regularize::LatticeRegularizer<ML, schedule::EveryNSteps>;
  ML ml{1.0 / 32, 1, 4, Crit{[](const Vec<2>& lo, const Vec<2>&) { return lo[0] < 0.5; }, 1}};
  conserving_remap(p, box, ml, RemapParams{h_over_dx});
  REQUIRE(p.n_real == 32 * 16 + 16 * 8);
  Simulation<2, kernel::CubicSpline, eos::IdealGas, Reg, Terms...> sim(
      std::move(p), box, gas, Reg(ml, schedule::EveryNSteps{33}, {.remap = {h_over_dx}}), TimeStepParams{}, terms...);
  const auto start = sim.totals();
  for (int s = 0; s < steps; ++s) sim.step();
  const auto end = sim.totals();
  TwoLevelRun r;
  r.regularizations = sim.regularizations();
  r.mass_error = std::abs(end.mass - start.mass);
  r.momentum = (end.momentum - start.momentum).norm();
  r.energy_error = std::abs(end.total_energy() - start.total_energy()) / start.total_energy();
  const auto& q = sim.particles();
  for (std::size_t a = 0; a < q.n_real; ++a) {
    r.drho = std::max(r.drho, std::abs(q.rho[a] - 1.0));
    r.v_over_cs = std::max(r.v_over_cs, (q.v[a] - v_of_x(q.x[a])).norm() / std::sqrt(5.0 / 3.0));
  }
  r.n_real = q.n_real;
  return r;
}

auto constant_velocity(const Vec<2>& v0) {
  return [v0](const Vec<2>&) { return v0; };
}

}  // namespace

TEST_CASE("a uniform state on a two-level lattice: h_ab alone perturbs it by a few percent at the faces",
          "[regularize][multilevel]") {
  // 100 steps, 3 regularizations
  const auto r = run_on_two_levels(Edge::periodic, constant_velocity(Vec<2>::Zero()), 100);
  CHECK(r.regularizations == 3);
  CHECK(r.mass_error < 1e-13);
  CHECK(r.momentum < 1e-13);
  // remaps conserve energy exactly; what drifts is the integrator's error on the face-driven motions
  CHECK(r.energy_error < 1e-3);
  INFO("max |rho - 1| = " << r.drho << ", max |v| / c_s = " << r.v_over_cs);
  // The paper's pair smoothing length h_ab = (h_a + h_b) / 2 is not normalised where h jumps: the state
  // relaxes to density errors of a few percent at the level faces.
  CHECK(r.drho > 0.01);
  CHECK(r.drho < 0.1);
  CHECK(r.v_over_cs < 0.15);
  CHECK(r.n_real == 32 * 16 + 16 * 8);  // the levels stay where the criterion put them
}

TEST_CASE("consistent gradients keep a uniform state on a two-level lattice uniform through regularizations",
          "[regularize][multilevel]") {
  // Walls along y: the level faces meet them, so the band's pairs include mirror images of other
  // particles, whose psi flips its normal component (a wall drift would leave the box: v0 is along x there).
  for (const auto& [y_edge, v0] :
       {std::pair{Edge::periodic, Vec<2>(0.0, 0.0)}, std::pair{Edge::periodic, Vec<2>(0.3, -0.2)},
        std::pair{Edge::reflecting, Vec<2>(0.0, 0.0)}, std::pair{Edge::reflecting, Vec<2>(0.3, 0.0)}}) {
    // 100 steps, 3 regularizations; with v0 the particles drift off the lattice between them
    const auto r = run_on_two_levels(y_edge, constant_velocity(v0), 100, physics::ConsistentGradient{});
    INFO((y_edge == Edge::reflecting ? "walls in y, " : "periodic, ")
         << "v0 = (" << v0[0] << ", " << v0[1] << "): max |rho - 1| = " << r.drho
         << ", max |v - v0| / c_s = " << r.v_over_cs << ", energy error " << r.energy_error);
    CHECK(r.regularizations == 3);
    CHECK(r.drho < 1e-9);  // asked: 1e-3
    CHECK(r.v_over_cs < 1e-9);
    CHECK(r.mass_error < 1e-13);
    CHECK(r.momentum < 1e-13);
    CHECK(r.energy_error < 1e-12);
    CHECK(r.n_real == 32 * 16 + 16 * 8);
  }
}

TEST_CASE("a set on a two-level lattice remaps onto itself: face cells are Voronoi cells of the new sites",
          "[regularize][multilevel]") {
  // left half on level 1; masses proportional to each site's Voronoi area (what a remap of a uniform
  // state gives), velocities and energies varying from particle to particle
  ParticleSet<2, true> p;
  const double dx = 1.0 / 64;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 64; ++i) p.add(dx * dx, Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), 1.6 * dx, 1.0);
  Box<2> box = box_with(Edge::periodic, Edge::reflecting);
  box.hi = Vec<2>(1.0, 0.25);
  auto ml = lattice::MultiLevel<2, decltype(left_of(0.5, 1))>{1.0 / 32, 1, 4, left_of(0.5, 1)};
  conserving_remap(p, box, ml, RemapParams{1.6});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    p.v[a] = Vec<2>(U(rng), U(rng));
    p.u[a] = 1.0 + 0.5 * U(rng);
  }
  const auto before = p;
  const auto stats = conserving_remap(p, box, ml, RemapParams{1.6});
  REQUIRE(p.n_real == before.n_real);
  CHECK(stats.kinetic_converted < 1e-12);
  double worst = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    worst = std::max(worst, (p.x[a] - before.x[a]).norm() / dx);
    worst = std::max(worst, std::abs(p.m[a] - before.m[a]) / before.m[a]);
    worst = std::max(worst, (p.v[a] - before.v[a]).norm());
    worst = std::max(worst, std::abs(p.u[a] - before.u[a]));
    worst = std::max(worst, std::abs(p.rho[a] - before.rho[a]));
  }
  CHECK(worst < 1e-10);
}

TEST_CASE("consistent gradients conserve momentum and energy in a flow across level faces",
          "[regularize][multilevel]") {
  auto shear_wave = [](const Vec<2>& x) {
    return Vec<2>(0.1 * std::sin(2.0 * std::numbers::pi * x[0]), 0.05 * std::cos(8.0 * std::numbers::pi * x[1]));
  };
  const auto plain = run_on_two_levels(Edge::periodic, shear_wave, 32);
  const auto corrected = run_on_two_levels(Edge::periodic, shear_wave, 32, physics::ConsistentGradient{});
  INFO("energy error: h_ab only " << plain.energy_error << ", consistent gradients " << corrected.energy_error);
  CHECK(corrected.mass_error < 1e-13);
  CHECK(corrected.momentum < 1e-13);
  // the leapfrog's error only, as without the correction
  CHECK(corrected.energy_error < 1e-5);
  CHECK(corrected.energy_error < 10.0 * plain.energy_error + 1e-8);
}
