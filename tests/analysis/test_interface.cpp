#include "rsph/analysis/interface.hpp"
#include "rsph/kernel/cubic_spline.hpp"
#include "rsph/kernel/lattice_sum.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <numbers>

using namespace rsph;
using K = kernel::CubicSpline;

namespace {

/// A square lattice over [0, 1] x [0, 0.5] whose density is 10 where `dense` holds and 1 elsewhere.
ParticleSet<2, false> two_phases(int n, const std::function<bool(const Vec<2>&)>& dense) {
  const double dx = 1.0 / n, bias = kernel::lattice_sum<K, 2>(1.2);
  ParticleSet<2, false> p;
  for (int j = 0; j < n / 2; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec<2> x((i + 0.5) * dx, (j + 0.5) * dx);
      p.add((dense(x) ? 10.0 : 1.0) * dx * dx / bias, x, Vec<2>::Zero(), 1.2 * dx);
    }
  return p;
}

Box<2> kh_box() {
  Box<2> b;
  b.hi = Vec<2>(1.0, 0.5);
  b.edge = {Edge::periodic, Edge::reflecting};
  return b;
}

}  // namespace

TEST_CASE("interpolated density: images of periodic and reflecting faces keep a uniform lattice uniform",
          "[analysis]") {
  // With its images the lattice fills the plane (the walls lie on lattice lines), so a point near a face
  // sees what the point a whole number of spacings inside sees.
  const auto p = two_phases(64, [](const Vec<2>&) { return true; });
  const std::vector<Vec<2>> at{{0.0, 0.0}, {1.0, 0.25}, {0.5, 0.5}, {1e-3, 0.499}, {0.3 + 1.0 / 64, 0.21}};
  const std::vector<Vec<2>> inside{{0.5, 0.25}, {0.5, 0.25}, {0.5, 0.25}, {0.5 + 1e-3, 0.249}, {0.3, 0.21}};
  const auto near_faces = analysis::interpolate_density<K>(p, at, kh_box());
  const auto interior = analysis::interpolate_density<K>(p, inside, kh_box());
  for (std::size_t i = 0; i < at.size(); ++i) {
    CHECK(near_faces[i] == Approx(interior[i]).epsilon(1e-12));
    CHECK(near_faces[i] == Approx(10.0).epsilon(5e-3));  // off the sites the lattice sum ripples a little
  }
  // without images the faces see half a kernel or less
  const auto open = analysis::interpolate_density<K>(p, at);
  for (std::size_t i = 0; i < 4; ++i) CHECK(open[i] < 0.6 * near_faces[i]);
}

TEST_CASE("interface folds: a wavy interface is crossed once per column, a curled-over one three times", "[analysis]") {
  const double k = 6.0 * std::numbers::pi;
  auto wavy = [&](const Vec<2>& x) { return x[1] > 0.25 + 0.03 * std::sin(k * x[0]); };
  const auto flat = analysis::interface_folds<K>(two_phases(256, wavy), kh_box(), std::sqrt(10.0), 1.0 / 1024);
  CHECK(flat.columns == 1024);
  CHECK(flat.rows == 512);
  CHECK(flat.overturned_fraction == 0.0);
  CHECK(flat.mean_crossings == 1.0);
  // a dense tongue of radius 0.04 below the interface: the 8 % of the columns through it cross three times
  auto tongue = [&](const Vec<2>& x) { return wavy(x) || (x - Vec<2>(0.5, 0.15)).norm() < 0.04; };
  const auto folded = analysis::interface_folds<K>(two_phases(256, tongue), kh_box(), std::sqrt(10.0), 1.0 / 1024);
  CHECK(folded.overturned_fraction == Approx(0.08).margin(0.005));
  CHECK(folded.mean_crossings == Approx(1.0 + 2.0 * folded.overturned_fraction).margin(1e-12));
  // the walls' mirror images: a level just below the dense phase's density is crossed nowhere
  const auto uniform =
      analysis::interface_folds<K>(two_phases(128, [](const Vec<2>&) { return true; }), kh_box(), 9.9, 1.0 / 256);
  CHECK(uniform.mean_crossings == 0.0);
  CHECK_THROWS_WITH(analysis::interface_folds<K>(two_phases(16, wavy), kh_box(), 3.0, 0.0),
                    Catch::Contains("spacing must be positive"));
}
