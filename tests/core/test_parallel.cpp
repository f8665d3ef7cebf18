#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <stdexcept>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "../regularize/particle_sets.hpp"

using namespace rsph;

namespace {

/// How often run_parallel visits each index of [0, n), and whether each thread's chunk follows the one
/// before it.
struct Coverage {
  std::vector<int> visits;
  bool in_order = true;
};
Coverage cover(std::size_t n) {
  Coverage c;
  c.visits.assign(n, 0);
  std::vector<std::size_t> begins(static_cast<std::size_t>(max_threads()) + 1, n), ends(begins.size(), n);
  run_parallel(n, [&](int t, std::size_t begin, std::size_t end) {
    begins[static_cast<std::size_t>(t)] = begin;
    ends[static_cast<std::size_t>(t)] = end;
    for (std::size_t i = begin; i < end; ++i) ++c.visits[i];  // chunks are disjoint: no race
  });
  for (std::size_t t = 0; t + 1 < begins.size() && begins[t + 1] != n; ++t) c.in_order &= ends[t] == begins[t + 1];
  return c;
}

}  // namespace

TEST_CASE("run_parallel visits every index once, in contiguous chunks by thread", "[core]") {
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
    const auto c = cover(n);
    INFO("n = " << n);
    CHECK(c.in_order);
    CHECK(std::count(c.visits.begin(), c.visits.end(), 1) == static_cast<std::ptrdiff_t>(n));
  }
}

TEST_CASE("run_parallel called from inside a parallel region still covers the whole range", "[core]") {
  // There the inner team is one thread although max_threads() says two: the chunks must follow the team.
  std::vector<int> complete(64, -1);
#ifdef _OPENMP
  const int before = omp_get_max_threads();
  omp_set_num_threads(2);  // whatever OMP_NUM_THREADS says, the inner calls ask for two
#endif
#pragma omp parallel num_threads(2)
  {
    int t = 0;
#ifdef _OPENMP
    t = omp_get_thread_num();
#endif
    const auto c = cover(1000);
    complete[static_cast<std::size_t>(t)] = std::count(c.visits.begin(), c.visits.end(), 1) == 1000;
  }
#ifdef _OPENMP
  omp_set_num_threads(before);
#endif
  CHECK(complete[0] == 1);
  for (std::size_t t = 1; t < complete.size(); ++t) CHECK(complete[t] != 0);  // -1: no such thread
}

TEST_CASE("run_parallel carries an exception out of the parallel region", "[core]") {
  CHECK_THROWS_AS(run_parallel(100,
                               [](int, std::size_t begin, std::size_t end) {
                                 if (begin <= 42 && 42 < end) throw std::runtime_error("index 42");
                               }),
                  std::runtime_error);
}

TEST_CASE("run_parallel_packed writes what each chunk counted, in the order of a serial pass", "[core]") {
  // the multiples of 3 below n, packed
  for (std::size_t n : {std::size_t{0}, std::size_t{5}, std::size_t{1001}}) {
    std::vector<std::size_t> out;
    const std::size_t total = run_parallel_packed(
        n,
        [](std::size_t begin, std::size_t end) {
          std::size_t k = 0;
          for (std::size_t i = begin; i < end; ++i) k += i % 3 == 0;
          return k;
        },
        [&](std::size_t size) { out.assign(size, n); },
        [&](int, std::size_t begin, std::size_t end, std::size_t first) {
          for (std::size_t i = begin; i < end; ++i)
            if (i % 3 == 0) out[first++] = i;
        });
    INFO("n = " << n);
    REQUIRE(total == (n + 2) / 3);
    REQUIRE(out.size() == total);
    for (std::size_t k = 0; k < total; ++k) CHECK(out[k] == 3 * k);
  }
}

#ifdef _OPENMP
TEST_CASE("a remap on two threads gives the new set of one thread", "[core][regularize]") {
  // The new set is written by both threads from their own first index on, and the per-thread sums are
  // reduced by cells: the particles must come out in the same lattice order with the same values.
  const Box<2> box = test::box_with(Edge::periodic, Edge::reflecting);
  const auto p0 = test::jittered_gas(48, 0.4, 9);
  auto remap_on = [&](int threads) {
    const int before = omp_get_max_threads();
    omp_set_num_threads(threads);
    auto p = p0;
    geometry::LocalVoronoi builder;
    const auto stats = regularize::remap_onto_lattice(p, box, lattice::Square{1.0 / 48}, builder, {});
    omp_set_num_threads(before);
    return std::pair{p, stats};
  };
  const auto [one, stats_one] = remap_on(1);
  const auto [two, stats_two] = remap_on(2);
  REQUIRE(one.n_real == two.n_real);
  double worst_m = 0.0, worst_v = 0.0, worst_u = 0.0;
  for (std::size_t a = 0; a < one.n_real; ++a) {
    REQUIRE(one.x[a] == two.x[a]);
    worst_m = std::max(worst_m, std::abs(one.m[a] / two.m[a] - 1.0));
    worst_v = std::max(worst_v, (one.v[a] - two.v[a]).norm());
    worst_u = std::max(worst_u, std::abs(one.u[a] / two.u[a] - 1.0));
  }
  CHECK(worst_m < 1e-14);  // only the cells the two threads share add their sums in another order
  CHECK(worst_v < 1e-14);
  CHECK(worst_u < 1e-13);
  CHECK(stats_two.kinetic_converted == Approx(stats_one.kinetic_converted).epsilon(1e-12));
  CHECK(stats_two.max_volume_mismatch == Approx(stats_one.max_volume_mismatch).margin(1e-15));
}
#endif
