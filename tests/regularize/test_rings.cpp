// The orbit-following rings lattice: its cells tile the plane as the Voronoi cells of its sites, its lookup by
// ring and angle finds every cell an old cell overlaps, gas on circular orbits returns to its sites exactly,
// and both remaps onto it conserve, and the second order carries linear fields exactly within its bounds.
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <random>
#include <set>

#include "../geometry/boost_oracle.hpp"
#include "conservation_check.hpp"
#include "particle_sets.hpp"

using namespace rsph;
using regularize::RemapParams;
using regularize::SecondOrderParams;

namespace {

const lattice::Rings rings{0.05, 0.3};  // Delta = 0.05 from r = 0.3: 38 sites on the innermost ring

/// Gas on rings first..last of `rings`, each ring turned by Omega(r) t (Keplerian), every particle moved by up to
/// `jitter` Delta, with masses, velocities (circular plus `kick` at random) and u varied at random.
template <bool E = true>
ParticleSet<2, E> polar_gas(std::int64_t first, std::int64_t last, double t, double jitter, unsigned seed,
                            double kick = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto sites = rings.sites(first, last);
  ParticleSet<2, E> p;
  for (std::size_t c = 0; c < sites.n_cells; ++c) {
    const Vec<2> s = sites.site(c);
    const double r = s.norm(), turn = t * std::pow(r, -1.5);
    Vec<2> x(std::cos(turn) * s.x() - std::sin(turn) * s.y(), std::sin(turn) * s.x() + std::cos(turn) * s.y());
    x += jitter * rings.spacing * Vec<2>(u(rng), u(rng));
    const Vec<2> v = std::pow(r, -0.5) * Vec<2>(-x.y(), x.x()) / x.norm() + kick * Vec<2>(u(rng), u(rng));
    p.add(1e-3 * (1.0 + 0.3 * u(rng)), x, v, 1.4 * rings.spacing, 1.0 + 0.5 * u(rng));
  }
  return p;
}

Box<2> open_box() { return test::box_with(Edge::open, Edge::open); }
/// The disk's remap parameters: h = 1.4 Delta, edge cells closed at 0.75 Delta, half-empty cells handed on.
const RemapParams disk_params{1.4, 0.5, 0.75 / 1.4, 1e-6};

/// The sites a remap of p onto `rings` uses.
template <bool E>
lattice::RingSites sites_for(const ParticleSet<2, E>& p, const RemapParams& params = disk_params) {
  double max_h = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) max_h = std::max(max_h, p.h[a]);
  return rings.following(std::span<const Vec<2>>(p.x.data(), p.n_real), std::span<const double>(p.m.data(), p.n_real),
                         params.closing_radius_in_h * max_h * 1.1);
}

/// The old cells of p as the second-order remap sees them, closed at open edges as `params` say.
regularize::second_order::CellStore<2> cells_of(const ParticleSet<2, true>& p, const RemapParams& params) {
  geometry::LocalVoronoi builder;
  regularize::second_order::CellStore<2> cells;
  regularize::second_order::CellsByThread by_thread;
  neighbors::CellList<2> lookup;
  std::vector<double> closing;
  regularize::second_order::collect_cells(p, open_box(), builder, params, region::Unbounded{}, closing, by_thread,
                                          lookup, cells);
  return cells;
}

/// The site nearest to x.
std::size_t site_of(const lattice::RingSites& sites, const Vec<2>& x) {
  std::size_t nearest = 0;
  for (std::size_t c = 1; c < sites.n_cells; ++c)
    if ((sites.site(c) - x).squaredNorm() < (sites.site(nearest) - x).squaredNorm()) nearest = c;
  return nearest;
}

}  // namespace

