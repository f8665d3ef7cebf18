// Fuzz cases for both Voronoi builders and both remaps: random, clustered, collinear, nearly coincident,
// lattice-corner and far-outlier sets with fixed seeds, in periodic, walled, open and mixed boxes. Each builder's
// cells tile the domain (and on small sets equal the brute-force cells); each remap conserves mass, momentum and
// energy and gives finite particles, or refuses the set with an error that says why. Never a crash, a hang or a
// NaN. RSPH_FUZZ_CASES sets how many cases (default 3000, half as many in 3D; tens of thousands for a long run).
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <numeric>
#include <random>
#include <string>

#include "voronoi3d_sets.hpp"

using namespace rsph;
using geometry::Point;

namespace {

const char* const kinds[] = {"uniform", "clustered", "collinear", "near-coincident", "lattice corners", "far outlier"};

struct Case {
  std::vector<Point> x;
  Box<2> box;
  std::string what;
};

/// The set for `seed`: its kind and box cycle with the seed; sizes from 2 to about 200.
Case make_case(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int kind = static_cast<int>(seed % 6);
  const Edge edges[5][2] = {{Edge::periodic, Edge::periodic},
                            {Edge::reflecting, Edge::reflecting},
                            {Edge::open, Edge::open},
                            {Edge::periodic, Edge::reflecting},
                            {Edge::open, Edge::periodic}};
  Case c;
  const auto& e = edges[(seed / 6) % 5];
  c.box.edge = {e[0], e[1]};
  const int n = 2 + static_cast<int>(std::uniform_int_distribution<int>(0, 198)(rng));
  auto inside = [](double v) { return std::clamp(v, 1e-9, 1.0 - 1e-9); };
  switch (kind) {
    case 0:
      for (int i = 0; i < n; ++i) c.x.emplace_back(u(rng), u(rng));
      break;
    case 1: {  // a tight cluster, its width 1e-4 to 1e-1
      const double w = std::pow(10.0, -1.0 - 3.0 * u(rng));
      std::normal_distribution<double> g(0.0, w);
      const Point centre(0.2 + 0.6 * u(rng), 0.2 + 0.6 * u(rng));
      for (int i = 0; i < n; ++i) c.x.emplace_back(inside(centre.x() + g(rng)), inside(centre.y() + g(rng)));
      break;
    }
    case 2: {  // on one line, across or along an axis, a few with a hair of noise
      const double y0 = u(rng), slope = seed % 2 ? 0.0 : u(rng) - 0.5;
      for (int i = 0; i < n; ++i) {
        const double t = (i + 0.5) / n;
        c.x.emplace_back(t, inside(y0 + slope * (t - 0.5) + (i % 7 == 0 ? 1e-7 * u(rng) : 0.0)));
      }
      break;
    }
    case 3:  // pairs 1e-9 to 1e-11 of a spacing apart
      for (int i = 0; i < n; i += 2) {
        const Point p(u(rng), u(rng));
        c.x.push_back(p);
        const double sep = std::pow(10.0, -9.0 - 2.0 * u(rng)) / std::sqrt(double(n));
        c.x.emplace_back(inside(p.x() + sep), p.y());
      }
      break;
    case 4: {  // on the nodes of a lattice, its corners and edges included
      const int m = 2 + static_cast<int>(std::sqrt(double(n)));
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i)
          if (u(rng) < 0.7) c.x.emplace_back(inside(double(i) / (m - 1)), inside(double(j) / (m - 1)));
      if (c.x.size() < 2) c.x = {Point(0.25, 0.25), Point(0.75, 0.75)};
      break;
    }
    default: {  // a cluster and a few outliers: far away across open edges, in the corners otherwise
      std::normal_distribution<double> g(0.3, 0.01);
      for (int i = 0; i < n; ++i) c.x.emplace_back(inside(g(rng)), inside(g(rng)));
      const bool open = c.box.edge[0] == Edge::open;
      c.x.emplace_back(open ? 40.0 : 0.999, 0.999);
      c.x.emplace_back(0.001, c.box.edge[1] == Edge::open ? -25.0 : 0.998);
      break;
    }
  }
  c.what = std::string(kinds[kind]) + ", " + std::to_string(c.x.size()) + " particles, seed " + std::to_string(seed);
  return c;
}

