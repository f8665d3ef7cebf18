#pragma once
// The SPH density of a uniform lattice is not exactly the nominal density: sum_b W(x_a - x_b, h) dx^D
// differs from 1 by a bias set by h/dx and the kernel (0.18 % for the cubic spline at h/dx = 1.2 in 1D).
// Scenes divide masses by this factor so the SPH density of a lattice equals the intended density.
#include "rsph/core/dimension.hpp"
#include "rsph/kernel/kernel.hpp"

#include <cmath>
#include <numbers>

namespace rsph::kernel {

/// dx^D sum over a Cartesian lattice of W(x_j, h), h = h_over_dx * dx (independent of dx).
template <class K, int D>
requires SmoothingKernel<K, D>
double lattice_sum(double h_over_dx) {
  const int reach = static_cast<int>(std::ceil(K::support * h_over_dx)) + 1;
  double sum = 0.0;
  if constexpr (D == 1) {
    for (int i = -reach; i <= reach; ++i) sum += W<K, 1>(std::abs(i), h_over_dx);
  } else if constexpr (D == 2) {
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j) sum += W<K, 2>(std::hypot(i, j), h_over_dx);
  } else {
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j)
        for (int k = -reach; k <= reach; ++k) sum += W<K, 3>(std::sqrt(double(i * i + j * j + k * k)), h_over_dx);
  }
  return sum;
}

/// The sites of a 2D lattice of unit spacing within `radius` of a site: f(x) for each offset x = i a1 + j a2
/// (the site itself included), with a1 = (1, 0) and a2 = (0, 1) (square) or (1/2, sqrt(3)/2) (hexagonal:
/// nearest neighbours at distance 1, cells of area sqrt(3)/2).
template <class F>
void for_each_lattice_offset(bool hexagonal, double radius, F&& f) {
  const double a2x = hexagonal ? 0.5 : 0.0, a2y = hexagonal ? std::numbers::sqrt3 / 2.0 : 1.0;
  const int rows = static_cast<int>(std::ceil(radius / a2y)) + 1, columns = static_cast<int>(std::ceil(radius)) + 2;
  for (int j = -rows; j <= rows; ++j)
    for (int i = -columns; i <= columns; ++i) {
      const Vec<2> x(i + j * a2x, j * a2y);
      if (x.norm() <= radius) f(x);
    }
}

/// The cell area times sum over a hexagonal lattice (nearest-neighbour distance dx) of W(x_j, h), h =
/// h_over_dx * dx: the hexagonal counterpart of lattice_sum<K, 2>, whose cells have area sqrt(3)/2 dx^2.
/// A scene that puts mass rho (sqrt(3)/2) dx^2 / this on each site has SPH density rho.
template <class K>
requires SmoothingKernel<K, 2>
double hexagonal_lattice_sum(double h_over_dx) {
  double sum = 0.0;
  for_each_lattice_offset(true, K::support * h_over_dx, [&](const Vec<2>& x) { sum += W<K, 2>(x.norm(), h_over_dx); });
  return std::numbers::sqrt3 / 2.0 * sum;
}

/// The integral of f(x) over [-R, R] by Simpson's rule (2000 intervals): a row of a lattice averaged over
/// its offset.
template <class F>
double row_integral(double R, F&& f) {
  constexpr int n = 2000;  // even
  const double dx = 2.0 * R / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) sum += ((i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0)) * f(-R + i * dx);
  return sum * dx / 3.0;
}

/// The counterpart of lattice_sum<K, 2> for rows dx apart, each of sites dx apart, that slide past each other
/// (lattice::Rings, its rings turned against each other by the shear): the particle's own row summed, every
/// other row averaged over its offset, i.e. integrated along it. A scene that puts mass rho dx^2 / this on each
/// site has SPH density rho on average.
template <class K>
requires SmoothingKernel<K, 2>
double sheared_rows_lattice_sum(double h_over_dx) {
  const double R = K::support * h_over_dx;
  const int rows = static_cast<int>(std::ceil(R));
  double sum = 0.0;
  for (int i = -rows; i <= rows; ++i) sum += W<K, 2>(std::abs(i), h_over_dx);
  for (int k = 1; k <= rows; ++k)
    sum += 2.0 * row_integral(R, [&](double x) { return W<K, 2>(std::hypot(x, double(k)), h_over_dx); });
  return sum;
}

}  // namespace rsph::kernel