TEST_CASE("rings lattice: the cells tile the plane as the Voronoi cells of the sites", "[regularize]") {
  for (const double t : {0.0, 0.7, 13.1}) {
    INFO("turned by Omega t, t = " << t);
    const auto gas = polar_gas(2, 12, t, 0.0, 1);
    const auto sites = sites_for(gas);
    // a window inside the rings: the cells' parts in it add up to it
    const auto window = geometry::ConvexPolygon::rectangle(0.2, 0.35, 0.75, 0.6);
    double covered = 0.0;
    for (std::size_t c = 0; c < sites.n_cells; ++c)
      covered += geometry::area(geometry::clip_convex(sites.cell(c, Vec<2>::Zero()), window));
    CHECK(std::abs(covered - geometry::area(window)) < 1e-12 * geometry::area(window));
    // every point lies in the cell of its nearest site
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-0.9, 0.9);
    for (int k = 0; k < 400; ++k) {
      const Vec<2> x(u(rng), u(rng));
      if (x.norm() < 0.45 || x.norm() > 0.85) continue;
      const auto cell = sites.cell(site_of(sites, x), x);
      for (int v = 0, w = cell.n - 1; v < cell.n; w = v++) {  // x (the origin here) inside every edge
        const Vec<2> e = cell[v] - cell[w];
        CHECK(e.x() * (-cell[w].y()) - e.y() * (-cell[w].x()) >= -1e-14);
      }
    }
  }
}

TEST_CASE(
    "rings lattice: the lookup by ring and angle names every cell an old cell overlaps, and the pieces, found "
    "nearest cell first, are the whole lookup's to the bit",
    "[regularize]") {
  const double jitter = GENERATE(0.45, 0.0);  // gas off its orbits, and on them (one piece an old cell)
  auto p = polar_gas(1, 10, 2.3, jitter, 3);
  const auto sites = sites_for(p);
  geometry::LocalVoronoi builder;
  std::vector<double> closing(p.n_real, 0.75 * rings.spacing);
  std::size_t checked = 0, overlapping = 0, pieces = 0, mismatched = 0;
  struct Visit {
    std::function<void(std::size_t, const geometry::ConvexPolygon&)> f;
    void restart() {}
    void operator()(int, std::size_t a, const geometry::ConvexPolygon& cell) { f(a, cell); }
  } visit;
  std::mutex lock;
  visit.f = [&](std::size_t a, const geometry::ConvexPolygon& cell) {
    const Vec<2>& xo = p.x[a];
    const double crumb = 1e-13 * geometry::area(cell);
    std::set<std::size_t> named;
    // every candidate clipped in the lookup's order, as the remap did before it looked at the nearest cell first
    std::vector<std::pair<std::size_t, double>> whole, found;
    sites.for_each_candidate(cell, xo, [&](std::size_t c) {
      named.insert(c);
      if (!sites.box_meets(c, xo, geometry::bounds(cell))) return;
      const auto window = sites.cell(c, xo);
      if (geometry::apart(cell, window, crumb / sites.diameter(c))) return;
      if (const double w = geometry::area(geometry::clip_convex(cell, window)); w > crumb) whole.emplace_back(c, w);
    });
    regularize::detail::for_each_site_piece(sites, cell, xo, crumb, [&](std::size_t c, const auto& piece) {
      found.emplace_back(c, geometry::area(piece));
    });
    std::lock_guard guard(lock);
    for (std::size_t c = 0; c < sites.n_cells; ++c) {
      const double overlap = geometry::area(geometry::clip_convex(cell, sites.cell(c, xo)));
      if (overlap <= 1e-14 * rings.spacing * rings.spacing) continue;
      ++overlapping;
      CHECK(named.count(c) == 1);
    }
    mismatched += found != whole;
    pieces += found.size();
    ++checked;
  };
  builder.build(p.x, open_box(), closing, visit);
  INFO("jitter " << jitter << " spacings: " << pieces << " pieces of " << checked << " old cells");
  CHECK(checked == p.n_real);
  CHECK(mismatched == 0);
  if (jitter > 0.0) {
    CHECK(overlapping > 3 * p.n_real);
  } else {
    // gas on the orbits the rings follow: each old cell lies in its own new cell (the edge rings' cells, which
    // take in the gas beyond them, excepted); measured 1.0 an old cell
    CHECK(pieces < 1.1 * static_cast<double>(p.n_real));
  }
}

