#pragma once
// The particle sets the remap benchmarks and the remap cost count share: a square lattice jittered or sheared
// as by Keplerian rotation, in a box periodic in x and walled in y.
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

}  // namespace rsph::bench
