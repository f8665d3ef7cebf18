#pragma once
// The SPH density of a uniform lattice is not exactly the nominal density: sum_b W(x_a - x_b, h) dx^D
// differs from 1 by a bias set by h/dx and the kernel (0.18 % for the cubic spline at h/dx = 1.2 in 1D).
// Scenes divide masses by this factor so the SPH density of a lattice equals the intended density.
#include "rsph/core/dimension.hpp"
#include "rsph/kernel/kernel.hpp"

#include <cmath>

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

}  // namespace rsph::kernel
