#pragma once
// Frozen particles: flagged in ParticleSet::frozen, they take part in every sum but are not
// integrated; their x and v follow a prescribed motion (the Keplerian boundary zones of §5).
#include "rsph/core/dimension.hpp"

#include <cstddef>
#include <utility>

namespace rsph::boundary {

/// Wraps motion(i, t, x, v), which sets the position and velocity of frozen particle i at time t.
template <class Motion>
struct PrescribedMotion {
  Motion motion;
  explicit PrescribedMotion(Motion m) : motion(std::move(m)) {}
  template <class V>
  void prescribe(std::size_t i, V& x, V& v, double t) const {
    motion(i, t, x, v);
  }
};

}  // namespace rsph::boundary