TEST_CASE(
    "rings lattice: a part of the gas (one rank's) gets the whole gas's rings, and the cells its old cells "
    "meet, as the whole lattice has them",
    "[regularize]") {
  auto p = polar_gas(1, 10, 2.3, 0.45, 3);
  const auto whole = sites_for(p);
  // the old cells of the gas right of x = 0.3 are this part's; the sums and extremes over "the ranks" are its own
  std::vector<std::uint32_t> mine;
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (p.x[a].x() > 0.3) mine.push_back(static_cast<std::uint32_t>(a));
  regularize::RankPart part;
  part.cells = mine;
  part.max_over_ranks = [](double v) { return v; };
  part.sum_over_ranks = [](std::span<double>) {};
  const double reach = disk_params.closing_radius_in_h * 1.4 * rings.spacing * 1.1;
  const auto sites = rings.following(std::span<const Vec<2>>(p.x.data(), p.n_real),
                                     std::span<const double>(p.m.data(), p.n_real), reach, part);
  REQUIRE(sites.n_cells == whole.n_cells);
  CHECK(sites.phase == whole.phase);
  // the part holds the sites near its old cells, an arc of each ring: its memory follows its gas
  CHECK(sites.n_held() < 3 * sites.n_cells / 4);
  std::size_t near = 0, near_held = 0, moved = 0;
  for (std::size_t c = 0; c < whole.n_cells; ++c) {
    bool close = false;
    for (const auto a : mine) close = close || (whole.site(c) - p.x[a]).norm() <= reach + 1.5 * rings.spacing;
    near += close;
    near_held += close && sites.slot(c) >= 0;
    moved += sites.site(c) != whole.site(c);  // held or placed when asked for, the same bits
  }
  CHECK(near_held == near);
  CHECK(near > sites.n_cells / 3);
  CHECK(moved == 0);
  geometry::LocalVoronoi builder;
  std::vector<double> closing(p.n_real, 0.75 * rings.spacing);
  std::vector<std::vector<std::pair<std::size_t, double>>> pieces(p.n_real), pieces_whole(p.n_real);
  struct Visit {
    std::function<void(std::size_t, const geometry::ConvexPolygon&)> f;
    void restart() {}
    void operator()(int, std::size_t a, const geometry::ConvexPolygon& cell) { f(a, cell); }
  } visit;
  visit.f = [&](std::size_t a, const geometry::ConvexPolygon& cell) {
    auto list = [&](const lattice::RingSites& s, auto& out) {
      regularize::detail::for_each_site_piece(
          s, cell, p.x[a], 1e-13 * geometry::area(cell),
          [&](std::size_t c, const geometry::ConvexPolygon& piece) { out.emplace_back(c, geometry::area(piece)); });
    };
    list(sites, pieces[a]);
    list(whole, pieces_whole[a]);
  };
  builder.build(p.x, open_box(), closing, visit);
  std::size_t listed = 0;
  for (const auto a : mine) {
    CHECK(pieces[a] == pieces_whole[a]);  // the same cells, the same overlaps, bit for bit
    listed += pieces[a].size();
  }
  CHECK(listed > 3 * mine.size());
}

TEST_CASE("rings lattice: the arc of a ring a part holds is the ring less the largest gap, round its end too",
          "[regularize]") {
  using Arcs = std::vector<std::pair<std::int64_t, std::int64_t>>;
  // sites 2-4 and 7-8 of 10: the gap 9, 0, 1 is the largest
  CHECK(lattice::detail::largest_gap(Arcs{{2, 4}, {7, 8}}, 10) == std::pair<std::int64_t, std::int64_t>{9, 3});
  // 0-3 and 8-11 (8, 9, 0, 1): the gap 4-7
  CHECK(lattice::detail::largest_gap(Arcs{{0, 3}, {8, 11}}, 10) == std::pair<std::int64_t, std::int64_t>{4, 4});
  // 5-13 round the end leaves site 4 (14 round the ring)
  CHECK(lattice::detail::largest_gap(Arcs{{5, 13}}, 10) == std::pair<std::int64_t, std::int64_t>{14, 1});
  // 1-6 and 4-10 of 11 leave site 0 (11 round the ring); 3-12 of 10 covers all
  CHECK(lattice::detail::largest_gap(Arcs{{1, 6}, {4, 10}}, 11) == std::pair<std::int64_t, std::int64_t>{11, 1});
  CHECK(lattice::detail::largest_gap(Arcs{{3, 12}}, 10).second == 0);
}

