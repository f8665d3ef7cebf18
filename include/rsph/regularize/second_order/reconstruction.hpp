#pragma once
// Linear reconstruction in one old cell, as pure functions of that cell and its Voronoi neighbours: the
// least-squares gradient and the Barth-Jespersen limiter. What the second-order remap hands out is the
// integral of these reconstructions over each overlap (remap_second.hpp).
#include "rsph/core/dimension.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

namespace rsph::regularize::second_order {

template <int D>
using Mat = Eigen::Matrix<double, D, D>;

/// One Voronoi neighbour b of cell a: its index, the vector from a's particle to b's (the nearest image
/// across periodic axes) and the face's weight in the least-squares sum.
template <int D>
struct Face {
  std::uint32_t b = 0;
  Vec<D> d = Vec<D>::Zero();
  double length = 0.0;  ///< the shared face's length (2D), 1 in 1D
};

/// The least-squares gradients of F fields at once: minimise sum_b w_b (dq_b - g . r_b)^2 for each field over
/// the faces' displacements r_b between reference points, with w_b = l_b / |r_b|^2 (face length over squared
/// distance, the weighting of moving-mesh codes, Pakmor et al. 2016). One normal matrix serves every field.
template <int D, int F>
struct LeastSquares {
  Mat<D> normal = Mat<D>::Zero();
  Eigen::Matrix<double, D, F> rhs = Eigen::Matrix<double, D, F>::Zero();
  double scale = 0.0;  ///< sum of w |r|^2, the matrix's trace: the yardstick of its determinant

  void add(const Vec<D>& r, double length, const Eigen::Matrix<double, F, 1>& dq) {
    const double r2 = r.squaredNorm();
    if (!(r2 > 0.0)) return;
    const double w = length / r2;
    normal.noalias() += w * r * r.transpose();
    rhs.noalias() += (w * r) * dq.transpose();
    scale += w * r2;
  }
  /// Column k: field k's gradient. False, leaving `g` alone, where the faces span fewer than D directions.
  bool solve(Eigen::Matrix<double, D, F>& g) const {
    if (!(scale > 0.0)) return false;
    const double det = normal.determinant();
    if (!(std::abs(det) > 1e-10 * std::pow(scale, D))) return false;
    g.noalias() = normal.inverse() * rhs;
    return true;
  }
};

/// Barth-Jespersen: the largest phi in [0, 1] for which q + phi g . o_k stays within [lo(k), hi(k)] for each
/// offset o_k (a point of the cell less the reconstruction's reference point). A linear field's extremes
/// over a convex region lie at its vertices; its mean over a region is its value at the centroid.
template <int D, class Lo, class Hi>
double barth_jespersen(double q, const Vec<D>& g, std::span<const Vec<D>> offsets, Lo&& lo, Hi&& hi) {
  double phi = 1.0;
  for (std::size_t k = 0; k < offsets.size(); ++k) {
    const double delta = g.dot(offsets[k]);
    if (delta > 0.0)
      phi = std::min(phi, (hi(k) - q) / delta);
    else if (delta < 0.0)
      phi = std::min(phi, (lo(k) - q) / delta);
  }
  return std::clamp(phi, 0.0, 1.0);
}

/// The range of a field over a cell and its faces' neighbours.
struct Range {
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  void add(double q) {
    lo = std::min(lo, q);
    hi = std::max(hi, q);
  }
  void add(const Range& o) {
    lo = std::min(lo, o.lo);
    hi = std::max(hi, o.hi);
  }
};

/// The ranges of the reconstructed fields: density, velocity components, specific total energy.
template <int D>
struct FieldRanges {
  Range rho, e;
  std::array<Range, D> v;
  void add(const FieldRanges& o) {
    rho.add(o.rho);
    e.add(o.e);
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) v[k].add(o.v[k]);
  }
};

}  // namespace rsph::regularize::second_order
