#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <limits>
#include <random>
#include <string>

#include "../geometry/boost_oracle.hpp"
#include "conservation_check.hpp"
#include "particle_sets.hpp"

using namespace rsph;
using regularize::remap_onto_lattice;
using regularize::RemapParams;
using test::box_with;
using test::jittered_gas;

namespace {

template <int D, bool E, class Lattice, class Builder = geometry::LocalVoronoi>
regularize::RemapStats check_conserving_remap(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice,
                                              RemapParams params = {}) {
  Builder builder;
  return test::check_conserved(
      p, [&](ParticleSet<D, E>& q) { return remap_onto_lattice(q, box, lattice, builder, params); }, true);
}

/// Runs the overlap pass over p's cells on `lattice` and checks every listed overlap against Boost.Geometry's
/// intersection of the old cell and the lattice cell, that they sum to the cell's area (none missed), that
/// each is positive and listed once, and that the V_o handed over is their sum in their order, to the bit.
template <class Lattice>
void check_listed_overlaps(const ParticleSet<2, true>& p, const Box<2>& box, const Lattice& lattice) {
  const Vec<2> L = box.hi - box.lo;
  const auto grid = regularize::detail::candidate_grid(p, box, lattice, RemapParams{});
  geometry::LocalVoronoi builder;
  regularize::RemapWorkspace<2> workspace;
  struct Record {
    const ParticleSet<2, true>* p;
    const Lattice* lattice;
    const Box<2>* box;
    const regularize::detail::CellGrid<2>* grid;
    Vec<2> L;
    struct Tally {  // per thread: cells arrive from every builder thread at once
      std::size_t cells = 0, overlaps = 0, sums_differing = 0, not_positive = 0, repeated = 0;
      double worst = 0.0, worst_sum = 0.0;
    };
    std::vector<Tally> tallies = std::vector<Tally>(static_cast<std::size_t>(geometry::builder_threads()));
    void restart() {}
    void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell,
                    std::span<const regularize::detail::Overlap> ov, double V_o, double cell_area) {
      auto& t = tallies[static_cast<std::size_t>(thread)];
      double sum = 0.0;
      for (std::size_t k = 0; k < ov.size(); ++k) {
        const auto& [flat, omega] = ov[k];
        const auto idx = grid->unflat(flat);
        geometry::ConvexPolygon shape = lattice->cell(*box, idx, p->x[a]);
        const Vec<2> d = lattice->site(*box, idx) - p->x[a];
        shape.translate(-(d.array() / L.array()).round().matrix().cwiseProduct(L));  // the image nearest x_a
        t.worst = std::max(t.worst, std::abs(omega - test::oracle_intersection_area(cell, shape)) / cell_area);
        t.not_positive += !(omega > 0.0);
        for (std::size_t m = 0; m < k; ++m) t.repeated += ov[m].first == flat;
        sum += omega;
      }
      t.worst_sum = std::max(t.worst_sum, std::abs(sum - geometry::area(cell)) / cell_area);
      t.sums_differing += V_o != sum;  // the pass's own sum, in the same order: the same bits
      ++t.cells;
      t.overlaps += ov.size();
    }
  } record{&p, &lattice, &box, &grid, L};
  regularize::detail::for_each_old_cell(p, box, lattice, builder, grid, region::Unbounded{}, workspace, record);
  typename Record::Tally all;
  for (const auto& t : record.tallies) {
    all.cells += t.cells;
    all.overlaps += t.overlaps;
    all.sums_differing += t.sums_differing;
    all.not_positive += t.not_positive;
    all.repeated += t.repeated;
    all.worst = std::max(all.worst, t.worst);
    all.worst_sum = std::max(all.worst_sum, t.worst_sum);
  }
  INFO(all.overlaps << " overlaps of " << all.cells << " cells");
  CHECK(all.cells == p.n_real);
  CHECK(all.overlaps > 3 * all.cells);  // a jittered cell spans several lattice cells
  CHECK(all.worst < 1e-13);
  CHECK(all.worst_sum < 1e-13);
  CHECK(all.sums_differing == 0);
  CHECK(all.not_positive == 0);
  CHECK(all.repeated == 0);
}

}  // namespace