/// O(N^2) cells of a box without open edges: each cut by every other point's bisector, images included.
std::vector<double> brute_force_areas(const std::vector<Point>& x, const Box<2>& box) {
  std::vector<double> out;
  for (std::size_t a = 0; a < x.size(); ++a) {
    geometry::ConvexPolygon cell = geometry::detail::initial_cell(x[a], box, 1.0, 0.0);
    for (std::size_t b = 0; b < x.size(); ++b)
      for (int ix = -1; ix <= 1; ++ix)
        for (int iy = -1; iy <= 1; ++iy) {
          if ((ix != 0 && !box.periodic(0)) || (iy != 0 && !box.periodic(1))) continue;
          if (b == a && ix == 0 && iy == 0) continue;
          const Point d = x[b] + Point(ix * box.size()[0], iy * box.size()[1]) - x[a];
          geometry::clip_halfplane(cell, d, 0.5 * d.squaredNorm());
        }
    out.push_back(geometry::area(cell));
  }
  return out;
}

unsigned fuzz_cases() {
  const char* env = std::getenv("RSPH_FUZZ_CASES");
  return env ? static_cast<unsigned>(std::strtoul(env, nullptr, 10)) : 3000u;
}

/// Builds the cells with both builders, or sees both refuse the set as input; returns whether they built.
bool check_cells(const Case& c) {
  const bool closed = c.box.edge[0] != Edge::open && c.box.edge[1] != Edge::open;
  const std::vector<double> closing(c.x.size(), closed ? 0.0 : 0.05);
  std::vector<double> local, boost;
  std::string refused;  // coincident sites, or a cell of more sides than a polygon holds (nearly collinear sets)
  try {
    geometry::LocalVoronoi lv;
    local = geometry::cell_areas(lv, c.x, c.box, closing);
  } catch (const InputError& e) {
    refused = e.what();
  } catch (const NumericalError& e) {
    refused = e.what();
  }
  if (!refused.empty()) {
    INFO(refused);
    CHECK(refused.size() > 20);
    // Boost cuts by the true neighbours alone, so it builds some nearly collinear sets whose intermediate cells
    // outgrow the polygon in the local builder's cuts; where it builds, its cells tile the domain.
    geometry::BoostVoronoi bv;
    try {
      const auto boost = geometry::cell_areas(bv, c.x, c.box, closing);
      if (closed) CHECK(std::abs(std::accumulate(boost.begin(), boost.end(), 0.0) - c.box.volume()) < 1e-8);
    } catch (const InputError&) {
    } catch (const NumericalError&) {
    }
    return false;
  }
  geometry::BoostVoronoi bv;
  try {
    boost = geometry::cell_areas(bv, c.x, c.box, closing);
  } catch (const NumericalError& e) {  // the same limit met in another order of cuts
    CHECK_THAT(e.what(), Catch::Contains("more than 64 vertices"));
    return false;
  }
  double worst = 0.0;
  for (std::size_t a = 0; a < c.x.size(); ++a) {
    REQUIRE(std::isfinite(local[a]));
    REQUIRE(local[a] > 0.0);
    worst = std::max(worst, std::abs(local[a] - boost[a]) / local[a]);
  }
  CHECK(worst < 1e-8);  // round-off on tiny cells of a tight cluster; a missed neighbour is of order 1
  if (closed) {
    const double domain = c.box.volume();
    // 1e-8: sites 2e-9 apart across a periodic face (lattice corners) leave sliver cells good to ~1e-9, as
    // positions known to 1e-16 give; a missed neighbour costs a whole cell
    CHECK(std::abs(std::accumulate(local.begin(), local.end(), 0.0) - domain) < 1e-8 * domain);
    if (c.x.size() <= 64) {
      const auto oracle = brute_force_areas(c.x, c.box);
      double off = 0.0;
      for (std::size_t a = 0; a < c.x.size(); ++a) off = std::max(off, std::abs(local[a] - oracle[a]) / oracle[a]);
      CHECK(off < 1e-9);
    }
  }
  return true;
}

/// The set as gas with random masses, velocities and energies.
ParticleSet<2, true> gas_on(const Case& c, unsigned seed) {
  std::mt19937_64 rng(seed + 1000003u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ParticleSet<2, true> p;
  for (const auto& x : c.x) p.add(0.5 + u(rng), x, Vec<2>(u(rng) - 0.5, u(rng) - 0.5), 0.05, 0.1 + u(rng));
  return p;
}

/// Remaps the gas onto `lattice` at first or second order: conserved to 1e-12 and finite, or refused by an
/// error that says why.
template <class Order, class Lattice, int D>
void check_remap(ParticleSet<D, true> p, const Box<D>& box, const Lattice& lattice) {
  const auto before = conservation(p);
  double scale = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) scale += p.m[a] * p.v[a].norm();
  regularize::LatticeRegularizer<Lattice, schedule::EveryNSteps, typename geometry::DefaultCellBuilder<D>::type,
                                 region::Unbounded, Order>
      reg(lattice, {}, {.remap = {1.2}});
  std::string refused;
  try {
    reg.remap(p, box, StepInfo{});
  } catch (const InputError& e) {
    refused = e.what();
  } catch (const NumericalError& e) {
    refused = e.what();
  }
  if (!refused.empty()) {  // refused, saying why
    INFO(refused);
    CHECK(refused.size() > 20);
    return;
  }
  const auto after = conservation(p);
  REQUIRE(p.n_real > 0);
  CHECK(std::abs(after.mass - before.mass) <= 1e-12 * before.mass);
  CHECK((after.momentum - before.momentum).norm() <= 1e-12 * scale);
  CHECK(std::abs(after.total_energy() - before.total_energy()) <= 1e-12 * before.total_energy());
  for (std::size_t a = 0; a < p.n_real; ++a) {
    REQUIRE(p.m[a] > 0.0);
    REQUIRE(p.x[a].allFinite());
    REQUIRE(p.v[a].allFinite());
    REQUIRE(std::isfinite(p.u[a]));
    REQUIRE(p.u[a] >= 0.0);
  }
}

}  // namespace

