#pragma once
// Dimension, vectors and the simulation box.
#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstdint>

namespace rsph {

/// floor(x) as an integer index (finite, |x| < 2^62: callers clamp first where x may be far or not finite), inline:
/// without SSE4.1, x86-64 compiles std::floor to a library call, and the cell searches take several per particle.
inline std::int64_t floor_index(double x) {
  const auto t = static_cast<std::int64_t>(x);  // truncates towards zero
  return t - static_cast<std::int64_t>(static_cast<double>(t) > x);
}

/// Fixed-size position/velocity vector. Never bind an Eigen expression to `auto`.
template <int D>
using Vec = Eigen::Matrix<double, D, 1>;

/// Fixed-size D x D tensor (velocity gradients, viscous stresses).
template <int D>
using Mat = Eigen::Matrix<double, D, D>;

template <int D>
concept SupportedDimension = (D == 1 || D == 2 || D == 3);

/// What happens at a box face.
enum class Edge { open, periodic, reflecting };

/// An axis-aligned domain with one edge kind per axis (both faces of an axis share it).
template <int D>
requires SupportedDimension<D>
struct Box {
  Vec<D> lo = Vec<D>::Zero();
  Vec<D> hi = Vec<D>::Ones();
  std::array<Edge, D> edge{};  // open by default

  Vec<D> size() const { return hi - lo; }
  double volume() const { return size().prod(); }
  bool periodic(int axis) const { return edge[axis] == Edge::periodic; }
  bool contains(const Vec<D>& x) const {
    for (int k = 0; k < D; ++k)
      if (x[k] < lo[k] || x[k] > hi[k]) return false;
    return true;
  }
  /// Minimum-image separation x_a - x_b over the periodic axes.
  Vec<D> separation(const Vec<D>& a, const Vec<D>& b) const {
    Vec<D> r = a - b;
    for (int k = 0; k < D; ++k) {
      if (!periodic(k)) continue;
      const double L = hi[k] - lo[k];
      r[k] -= L * std::round(r[k] / L);
    }
    return r;
  }
  /// Wrap a position into the box along periodic axes.
  void wrap(Vec<D>& x) const {
    for (int k = 0; k < D; ++k) {
      if (!periodic(k)) continue;
      const double L = hi[k] - lo[k];
      x[k] -= L * std::floor((x[k] - lo[k]) / L);
      if (x[k] >= hi[k]) x[k] = lo[k];  // round-off at the upper face
    }
  }
};

}  // namespace rsph