TEST_CASE("remap conserves mass, momentum and total energy (square lattice, periodic and walls)", "[regularize]") {
  for (auto box : {box_with(Edge::periodic, Edge::periodic), box_with(Edge::periodic, Edge::reflecting),
                   box_with(Edge::reflecting, Edge::reflecting)}) {
    auto p = jittered_gas(40, 0.45, 1);
    const auto stats = check_conserving_remap(p, box, lattice::Square{1.0 / 40});
    CHECK(stats.n_after == 1600);
    CHECK(stats.kinetic_converted > 0.0);
    // new particles sit on the lattice, in lattice order, with h = (h/Delta) Delta
    CHECK((p.x[0] - Vec<2>(0.5 / 40, 0.5 / 40)).norm() < 1e-15);
    CHECK((p.x[41] - Vec<2>(1.5 / 40, 1.5 / 40)).norm() < 1e-15);
    CHECK(p.h[7] == Approx(1.2 / 40));
  }
}

TEST_CASE("remap onto a hexagonal lattice conserves exactly", "[regularize]") {
  const double dx = 1.0 / 40;
  Box<2> box = box_with(Edge::periodic, Edge::periodic);
  box.hi[1] = 46 * dx * std::sqrt(3.0) / 2.0;  // an even number of rows
  auto p = jittered_gas(40, 0.45, 2);
  for (auto& x : p.x) x[1] *= box.hi[1];
  const auto stats = check_conserving_remap(p, box, lattice::Hexagonal{dx});
  CHECK(stats.n_after == 40 * 46);
}

TEST_CASE("hexagonal lattice: each overlap equals Boost.Geometry's intersection of the cell and the hexagon",
          "[regularize]") {
  // The hexagonal path decides from the old cell's extent along the hexagon's side normals which sides cut and
  // which hexagons lie apart; every overlap it reports must be the oracle's, and none may be missed.
  const double dx = 1.0 / 20;
  Box<2> box = box_with(Edge::periodic, Edge::periodic);
  box.hi[1] = 24 * dx * std::sqrt(3.0) / 2.0;
  for (const double shear : {0.0, 4.0}) {
    auto p = jittered_gas(20, 0.45, 6, shear);
    for (auto& x : p.x) x[1] *= box.hi[1];
    INFO("shear " << shear);
    check_listed_overlaps(p, box, lattice::Hexagonal{dx});
  }
}

TEST_CASE("square lattice: each listed overlap equals Boost.Geometry's intersection of the cell and the square",
          "[regularize]") {
  // The square path lists the Green's-theorem overlaps without a branch per grid cell (each written, kept by
  // advancing a count); what it keeps must be the oracle's, above the crumbs, with none missed.
  for (auto box : {box_with(Edge::periodic, Edge::periodic), box_with(Edge::periodic, Edge::reflecting)})
    for (const double shear : {0.0, 4.0}) {
      auto p = jittered_gas(20, 0.45, 6, shear);
      INFO("shear " << shear);
      check_listed_overlaps(p, box, lattice::Square{1.0 / 20});
    }
}

TEST_CASE("isothermal gas: the kinetic energy lost is reported, not stored", "[regularize]") {
  auto p = jittered_gas<false>(30, 0.4, 3);
  const auto stats = check_conserving_remap(p, box_with(Edge::periodic, Edge::periodic), lattice::Square{1.0 / 30});
  CHECK(stats.kinetic_converted > 0.0);
}

