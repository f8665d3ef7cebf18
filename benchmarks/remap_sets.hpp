#pragma once
// The particle sets the remap benchmarks and the remap cost count share: a square lattice jittered or sheared
// as by Keplerian rotation, in a box periodic in x and walled in y; in 3D a cubic lattice jittered, or moved
// by a shearing velocity field for one step, in a box periodic in x and y and walled in z.
#include "rsph/rsph.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

namespace rsph::bench {

enum Layout { jittered = 0, sheared = 1 };

/// A square lattice of about n_particles, jittered by up to +-jitter spacings per axis or sheared.
inline ParticleSet<2, true> make_set(std::int64_t n_particles, int layout, double jitter = 0.3) {
  const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n_particles))));
  const double dx = 1.0 / n;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.3, 0.3), unit(-1.0, 1.0);
  ParticleSet<2, true> p;
  p.reserve(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j) {
    const double y = (j + 0.5) * dx;
    // Keplerian-like shear: rows slide by an amount that grows with y (several spacings between rows)
    const double shift = layout == sheared ? 7.3 * y * y : 0.0;
    for (int i = 0; i < n; ++i) {
      double x = (i + 0.5) * dx + shift + (layout == jittered ? jitter * unit(rng) * dx : 0.0);
      x -= std::floor(x);
      p.add(dx * dx, Vec<2>(x, std::clamp(y + (layout == jittered ? jitter * unit(rng) * dx : 0.0), 0.0, 1.0)),
            Vec<2>(u(rng), u(rng)), 1.2 * dx, 1.0);
    }
  }
  return p;
}

inline Box<2> domain() {
  Box<2> b;
  b.edge = {Edge::periodic, Edge::reflecting};
  return b;
}

inline double spacing_of(const ParticleSet<2, true>& p) {
  return 1.0 / std::lround(std::sqrt(static_cast<double>(p.n_real)));
}

/// A cubic lattice of about n_particles in the unit cube: jittered by up to +-0.3 spacings per axis, or moved
/// for one step's worth of motion by the shearing field v = (sin 2 pi z, sin 2 pi x, 0), the step's largest
/// displacement 0.3 spacings (a Courant number of 0.3 in units of the spacing).
inline ParticleSet<3, true> make_set3(std::int64_t n_particles, int layout) {
  const int n = static_cast<int>(std::lround(std::cbrt(static_cast<double>(n_particles))));
  const double dx = 1.0 / n;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.3, 0.3), unit(-1.0, 1.0);
  ParticleSet<3, true> p;
  p.reserve(static_cast<std::size_t>(n) * n * n);
  constexpr double two_pi = 6.283185307179586;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        Vec<3> x((i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx);
        if (layout == jittered) {
          x += 0.3 * dx * Vec<3>(unit(rng), unit(rng), unit(rng));
          x[2] = std::clamp(x[2], 0.0, 1.0);
        } else {
          x += 0.3 * dx * Vec<3>(std::sin(two_pi * x[2]), std::sin(two_pi * x[0]), 0.0);
        }
        for (int a = 0; a < 2; ++a) x[a] -= std::floor(x[a]);
        p.add(dx * dx * dx, x, Vec<3>(u(rng), u(rng), u(rng)), 1.2 * dx, 1.0);
      }
  return p;
}

inline Box<3> domain3() {
  Box<3> b;
  b.edge = {Edge::periodic, Edge::periodic, Edge::reflecting};
  return b;
}

inline double spacing_of(const ParticleSet<3, true>& p) {
  return 1.0 / std::lround(std::cbrt(static_cast<double>(p.n_real)));
}

}  // namespace rsph::bench
