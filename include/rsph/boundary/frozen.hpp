#pragma once
// Frozen particles: flagged in ParticleSet::frozen, they take part in every sum but are not
// integrated; their x and v follow a prescribed motion (the Keplerian boundary zones of §5).
#include "rsph/core/dimension.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/physics/concept.hpp"

#include <cstddef>
#include <tuple>
#include <type_traits>
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

/// Moves the frozen particles over a step of dt that ends at `time`: each PrescribedMotion term sets their
/// x and v, each BoundaryZone term turns those inside it.
template <int D, bool E, class... Terms>
void prescribe_frozen(const std::tuple<Terms...>& terms, ParticleSet<D, E>& p, double time, double dt) {
  auto apply_motion = [&](const auto& t) {
    using T = std::decay_t<decltype(t)>;
    if constexpr (rsph::PrescribedMotion<T, D>)
      for (std::size_t a = 0; a < p.n_real; ++a)
        if (p.frozen[a]) t.prescribe(a, p.x[a], p.v[a], time);
    if constexpr (BoundaryZone<T, D>) {
      const std::size_t n = p.n_real;
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
      for (std::size_t a = 0; a < n; ++a)
        if (p.frozen[a] && t.contains(p.x[a])) t.advance(p.x[a], p.v[a], dt);
    }
  };
  std::apply([&](const auto&... term) { (apply_motion(term), ...); }, terms);
}

/// Relaxes the velocities of the integrated particles over a step (or block) of dt that has just ended, as each
/// VelocityDamping term says (the wave-damping zones).
template <int D, bool E, class... Terms>
void damp_velocities(const std::tuple<Terms...>& terms, ParticleSet<D, E>& p, double dt) {
  auto damp = [&](const auto& t) {
    if constexpr (VelocityDamping<std::decay_t<decltype(t)>, D>) {
      if (!t.active()) return;
      const std::size_t n = p.n_real;
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
      for (std::size_t a = 0; a < n; ++a)
        if (!p.frozen[a]) t.damp(p.x[a], p.v[a], dt);
    }
  };
  std::apply([&](const auto&... term) { (damp(term), ...); }, terms);
}

/// Whether a boundary zone keeps its members through a regularization (`members_kept`): they are left out of
/// the remap and keep their identity, and the new particles are not made members, however near they land.
/// Otherwise (the paper's zones) membership is decided anew by position after every regularization.
template <class T>
bool keeps_members(const T& t) {
  if constexpr (requires { t.members_kept; })
    return t.members_kept;
  else
    return false;
}
template <class... Terms>
bool any_zone_keeps_members(const std::tuple<Terms...>& terms) {
  return std::apply([](const auto&... t) { return (keeps_members(t) || ... || false); }, terms);
}

/// Flags the particles inside a boundary zone as frozen (other flags stay); their velocity is the zone's. After
/// a regularization (`after_remap`), zones that keep their members flag none.
template <int D, bool E, class... Terms>
void mark_zone_members(const std::tuple<Terms...>& terms, ParticleSet<D, E>& p, bool after_remap = false) {
  auto mark = [&](const auto& t) {
    if constexpr (BoundaryZone<std::decay_t<decltype(t)>, D>)
      for (std::size_t a = 0; a < p.n_real && !(after_remap && keeps_members(t)); ++a)
        if (t.contains(p.x[a])) {
          p.frozen[a] = 1;
          Vec<D> x = p.x[a];
          t.advance(x, p.v[a], 0.0);
        }
  };
  std::apply([&](const auto&... term) { (mark(term), ...); }, terms);
}

}  // namespace rsph::boundary