TEST_CASE("a particle set on the target lattice maps onto itself exactly", "[regularize]") {
  for (auto box : {box_with(Edge::periodic, Edge::periodic), box_with(Edge::reflecting, Edge::reflecting)}) {
    auto p = jittered_gas(25, 0.0, 4);
    const auto before = p;
    geometry::LocalVoronoi builder;
    const auto stats = remap_onto_lattice(p, box, lattice::Square{1.0 / 25}, builder, RemapParams{});
    REQUIRE(p.n_real == before.n_real);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      CHECK(p.m[a] == Approx(before.m[a]).epsilon(1e-13));
      CHECK((p.x[a] - before.x[a]).norm() < 1e-14);
      CHECK((p.v[a] - before.v[a]).norm() < 1e-12);
      CHECK(p.u[a] == Approx(before.u[a]).epsilon(1e-12));
    }
    CHECK(std::abs(stats.kinetic_converted) < 1e-14);
  }
}

TEST_CASE("a set on a hexagonal lattice maps onto itself exactly, walls included", "[regularize]") {
  // Hexagons do not tile a box with walls: the parts of the hexagons beyond a wall that lie inside it must
  // go to the nearest sites inside, as the old cells (clipped to the box) do, or the wall rows mix.
  const double dx = 1.0 / 12;
  const lattice::Hexagonal hexagonal{dx};
  for (auto box : {box_with(Edge::periodic, Edge::periodic), box_with(Edge::periodic, Edge::reflecting),
                   box_with(Edge::reflecting, Edge::reflecting)}) {
    box.hi[1] = 14 * hexagonal.row_pitch();
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(0.5, 1.5);
    ParticleSet<2, true> p;
    for (std::int64_t j = 0; j < 14; ++j)
      for (std::int64_t i = 0; i < 12; ++i)
        p.add(u(rng) * hexagonal.cell_volume(), hexagonal.site(box, {i, j}), Vec<2>(u(rng), u(rng) - 1.0), 1.2 * dx,
              u(rng));
    const auto before = p;
    geometry::LocalVoronoi builder;
    const auto stats = remap_onto_lattice(p, box, hexagonal, builder, RemapParams{});
    INFO("edges " << static_cast<int>(box.edge[0]) << ", " << static_cast<int>(box.edge[1]));
    REQUIRE(p.n_real == before.n_real);
    double worst_m = 0.0, worst_x = 0.0, worst_v = 0.0;
    for (std::size_t a = 0; a < p.n_real; ++a) {
      worst_m = std::max(worst_m, std::abs(p.m[a] / before.m[a] - 1.0));
      worst_x = std::max(worst_x, (p.x[a] - before.x[a]).norm());
      worst_v = std::max(worst_v, (p.v[a] - before.v[a]).norm());
    }
    CHECK(worst_m < 1e-12);
    CHECK(worst_x < 1e-14);
    CHECK(worst_v < 1e-12);
    CHECK(std::abs(stats.kinetic_converted) < 1e-14);
  }
}