TEST_CASE("fuzz: both Voronoi builders and both remaps on hostile sets", "[fuzz][voronoi][regularize]") {
  const unsigned n = fuzz_cases();
  unsigned built = 0, remapped = 0;
  for (unsigned seed = 0; seed < n; ++seed) {
    const Case c = make_case(seed);
    INFO(c.what << ", edges " << int(c.box.edge[0]) << "," << int(c.box.edge[1]));
    if (!check_cells(c)) continue;
    ++built;
    if (seed % 3 != 0) continue;  // the remaps on a third of the cases (each builds the cells again)
    const double dx = 1.0 / std::max(4.0, std::round(std::sqrt(double(c.x.size()))));
    check_remap<regularize::FirstOrder>(gas_on(c, seed), c.box, lattice::Square{dx});
    check_remap<regularize::SecondOrder>(gas_on(c, seed), c.box, lattice::Square{dx});
    ++remapped;
  }
  CHECK(built > n * 3 / 4);  // refusals are the exception: coincident sites, nearly collinear sets
  CHECK(remapped > 0);
}

// The 3D half: the same kinds of set (uniform, clustered, on a line or a few planes, nearly coincident pairs,
// lattice nodes, far outliers) in periodic, walled, open and mixed boxes, for LocalVoronoi3 and the 3D remaps
// of both orders. Half as many cases as the 2D half.
namespace {

using geometry::Point3;

struct Case3 {
  std::vector<Point3> x;
  Box<3> box;
  std::string what;
};

const char* const kinds3[] = {"uniform",         "clustered",     "collinear or coplanar",
                              "near-coincident", "lattice nodes", "far outlier"};

Case3 make_case3(unsigned seed) {
  std::mt19937_64 rng(seed + 7777u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int kind = static_cast<int>(seed % 6);
  const Edge edges[5][3] = {{Edge::periodic, Edge::periodic, Edge::periodic},
                            {Edge::reflecting, Edge::reflecting, Edge::reflecting},
                            {Edge::open, Edge::open, Edge::open},
                            {Edge::periodic, Edge::reflecting, Edge::open},
                            {Edge::open, Edge::periodic, Edge::periodic}};
  Case3 c;
  const auto& e = edges[(seed / 6) % 5];
  c.box.edge = {e[0], e[1], e[2]};
  const int n = 2 + static_cast<int>(std::uniform_int_distribution<int>(0, 148)(rng));
  auto inside = [](Point3 p) { return p.cwiseMax(Point3::Constant(1e-9)).cwiseMin(Point3::Constant(1.0 - 1e-9)); };
  switch (kind) {
    case 0:
      for (int i = 0; i < n; ++i) c.x.emplace_back(u(rng), u(rng), u(rng));
      break;
    case 1: {  // a tight cluster, its width 1e-4 to 1e-1
      std::normal_distribution<double> g(0.0, std::pow(10.0, -1.0 - 3.0 * u(rng)));
      const Point3 centre(0.2 + 0.6 * u(rng), 0.2 + 0.6 * u(rng), 0.2 + 0.6 * u(rng));
      for (int i = 0; i < n; ++i) c.x.push_back(inside(centre + Point3(g(rng), g(rng), g(rng))));
      break;
    }
    case 2: {  // on one line (odd seeds) or on two to four planes z = const, a few with a hair of noise
      const int planes = 2 + static_cast<int>(seed / 30 % 3);
      for (int i = 0; i < n; ++i) {
        const double t = (i + 0.5) / n, hair = i % 7 == 0 ? 1e-7 * u(rng) : 0.0;
        if (seed % 2)
          c.x.push_back(inside(Point3(t, 0.3 + 0.2 * t + hair, 0.6)));
        else
          c.x.push_back(inside(Point3(u(rng), u(rng), (0.5 + i % planes) / planes + hair)));
      }
      break;
    }
    case 3:  // pairs 1e-9 to 1e-11 of a spacing apart
      for (int i = 0; i < n; i += 2) {
        const Point3 p(u(rng), u(rng), u(rng));
        c.x.push_back(p);
        const double sep = std::pow(10.0, -9.0 - 2.0 * u(rng)) / std::cbrt(double(n));
        c.x.push_back(inside(p + Point3(sep, 0.0, 0.0)));
      }
      break;
    case 4: {  // on the nodes of a lattice, its corners, edges and faces included
      const int m = 2 + static_cast<int>(std::cbrt(double(n)));
      for (int k = 0; k < m; ++k)
        for (int j = 0; j < m; ++j)
          for (int i = 0; i < m; ++i)
            if (u(rng) < 0.7) c.x.push_back(inside(Point3(i, j, k) / (m - 1)));
      if (c.x.size() < 2) c.x = {Point3::Constant(0.25), Point3::Constant(0.75)};
      break;
    }
    default: {  // a cluster and a few outliers: far away across open edges, in the corners otherwise
      std::normal_distribution<double> g(0.3, 0.01);
      for (int i = 0; i < n; ++i) c.x.push_back(inside(Point3(g(rng), g(rng), g(rng))));
      c.x.emplace_back(c.box.edge[0] == Edge::open ? 40.0 : 0.999, 0.999, 0.5);
      c.x.emplace_back(0.001, 0.5, c.box.edge[2] == Edge::open ? -25.0 : 0.998);
      break;
    }
  }
  c.what = std::string(kinds3[kind]) + ", " + std::to_string(c.x.size()) + " particles, seed " + std::to_string(seed);
  return c;
}

bool closed3(const Box<3>& box) {
  return box.edge[0] != Edge::open && box.edge[1] != Edge::open && box.edge[2] != Edge::open;
}

/// Builds the 3D cells: finite and positive, tiling a closed box, equal to the brute-force cells on small sets;
/// or the set refused with an error that says why. Returns whether they were built.
bool check_cells3(const Case3& c) {
  const std::vector<double> closing(c.x.size(), closed3(c.box) ? 0.0 : 0.05);
  std::vector<double> volumes;
  try {
    geometry::LocalVoronoi3 builder;
    volumes = geometry::cell_volumes(builder, c.x, c.box, closing);
  } catch (const InputError& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).size() > 20);
    return false;
  }
  for (double v : volumes) {
    REQUIRE(std::isfinite(v));
    REQUIRE(v > 0.0);
  }
  if (closed3(c.box)) {
    const double domain = c.box.volume();
    CHECK(std::abs(std::accumulate(volumes.begin(), volumes.end(), 0.0) - domain) < 1e-8 * domain);
  }
  if (c.x.size() <= 40) {
    double off = 0.0;
    for (std::size_t a = 0; a < c.x.size(); ++a) {
      const double oracle = geometry::volume(test::brute_force_cell(c.x, c.box, a, closing[a]));
      off = std::max(off, std::abs(volumes[a] - oracle) / oracle);
    }
    CHECK(off < 1e-9);
  }
  return true;
}

