#pragma once
// The check every remap test makes: mass, momentum and total energy (or, without u, the kinetic energy the
// remap reports as dissipated) the same to 1e-13 before and after, every new particle with positive mass and
// finite, non-negative u.
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <cmath>

namespace rsph::test {

/// Remaps p with remap() and checks conservation; `heats_only`: the remap may only turn kinetic energy into
/// heat (first order: averaging), never the reverse.
template <int D, bool E, class Remap>
regularize::RemapStats check_conserved(ParticleSet<D, E>& p, Remap&& remap, bool heats_only) {
  const auto before = conservation(p);
  double scale = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) scale += p.m[a] * p.v[a].norm();
  const regularize::RemapStats stats = remap(p);
  const auto after = conservation(p);
  CHECK(stats.max_volume_mismatch < 1e-12);
  CHECK(std::abs(after.mass - before.mass) / before.mass < 1e-13);
  CHECK((after.momentum - before.momentum).norm() <= 1e-13 * scale);
  if constexpr (E) {
    CHECK(std::abs(after.total_energy() - before.total_energy()) / before.total_energy() < 1e-13);
    if (heats_only) CHECK(after.thermal >= before.thermal - 1e-13 * before.total_energy());
  } else {
    CHECK(stats.kinetic_converted == Approx(before.kinetic - after.kinetic).margin(1e-14));
  }
  if (heats_only) CHECK(stats.kinetic_converted >= -1e-15);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    REQUIRE(p.m[a] > 0.0);
    REQUIRE(p.v[a].allFinite());
    if constexpr (E) REQUIRE(p.u[a] >= 0.0);
  }
  return stats;
}

}  // namespace rsph::test