TEST_CASE("fuzz: sheared, clustered, near-coincident, collinear and lattice-corner sets", "[regularize]") {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto periodic = box_with(Edge::periodic, Edge::periodic);
  const lattice::Square square{1.0 / 32};
  SECTION("sheared as by Keplerian rotation") {
    for (double shear : {0.1, 0.9, 3.7}) {
      auto p = jittered_gas(32, 0.1, 10, shear);
      check_conserving_remap(p, box_with(Edge::periodic, Edge::reflecting), square);
    }
  }
  SECTION("clustered with empty regions") {
    ParticleSet<2, true> p;
    for (int c = 0; c < 5; ++c) {
      const Vec<2> centre(u(rng), u(rng));
      for (int k = 0; k < 150; ++k) {
        Vec<2> x = centre + 0.05 * Vec<2>(u(rng) - 0.5, u(rng) - 0.5);
        periodic.wrap(x);
        p.add(1e-3, x, Vec<2>(u(rng), u(rng)), 0.03, u(rng));
      }
    }
    check_conserving_remap(p, periodic, square);
  }
  SECTION("near-coincident pairs (1e-9 apart)") {
    auto p = jittered_gas(20, 0.3, 11);
    for (std::size_t a = 0; a + 1 < p.n_real; a += 7) {
      p.x[a + 1] = p.x[a] + Vec<2>(1e-9, 0.3e-9);
      periodic.wrap(p.x[a + 1]);
    }
    check_conserving_remap(p, periodic, lattice::Square{1.0 / 20});
    auto q = jittered_gas(20, 0.3, 11);
    for (std::size_t a = 0; a + 1 < q.n_real; a += 7) q.x[a + 1] = q.x[a] + Vec<2>(1e-9, 0.3e-9);
    check_conserving_remap<2, true, lattice::Square, geometry::BoostVoronoi>(
        q, box_with(Edge::reflecting, Edge::reflecting), lattice::Square{1.0 / 20});
  }
  SECTION("collinear rows and particles on lattice corners") {
    ParticleSet<2, true> p;
    for (int i = 0; i < 64; ++i) p.add(1e-3, Vec<2>(i / 64.0, 0.5), Vec<2>(u(rng), 0.0), 0.05, 1.0);  // one line
    for (int i = 0; i < 32; ++i)
      for (int j = 0; j < 32; j += 5) p.add(1e-3, Vec<2>(i / 32.0, j / 32.0), Vec<2>(0.0, u(rng)), 0.05, 1.0);
    check_conserving_remap(p, box_with(Edge::reflecting, Edge::reflecting), square);
  }
  SECTION("exactly coincident particles are refused") {
    auto p = jittered_gas(10, 0.3, 12);
    p.x[5] = p.x[6];
    geometry::LocalVoronoi builder;
    CHECK_THROWS_WITH(remap_onto_lattice(p, periodic, square, builder, RemapParams{}), Catch::Contains("coincides"));
  }
  SECTION("particles outside the domain are refused") {
    auto p = jittered_gas(10, 0.3, 13);
    p.x[2][0] = -0.25;
    geometry::LocalVoronoi builder;
    CHECK_THROWS_WITH(remap_onto_lattice(p, periodic, square, builder, RemapParams{}),
                      Catch::Contains("outside the domain"));
  }
}

TEST_CASE("open edges: cells closed by discs; nearly empty cells hand their share on", "[regularize]") {
  ParticleSet<2, true> p;
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 400; ++k) {
    const double r = 0.5 + 0.1 * u(rng), phi = 3.14159265 * u(rng);
    p.add(1e-4, Vec<2>(r * std::cos(phi), r * std::sin(phi)), Vec<2>(-std::sin(phi), std::cos(phi)), 0.03, 0.1);
  }
  RemapParams params;
  params.min_fill = 0.2;  // large, so that edge cells are dropped
  auto q = p;
  const auto stats = check_conserving_remap(p, box_with(Edge::open, Edge::open), lattice::Square{0.02}, params);
  CHECK(stats.dropped_cells > 0);
  // the same ring onto hexagons: the candidate range and the side tests hold at open edges too
  const auto hexagonal = check_conserving_remap(q, box_with(Edge::open, Edge::open), lattice::Hexagonal{0.02}, params);
  CHECK(hexagonal.dropped_cells > 0);
  CHECK(hexagonal.n_after > 100);
}

