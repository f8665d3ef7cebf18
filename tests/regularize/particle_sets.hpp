#pragma once
// Particle sets the regularization tests remap: a jittered, optionally sheared periodic gas.
#include "rsph/rsph.hpp"

#include <cmath>
#include <random>

namespace rsph::test {

template <bool E = true>
ParticleSet<2, E> jittered_gas(int n, double jitter, unsigned seed, double shear = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<2, E> p;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double x = (i + 0.5 + jitter * u(rng)) * dx + shear * ((j + 0.5) * dx - 0.5);
      x -= std::floor(x);
      p.add(dx * dx * (1.0 + 0.3 * u(rng)), Vec<2>(x, (j + 0.5 + jitter * u(rng)) * dx), Vec<2>(u(rng), 0.5 * u(rng)),
            1.2 * dx, 1.0 + 0.5 * u(rng));
    }
  return p;
}

/// An n x n lattice in the unit square whose upper half is offset by s Delta in x (periodic), each particle
/// of mass Delta^2, u = 1, h = 1.2 Delta and velocity (vx(y), 0): two half-planes sliding past each other.
template <class Vx>
ParticleSet<2, true> offset_halves(int n, double s, Vx&& vx) {
  ParticleSet<2, true> p;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      Vec<2> x((i + 0.5 + (j >= n / 2 ? s : 0.0)) * dx, (j + 0.5) * dx);
      x[0] = std::fmod(x[0], 1.0);
      p.add(dx * dx, x, Vec<2>(vx(x[1]), 0.0), 1.2 * dx, 1.0);
    }
  return p;
}

inline Box<2> box_with(Edge ex, Edge ey) {
  Box<2> b;
  b.edge = {ex, ey};
  return b;
}

}  // namespace rsph::test