/// The 3D set as gas with random masses, velocities and energies.
ParticleSet<3, true> gas_on(const Case3& c, unsigned seed) {
  std::mt19937_64 rng(seed + 1000003u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ParticleSet<3, true> p;
  for (const auto& x : c.x)
    p.add(0.5 + u(rng), x, Vec<3>(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5), 0.05, 0.1 + u(rng));
  return p;
}

}  // namespace

TEST_CASE("fuzz: the 3D Voronoi builder and both 3D remaps on hostile sets", "[fuzz][geometry][3d]") {
  const unsigned n = fuzz_cases() / 2;
  unsigned built = 0, remapped = 0;
  for (unsigned seed = 0; seed < n; ++seed) {
    const Case3 c = make_case3(seed);
    INFO(c.what << ", edges " << int(c.box.edge[0]) << "," << int(c.box.edge[1]) << "," << int(c.box.edge[2]));
    if (!check_cells3(c)) continue;
    ++built;
    if (seed % 3 != 0) continue;
    const double dx = 1.0 / std::max(3.0, std::round(std::cbrt(double(c.x.size()))));
    check_remap<regularize::FirstOrder>(gas_on(c, seed), c.box, lattice::Cubic{dx});
    check_remap<regularize::SecondOrder>(gas_on(c, seed), c.box, lattice::Cubic{dx});
    ++remapped;
  }
  CHECK(built > n * 3 / 4);
  CHECK(remapped > 0);
}