TEST_CASE("a shear interface between rows offset by s Delta exchanges s (1 - s) / 8 of each cell per remap",
          "[regularize]") {
  // Two lattice half-planes sliding past each other (the Kelvin-Helmholtz interface between remaps): the
  // upper rows are offset by s Delta in x. The Voronoi cells of the two interface rows meet along a zigzag,
  // not along the lattice line between them: each cell reaches a triangle of area s (1 - s) / 8 Delta^2
  // into the other row's new cells and gives up as much of its own. The remap thus mixes that fraction of
  // momentum across the interface every time, whatever the flow does between remaps (none at s = 0).
  const int n = 16;
  const double dx = 1.0 / n, U = 1.0;
  for (double s : {0.0, 0.25, 0.5, 0.7}) {
    auto p = test::offset_halves(n, s, [&](double y) { return y > 0.5 ? -U : U; });
    const auto stats = check_conserving_remap(p, box_with(Edge::periodic, Edge::reflecting), lattice::Square{dx});
    REQUIRE(p.n_real == static_cast<std::size_t>(n * n));
    const double f = s * (1.0 - s) / 8.0;
    INFO("s = " << s << ", exchanged fraction " << f);
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const int row = static_cast<int>(std::floor(p.x[a][1] / dx));
      const double expected = row == n / 2 - 1 ? U * (1.0 - 2.0 * f)
                              : row == n / 2   ? -U * (1.0 - 2.0 * f)
                              : row < n / 2    ? U
                                               : -U;
      CHECK(p.m[a] == Approx(dx * dx).epsilon(1e-12));
      CHECK(p.v[a][0] == Approx(expected).margin(1e-12));
      CHECK(std::abs(p.v[a][1]) < 1e-12);
    }
    // per column, the two interface cells lose m U^2 (1 - (1 - 2 f)^2) of kinetic energy to heat
    CHECK(stats.kinetic_converted == Approx(n * dx * dx * U * U * 4.0 * f * (1.0 - f)).margin(1e-14));
  }
}

TEST_CASE("1D remap: a shift by one spacing keeps a profile, half a spacing diffuses most", "[regularize]") {
  auto pulse = [](double shift) {
    ParticleSet<1, true> p;
    const int n = 64;
    const double dx = 1.0 / n;
    for (int i = 0; i < n; ++i) {
      const double m = (i >= 30 && i < 34) ? 2.0 * dx : dx;
      p.add(m, Vec<1>(std::fmod((i + 0.5) * dx + shift * dx, 1.0)), Vec<1>(0.0), 1.4 * dx, 1.0);
    }
    return p;
  };
  Box<1> box;
  box.edge = {Edge::periodic};
  geometry::LocalVoronoi unused;
  auto width_after = [&](double shift, int remaps) {
    auto p = pulse(0.0);
    const double m0 = conservation(p).mass;
    for (int r = 0; r < remaps; ++r) {
      for (auto& x : p.x) {
        x[0] += shift / 64.0;
        box.wrap(x);
      }
      remap_onto_lattice(p, box, lattice::Uniform1D{1.0 / 64}, unused, RemapParams{1.4});
      CHECK(std::abs(conservation(p).mass - m0) / m0 < 1e-14);
    }
    // second central moment of the excess mass over the background, in units of Delta
    double M = 0.0, mean = 0.0, var = 0.0;
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const double excess = p.m[a] - 1.0 / 64;
      M += excess;
      mean += excess * p.x[a][0];
    }
    mean /= M;
    for (std::size_t a = 0; a < p.n_real; ++a) var += (p.m[a] - 1.0 / 64) * std::pow(p.x[a][0] - mean, 2);
    return std::sqrt(var / M) * 64;
  };
  const double w0 = width_after(0.0, 0);
  CHECK(width_after(1.0, 20) == Approx(w0).epsilon(1e-12));
  const double w01 = width_after(0.1, 20), w025 = width_after(0.25, 20), w05 = width_after(0.5, 20);
  CHECK(w01 > w0);
  CHECK(w025 > w01);
  CHECK(w05 > w025);
}

