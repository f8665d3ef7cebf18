// The particle set's own operations: moving a subset out and back, every field and identity kept.
#include "rsph/core/particle_set.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

TEST_CASE("particle set: take_if moves a subset out with its fields and identities, append brings it back", "[core]") {
  ParticleSet<2, true> p;
  for (int a = 0; a < 10; ++a) {
    p.add(1.0 + a, Vec<2>(a, -a), Vec<2>(0.5 * a, 1.0), 0.1 * (a + 1), 2.0 * a);
    p.frozen[static_cast<std::size_t>(a)] = a % 3 == 0;
    p.dv_dt[static_cast<std::size_t>(a)] = Vec<2>(a, a);
  }
  p.add_ghost(1, Vec<2>(9.0, 9.0), Vec<2>::Zero());
  const auto taken = p.take_if([&](std::size_t a) { return p.frozen[a] != 0; });
  REQUIRE(taken.n_real == 4);  // 0, 3, 6, 9
  REQUIRE(p.n_real == 6);
  CHECK(p.n_ghost() == 0);
  for (std::size_t k = 0; k < 4; ++k) {
    const auto a = 3 * k;
    CHECK(taken.id[k] == a);
    CHECK(taken.m[k] == 1.0 + static_cast<double>(a));
    CHECK(taken.u[k] == 2.0 * static_cast<double>(a));
    CHECK(taken.dv_dt[k] == Vec<2>(static_cast<double>(a), static_cast<double>(a)));
    CHECK(taken.frozen[k] == 1);
  }
  CHECK(p.id[0] == 1);  // the rest in order
  CHECK(p.id[5] == 8);
  p.append(taken);
  REQUIRE(p.n_real == 10);
  CHECK(p.id[6] == 0);
  CHECK(p.id[9] == 9);
  CHECK(p.h[9] == Approx(1.0));
  CHECK(p.frozen[9] == 1);
  CHECK(p.next_id == 10);
}
