#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <set>

using namespace rsph;

namespace {

template <int D, class Reach>
void compare_with_brute_force(unsigned seed, std::array<Edge, D> edges, Reach reach, double support_factor,
                              double h_lo = 0.02, double h_hi = 0.05) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0), hu(h_lo, h_hi);
  ParticleSet<D, false> p;
  Box<D> box;
  box.edge = edges;
  const int n = D == 1 ? 300 : (D == 2 ? 1500 : 3000);
  for (int i = 0; i < n; ++i) {
    Vec<D> x;
    for (int k = 0; k < D; ++k) x[k] = u(rng);
    p.add(1.0, x, Vec<D>::Zero(), hu(rng));
  }
  const double h_max = *std::max_element(p.h.begin(), p.h.end());
  const double h_min = *std::min_element(p.h.begin(), p.h.end());
  const double width = support_factor * h_max;
  boundary::make_ghosts(p, box, width);
  neighbors::CellList<D> cells;
  cells.build(p.x, support_factor * h_min);  // small cells: large-h particles search several rings
  neighbors::NeighborList nl;
  neighbors::build_neighbor_list<D>(p.x, p.h, p.n_real, reach, cells, nl);

  bool any_reflecting = false;
  for (int k = 0; k < D; ++k) any_reflecting |= edges[k] == Edge::reflecting;
  std::set<std::pair<std::uint32_t, std::uint32_t>> fast;
  for (std::size_t a = 0; a < p.n_real; ++a)
    for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
      const std::uint32_t b = nl.index[k];
      const std::uint32_t src = b < p.n_real ? b : p.ghost_source[b - p.n_real];
      const bool fresh = fast.emplace(static_cast<std::uint32_t>(a), src).second;
      if (!any_reflecting) CHECK(fresh);  // each neighbour found once (no duplicate periodic images)
    }
  std::vector<Vec<D>> xr(p.x.begin(), p.x.begin() + static_cast<std::ptrdiff_t>(p.n_real));
  std::vector<double> hr(p.h.begin(), p.h.begin() + static_cast<std::ptrdiff_t>(p.n_real));
  Box<D> oracle_box = box;
  for (int k = 0; k < D; ++k)
    if (oracle_box.edge[k] == Edge::reflecting) oracle_box.edge[k] = Edge::open;  // mirrors are not neighbours
  const auto slow = neighbors::brute_force_pairs<D>(xr, hr, p.n_real, reach, oracle_box);
  const std::set<std::pair<std::uint32_t, std::uint32_t>> slow_set(slow.begin(), slow.end());
  // every true pair is found; extra pairs may only be mirror images (reflecting axes)
  for (const auto& pr : slow_set) CHECK(fast.count(pr) == 1);
  if (!any_reflecting) CHECK(fast.size() == slow_set.size());
  CHECK(slow_set.size() > static_cast<std::size_t>(n));
}

}  // namespace

TEST_CASE("cell list finds exactly the brute-force pairs (variable h, open box)", "[neighbors]") {
  compare_with_brute_force<1>(1, {Edge::open}, neighbors::MeanH{2.0}, 2.0);
  compare_with_brute_force<2>(2, {Edge::open, Edge::open}, neighbors::MeanH{2.0}, 2.0);
  compare_with_brute_force<3>(3, {Edge::open, Edge::open, Edge::open}, neighbors::MeanH{2.0}, 2.0);
}

TEST_CASE("cell list finds exactly the brute-force pairs in periodic boxes", "[neighbors]") {
  compare_with_brute_force<1>(4, {Edge::periodic}, neighbors::MeanH{2.0}, 2.0);
  compare_with_brute_force<2>(5, {Edge::periodic, Edge::periodic}, neighbors::MeanH{2.0}, 2.0);
  compare_with_brute_force<2>(6, {Edge::periodic, Edge::open}, neighbors::MeanH{3.0}, 3.0);
  compare_with_brute_force<3>(7, {Edge::periodic, Edge::periodic, Edge::periodic}, neighbors::MeanH{2.0}, 2.0);
}

TEST_CASE("grad-h search radius support * max(h_a, h_b)", "[neighbors]") {
  compare_with_brute_force<2>(8, {Edge::periodic, Edge::periodic}, neighbors::MaxH{2.0, 1.25}, 2.5);
}

TEST_CASE("smoothing lengths spread over a factor 10: pairs seen only from the larger h are kept", "[neighbors]") {
  compare_with_brute_force<2>(10, {Edge::periodic, Edge::periodic}, neighbors::MeanH{2.0}, 2.0, 0.008, 0.08);
  compare_with_brute_force<2>(11, {Edge::periodic, Edge::open}, neighbors::MaxH{2.0, 1.25}, 2.5, 0.008, 0.08);
  compare_with_brute_force<1>(12, {Edge::periodic}, neighbors::MeanH{3.0}, 3.0, 0.002, 0.02);
}

TEST_CASE("reflecting walls add mirror images and keep real pairs", "[neighbors]") {
  compare_with_brute_force<2>(9, {Edge::reflecting, Edge::periodic}, neighbors::MeanH{2.0}, 2.0);
}

TEST_CASE("neighbour lists of a subset of the points equal their rows in the full list", "[neighbors]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<2>> x;
  std::vector<double> h;
  for (int i = 0; i < 2000; ++i) {
    x.emplace_back(u(rng), u(rng));
    h.push_back(0.02 + 0.03 * u(rng));  // a spread of h: the scatter pass matters
  }
  neighbors::CellList<2> cells;
  cells.build(x, 0.08);
  neighbors::NeighborList full, part;
  neighbors::build_neighbor_list<2>(x, h, x.size(), neighbors::MeanH{2.0}, cells, full);
  std::vector<std::uint32_t> subset;
  std::vector<std::int32_t> row(x.size(), -1);
  for (std::uint32_t a = 0; a < x.size(); a += 7) {
    row[a] = static_cast<std::int32_t>(subset.size());
    subset.push_back(a);
  }
  neighbors::build_neighbor_list<2>(x, h, neighbors::Subset{&subset, &row}, neighbors::MeanH{2.0}, cells, part);
  REQUIRE(part.offset.size() == subset.size() + 1);
  for (std::size_t i = 0; i < subset.size(); ++i) {
    const std::uint32_t a = subset[i];
    std::vector<std::uint32_t> want(full.index.begin() + static_cast<std::ptrdiff_t>(full.offset[a]),
                                    full.index.begin() + static_cast<std::ptrdiff_t>(full.offset[a + 1]));
    std::vector<std::uint32_t> got(part.index.begin() + static_cast<std::ptrdiff_t>(part.offset[i]),
                                   part.index.begin() + static_cast<std::ptrdiff_t>(part.offset[i + 1]));
    std::sort(want.begin(), want.end());
    std::sort(got.begin(), got.end());
    REQUIRE(got == want);
  }
}