TEST_CASE("rings lattice: gas on circular orbits returns to its sites with its own mass, momentum and energy",
          "[regularize]") {
  // The analogue of the drifting pulse's s = 0: after any time, each ring has turned by its own angle, and the
  // lattice turned with it maps every particle onto itself.
  for (const double t : {0.37, 5.0, 61.9}) {
    for (const bool second : {false, true}) {
      INFO("t = " << t << (second ? ", second order" : ", first order"));
      auto p = polar_gas(0, 9, t, 0.0, 4);
      const auto old = p;
      geometry::LocalVoronoi builder;
      const auto stats = second ? regularize::remap_second_order(p, open_box(), rings, builder, disk_params, {})
                                : regularize::remap_onto_lattice(p, open_box(), rings, builder, disk_params);
      REQUIRE(stats.n_after == old.n_real);
      double worst_x = 0.0, worst_m = 0.0, worst_v = 0.0, worst_u = 0.0;
      for (std::size_t a = 0; a < p.n_real; ++a) {
        std::size_t b = 0;  // the old particle at this site
        for (std::size_t k = 1; k < old.n_real; ++k)
          if ((old.x[k] - p.x[a]).squaredNorm() < (old.x[b] - p.x[a]).squaredNorm()) b = k;
        worst_x = std::max(worst_x, (old.x[b] - p.x[a]).norm() / rings.spacing);
        worst_m = std::max(worst_m, std::abs(p.m[a] - old.m[b]) / old.m[b]);
        worst_v = std::max(worst_v, (p.v[a] - old.v[b]).norm() / old.v[b].norm());
        worst_u = std::max(worst_u, std::abs(p.u[a] - old.u[b]) / old.u[b]);
      }
      CHECK(worst_x < 1e-12);
      CHECK(worst_m < 1e-12);
      CHECK(worst_v < 1e-12);
      CHECK(worst_u < 1e-12);
    }
  }
}

TEST_CASE("rings lattice: both remaps conserve mass, momentum and total energy on perturbed polar sets",
          "[regularize]") {
  for (const double jitter : {0.1, 0.45}) {
    INFO("jitter " << jitter);
    geometry::LocalVoronoi builder;
    auto first = polar_gas(0, 12, 3.3, jitter, 5, 0.1);
    const auto s1 = test::check_conserved(
        first, [&](auto& q) { return regularize::remap_onto_lattice(q, open_box(), rings, builder, disk_params); },
        true);
    auto second = polar_gas(0, 12, 3.3, jitter, 5, 0.1);
    const auto s2 = test::check_conserved(
        second, [&](auto& q) { return regularize::remap_second_order(q, open_box(), rings, builder, disk_params, {}); },
        false);
    CHECK(s1.n_after > 0.97 * s1.n_before);
    CHECK(s2.n_after == s1.n_after);
    auto cold = polar_gas<false>(0, 12, 3.3, jitter, 6, 0.1);
    test::check_conserved(
        cold, [&](auto& q) { return regularize::remap_second_order(q, open_box(), rings, builder, disk_params, {}); },
        false);
  }
}