TEST_CASE("open edges: tails lighter than min_mass_ratio join their neighbours, conserving exactly", "[regularize]") {
  // a Gaussian blob whose outer particles carry masses down to 1e-12 of the centre's
  ParticleSet<2, false> p;
  const double dx = 0.02;
  for (int j = -30; j <= 30; ++j)
    for (int i = -30; i <= 30; ++i) {
      const Vec<2> x(i * dx + 0.003 * ((i * 7 + j * 3) % 5), j * dx + 0.002 * ((i * 5 + j) % 7));
      p.add(std::exp(-x.squaredNorm() / 0.02) * dx * dx, x, Vec<2>(-x[1], x[0]), 1.6 * dx);
    }
  const auto open = box_with(Edge::open, Edge::open);
  auto all = p;
  const auto kept_all = check_conserving_remap(all, open, lattice::Square{dx}, RemapParams{1.6, 0.5, 0.75 / 1.6});
  const auto stats = check_conserving_remap(p, open, lattice::Square{dx}, RemapParams{1.6, 0.5, 0.75 / 1.6, 1e-6});
  CHECK(stats.n_after < kept_all.n_after);
  auto light = [](const ParticleSet<2, false>& q) {
    double m_max = 0.0;
    for (std::size_t a = 0; a < q.n_real; ++a) m_max = std::max(m_max, q.m[a]);
    std::size_t n = 0;
    for (std::size_t a = 0; a < q.n_real; ++a) n += q.m[a] < 1e-6 * m_max;
    return n;
  };
  INFO("light particles: " << light(all) << " of " << all.n_real << " without the ratio, " << light(p) << " of "
                           << p.n_real << " with it");
  CHECK(light(p) * 10 < light(all));  // only isolated local maxima of the far tail stay (104 of 1640)
  CHECK(light(p) * 20 < p.n_real);
  // a new cell less than half covered gets no particle: the edge does not creep outwards
  double r_before = 0.0, r_after = 0.0;
  for (std::size_t a = 0; a < all.n_real; ++a) r_after = std::max(r_after, all.x[a].norm());
  for (int k : {-30, 30}) r_before = std::max(r_before, std::hypot(k * dx, k * dx));
  CHECK(r_after < r_before + dx);
}

TEST_CASE("the new particles carry no pressure, rates or frozen flags of the old ones", "[regularize]") {
  auto p = jittered_gas(20, 0.3, 5);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    p.P[a] = p.cs[a] = p.du_dt[a] = 1.0;
    p.dv_dt[a] = Vec<2>(1.0, -1.0);
    p.frozen[a] = 1;
  }
  geometry::LocalVoronoi builder;
  remap_onto_lattice(p, box_with(Edge::periodic, Edge::periodic), lattice::Square{1.0 / 20}, builder, RemapParams{});
  REQUIRE(p.n_real == 400);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    CHECK(p.P[a] == 0.0);
    CHECK(p.cs[a] == 0.0);
    CHECK(p.du_dt[a] == 0.0);
    CHECK(p.dv_dt[a] == Vec<2>::Zero());
    CHECK(p.frozen[a] == 0);
  }
}

TEST_CASE("the remap refuses non-finite, negative and all-zero fields, naming the particle and field", "[remap]") {
  const Box<2> box = box_with(Edge::periodic, Edge::periodic);
  auto refuses = [&](auto spoil, const std::string& expect) {
    auto p = jittered_gas(16, 0.2, 5);
    spoil(p);
    geometry::LocalVoronoi builder;
    INFO(expect);
    CHECK_THROWS_WITH(remap_onto_lattice(p, box, lattice::Square{1.0 / 16}, builder, RemapParams{}),
                      Catch::Contains(expect));
  };
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  // a mass of -inf once sent the hand-on of sparse cells round forever
  refuses([&](auto& p) { p.m[3] = -inf; }, "particle 3: mass must be finite and non-negative");
  refuses([&](auto& p) { p.m[7] = -1e-3; }, "particle 7: mass must be finite and non-negative");
  refuses([&](auto& p) { p.m[0] = nan; }, "particle 0: mass");
  refuses([&](auto& p) { p.v[5] = Vec<2>(nan, 0.0); }, "particle 5: velocity is not finite");
  refuses([&](auto& p) { p.u[9] = inf; }, "particle 9: internal energy must be finite");
  refuses([&](auto& p) { p.x[2] = Vec<2>(inf, 0.5); }, "particle 2: position is not finite");
  refuses(
      [&](auto& p) {
        for (auto& m : p.m) m = 0.0;
      },
      "every mass is zero");
}

