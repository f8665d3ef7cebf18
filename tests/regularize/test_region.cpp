// Closing regions: an annulus keeps a rotating disk's edges where they are across regularizations.
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

using namespace rsph;

namespace {

/// Particles on a jittered square lattice inside r_in <= r <= r_out, turned by `angle`.
ParticleSet<2, true> jittered_annulus(double r_in, double r_out, double dx, double angle, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  ParticleSet<2, true> p;
  const auto n = static_cast<int>(r_out / dx) + 1;
  const double c = std::cos(angle), s = std::sin(angle);
  for (int j = -n; j <= n; ++j)
    for (int i = -n; i <= n; ++i) {
      const Vec<2> y((i + u(rng)) * dx, (j + u(rng)) * dx);
      const Vec<2> x(c * y[0] - s * y[1], s * y[0] + c * y[1]);
      if (x.norm() < r_in || x.norm() > r_out) continue;
      p.add(dx * dx, x, Vec<2>(-x[1], x[0]), 1.4 * dx, 1.0);
    }
  return p;
}

Box<2> open_box() {
  Box<2> b;
  b.lo = Vec<2>(-3.0, -3.0);
  b.hi = Vec<2>(3.0, 3.0);
  b.edge = {Edge::open, Edge::open};
  return b;
}

}  // namespace

TEST_CASE("annulus region: the tangent cuts keep a cell's inner side and spare particles beyond an edge",
          "[regularize][region]") {
  const region::Annulus annulus{0.5, 2.0};
  geometry::ConvexPolygon square;
  for (const auto& v : {Vec<2>(-0.1, -0.1), Vec<2>(0.1, -0.1), Vec<2>(0.1, 0.1), Vec<2>(-0.1, 0.1)}) square.push(v);
  auto at_outer = square;
  annulus.clip(Vec<2>(1.95, 0.0), at_outer);  // the outer tangent x = 2 cuts 0.05 off the right side
  CHECK(geometry::area(at_outer) == Approx(0.2 * 0.15).epsilon(1e-12));
  auto at_inner = square;
  annulus.clip(Vec<2>(0.0, -0.55), at_inner);  // the inner tangent y = -0.5 keeps y <= -0.5
  CHECK(geometry::area(at_inner) == Approx(0.2 * 0.15).epsilon(1e-12));
  auto beyond = square;
  annulus.clip(Vec<2>(2.2, 0.0), beyond);  // beyond the edge: cut at its own radius, half kept
  CHECK(geometry::area(beyond) == Approx(0.2 * 0.1).epsilon(1e-12));
}

TEST_CASE("annulus region: repeated remaps of a turning disk conserve mass exactly and keep its edges",
          "[regularize][region]") {
  const double r_in = 0.5, r_out = 2.0, dx = 0.05;
  const region::Annulus annulus{r_in, r_out};
  const regularize::RemapParams params{1.4, 0.5, 0.75 / 1.4, 0.0};
  geometry::LocalVoronoi builder;
  auto run = [&](auto region_policy) {
    auto p = jittered_annulus(r_in, r_out, dx, 0.0, 7);
    const std::size_t n0 = p.n_real;
    const double mass0 = conservation(p).mass;
    double max_mass_error = 0.0, r_min = 1e9, r_max = 0.0;
    for (int k = 0; k < 10; ++k) {
      // turn the lattice-ordered set off the lattice, as an orbit does between regularizations
      const double c = std::cos(0.013 * (k + 1)), s = std::sin(0.013 * (k + 1));
      for (std::size_t a = 0; a < p.n_real; ++a)
        p.x[a] = Vec<2>(c * p.x[a][0] - s * p.x[a][1], s * p.x[a][0] + c * p.x[a][1]);
      regularize::remap_onto_lattice(p, open_box(), lattice::Square{dx}, builder, params, region_policy);
      max_mass_error = std::max(max_mass_error, std::abs(conservation(p).mass - mass0) / mass0);
    }
    for (std::size_t a = 0; a < p.n_real; ++a) {
      r_min = std::min(r_min, p.x[a].norm());
      r_max = std::max(r_max, p.x[a].norm());
    }
    return std::tuple{max_mass_error, static_cast<double>(p.n_real) / static_cast<double>(n0), r_min, r_max};
  };
  const auto [err_a, growth_a, r_min_a, r_max_a] = run(annulus);
  const auto [err_u, growth_u, r_min_u, r_max_u] = run(region::Unbounded{});
  INFO("annulus: count x" << growth_a << ", r in [" << r_min_a << ", " << r_max_a << "]; closing disc only: x"
                          << growth_u << ", r in [" << r_min_u << ", " << r_max_u << "]");
  CHECK(err_a < 1e-13);
  CHECK(err_u < 1e-13);
  // new particles sit where their cells are at least half inside the annulus
  CHECK(r_min_a > r_in - 0.5 * dx);
  CHECK(r_max_a < r_out + 0.5 * dx);
  CHECK(std::abs(growth_a - 1.0) < 0.01);
  // without the region the edges creep outwards by a fraction of a cell per remap
  CHECK(growth_u > growth_a + 0.01);
}