TEST_CASE("rings lattice: the second-order remap carries a linear field exactly and keeps within bounds",
          "[regularize]") {
  const Vec<2> rho_grad(0.3, -0.2);
  Eigen::Matrix2d v_grad;
  v_grad << -0.1, 0.4, 0.2, 0.0;
  auto rho = [&](const Vec<2>& x) { return 1.0 + rho_grad.dot(x); };
  auto v = [&](const Vec<2>& x) { return Vec<2>(Vec<2>(0.5, -0.3) + v_grad * x); };
  // old cells closed at 2 Delta, not 0.75: no interior cell of the jittered set is cut short
  const RemapParams params{1.4, 0.5, 2.0 / 1.4, 1e-6};
  auto p = polar_gas(0, 14, 1.9, 0.3, 7);
  // every particle the cell averages: m = rho(x_c) V, v = v(x_m), x_m = x_c + I grad rho / m
  const auto cells = cells_of(p, params);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const Vec<2> x_c = p.x[a] + cells.centroid[a];
    p.m[a] = cells.volume[a] * rho(x_c);
    p.v[a] = v(x_c + cells.inertia[a] * rho_grad / p.m[a]);
  }
  const auto old = p;
  const auto sites = sites_for(p);
  SecondOrderParams no_limiter;
  no_limiter.limit = false;
  geometry::LocalVoronoi builder;
  auto limited = p;
  regularize::remap_second_order(p, open_box(), rings, builder, params, no_limiter);
  regularize::remap_second_order(limited, open_box(), rings, builder, params, {});
  REQUIRE(p.n_real == limited.n_real);
  double worst_m = 0.0, worst_v = 0.0, worst_limited = 0.0;
  std::size_t inner = 0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const std::size_t c = site_of(sites, p.x[a]);
    REQUIRE((sites.site(c) - p.x[a]).norm() < 1e-12);
    REQUIRE((limited.x[a] - p.x[a]).norm() == 0.0);
    const double r = sites.site(c).norm();
    if (r < 0.3 + 3.0 * rings.spacing || r > 0.3 + 12.0 * rings.spacing) continue;  // old gas on every side
    const auto m = geometry::moments(sites.cell(c, Vec<2>::Zero()));
    const Vec<2> x_c = m.first / m.area;
    Eigen::Matrix2d I;
    I << m.xx, m.xy, m.xy, m.yy;
    I -= m.area * x_c * x_c.transpose();
    const double mass = m.area * rho(x_c);
    worst_m = std::max(worst_m, std::abs(p.m[a] - mass) / mass);
    worst_v = std::max(worst_v, (p.v[a] - v(x_c + I * rho_grad / mass)).norm());
    if (r > 0.3 + 5.0 * rings.spacing && r < 0.3 + 10.0 * rings.spacing)
      worst_limited = std::max(worst_limited, std::abs(limited.m[a] - mass) / mass);
    ++inner;
  }
  CHECK(inner > 500);
  CHECK(worst_m < 1e-12);
  CHECK(worst_v < 1e-12);
  CHECK(worst_limited < 1e-12);
  // bounds: each new density within the range of the old cells that overlap its cell and of their neighbours
  auto bumpy = polar_gas(0, 10, 0.9, 0.4, 8);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t a = 0; a < bumpy.n_real; ++a) bumpy.m[a] *= u(rng) < 0.2 ? 5.0 : 1.0;
  const auto bc = cells_of(bumpy, params);
  const auto before = bumpy;
  const auto bsites = sites_for(bumpy);
  const auto stats = regularize::remap_second_order(bumpy, open_box(), rings, builder, params, {});
  CHECK(stats.limited_cells > 0);
  std::size_t bounded = 0;
  for (std::size_t k = 0; k < bumpy.n_real; ++k) {
    const double r = bumpy.x[k].norm();
    if (r < 0.3 + 2.0 * rings.spacing || r > 0.3 + 9.0 * rings.spacing) continue;  // no hand-on from edge cells
    const auto cell = bsites.cell(site_of(bsites, bumpy.x[k]), Vec<2>::Zero());
    regularize::second_order::Range range;
    double covered = 0.0;
    for (std::size_t a = 0; a < before.n_real; ++a) {
      geometry::ConvexPolygon o = bc.polygon(a);
      o.translate(before.x[a]);
      const double w = geometry::area(geometry::clip_convex(o, cell));
      if (w <= 1e-12 * rings.spacing * rings.spacing) continue;
      covered += w;
      range.add(before.m[a] / bc.volume[a]);
      for (const auto& f : bc.faces_of(a))
        if (f.b != regularize::second_order::CellStore<2>::no_neighbour) range.add(before.m[f.b] / bc.volume[f.b]);
    }
    if (!(covered > 0.0)) continue;
    const double rho_new = bumpy.m[k] / covered;
    CHECK(rho_new >= range.lo * (1.0 - 1e-12));
    CHECK(rho_new <= range.hi * (1.0 + 1e-12));
    ++bounded;
  }
  CHECK(bounded > 400);
}
