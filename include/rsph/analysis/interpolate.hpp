#pragma once
// SPH interpolation of the density at arbitrary points, for measurements on snapshots (disk maps, interfaces).
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/dimension.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace rsph::analysis {

/// Sigma(x) = sum_b m_b W(|x - x_b|, h_b) at each point, over the real particles and, for the periodic and
/// reflecting axes of `box`, their images (boundary::make_ghosts), so points near those faces miss nothing.
/// The default box is open: the real particles alone.
template <class Kernel, class Particles>
std::vector<double> interpolate_density(const Particles& p, const std::vector<Vec<2>>& points, const Box<2>& box = {}) {
  double h_max = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) h_max = std::max(h_max, p.h[a]);
  const double reach = Kernel::support * h_max;
  Particles with_images = p;
  boundary::make_ghosts(with_images, box, reach);
  const auto& x = with_images.x;
  neighbors::CellList<2> cells;
  cells.build(x, reach);
  std::vector<double> sigma(points.size(), 0.0);
  const auto n = static_cast<std::ptrdiff_t>(points.size());
#pragma omp parallel for schedule(static) if (n >= std::ptrdiff_t(kParallelMin))
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const Vec<2>& at = points[static_cast<std::size_t>(i)];
    double s = 0.0;
    cells.for_each_within(at, reach, [&](std::uint32_t b) {
      const double r = (at - x[b]).norm();
      const double h = with_images.h[b];
      if (r < Kernel::support * h) s += with_images.m[b] * kernel::W<Kernel, 2>(r, h);
    });
    sigma[static_cast<std::size_t>(i)] = s;
  }
  return sigma;
}

}  // namespace rsph::analysis