TEST_CASE("a far outlier on an open axis costs no more than any other particle: the sums go sparse", "[remap]") {
  // ten million box lengths away along the open axis: 2.6e9 lattice cells between it and the rest, which a dense
  // grid of sums could not hold; the sparse sums hold the cells that receive something, about two per particle
  for (const double far : {1e3, 1e7}) {
    auto p = jittered_gas(16, 0.2, 5);
    p.x[4] = Vec<2>(0.5, far);
    geometry::LocalVoronoi builder;
    regularize::RemapWorkspace<2> ws;
    const auto stats = test::check_conserved(
        p,
        [&](auto& q) {
          return remap_onto_lattice(q, box_with(Edge::periodic, Edge::open), lattice::Square{1.0 / 16}, builder,
                                    RemapParams{}, region::Unbounded{}, &ws);
        },
        true);
    CHECK(ws.sums[0].sparse);
    CHECK(ws.sums[0].size() < 4 * 256);
    CHECK(stats.n_after > 200);
  }
}

TEST_CASE("sparse sums give the dense sums' particles to the bit, both orders, 2D and 3D", "[remap]") {
  auto remap_both = [](auto p, const auto& box, const auto& lattice, auto order) {
    using P = decltype(p);
    constexpr int D = P::dim;
    typename geometry::DefaultCellBuilder<D>::type builder;
    RemapParams dense, sparse;
    sparse.dense_cells_per_particle = 0.0;  // every grid sparse
    auto q = p;
    regularize::RemapWorkspace<D> ws_dense, ws_sparse;
    typename decltype(order)::template Workspace<D> w2_dense, w2_sparse;
    order.remap(p, box, lattice, builder, dense, region::Unbounded{}, ws_dense, w2_dense);
    order.remap(q, box, lattice, builder, sparse, region::Unbounded{}, ws_sparse, w2_sparse);
    CHECK_FALSE(ws_dense.sums[0].sparse);
    CHECK(ws_sparse.sums[0].sparse);
    REQUIRE(p.n_real == q.n_real);
    std::size_t differ = 0;
    for (std::size_t a = 0; a < p.n_real; ++a)
      differ += p.m[a] != q.m[a] || p.x[a] != q.x[a] || p.v[a] != q.v[a] || p.u[a] != q.u[a] || p.h[a] != q.h[a];
    CHECK(differ == 0);
  };
  auto open_2d = jittered_gas(24, 0.3, 8);
  remap_both(open_2d, box_with(Edge::periodic, Edge::open), lattice::Square{1.0 / 24}, regularize::FirstOrder{});
  remap_both(open_2d, box_with(Edge::open, Edge::reflecting), lattice::Square{1.0 / 24}, regularize::SecondOrder{});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<3, true> cloud;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i)
        cloud.add(1.0 + 0.5 * u(rng),
                  Vec<3>(i + 0.5 + 0.3 * u(rng), j + 0.5 + 0.3 * u(rng), k + 0.5 + 0.3 * u(rng)) / 8.0,
                  Vec<3>(u(rng), u(rng), u(rng)), 0.15, 1.0 + 0.5 * u(rng));
  Box<3> box3;
  box3.edge = {Edge::periodic, Edge::reflecting, Edge::open};
  remap_both(cloud, box3, lattice::Cubic{1.0 / 8}, regularize::FirstOrder{});
  remap_both(cloud, box3, lattice::Cubic{1.0 / 8}, regularize::SecondOrder{});
}
