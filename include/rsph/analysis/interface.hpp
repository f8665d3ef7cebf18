#pragma once
// How far the interface between two phases of different density has rolled up. The mode amplitude of a
// Kelvin-Helmholtz run measures the transverse velocity of the mode, not the shape of the interface: a wave
// whose crests stay single-valued and a billow that curls over can carry the same amplitude. Along a
// vertical line, a single-valued interface is crossed once; where a billow has curled over, three times
// or more.
#include "rsph/analysis/interpolate.hpp"
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace rsph::analysis {

struct InterfaceFolds {
  std::size_t columns = 0, rows = 0;  ///< the sampling grid
  double overturned_fraction = 0.0;   ///< columns that cross the level three times or more
  double mean_crossings = 0.0;        ///< crossings per column (1 for a flat or wavy interface)
};

/// Samples the SPH density (interpolate_density, images of periodic and reflecting axes included) at the
/// centres of a grid of about `spacing` over the box and counts, along each column (constant x), the
/// changes of rho > level between neighbouring samples.
template <class Kernel, class Particles>
InterfaceFolds interface_folds(const Particles& p, const Box<2>& box, double level, double spacing) {
  require(spacing > 0.0,
          "interface folds: the sampling spacing must be positive (got " + std::to_string(spacing) + ")");
  InterfaceFolds f;
  const Vec<2> size = box.size();
  f.columns = static_cast<std::size_t>(std::max(1.0, std::round(size[0] / spacing)));
  f.rows = static_cast<std::size_t>(std::max(2.0, std::round(size[1] / spacing)));
  require(f.columns * f.rows <= (std::size_t{1} << 26), "interface folds: more than 2^26 samples");
  std::vector<Vec<2>> points;
  points.reserve(f.columns * f.rows);
  for (std::size_t i = 0; i < f.columns; ++i)
    for (std::size_t j = 0; j < f.rows; ++j)
      points.emplace_back(box.lo[0] + (static_cast<double>(i) + 0.5) * size[0] / static_cast<double>(f.columns),
                          box.lo[1] + (static_cast<double>(j) + 0.5) * size[1] / static_cast<double>(f.rows));
  const std::vector<double> rho = interpolate_density<Kernel>(p, points, box);
  std::size_t overturned = 0, crossings = 0;
  for (std::size_t i = 0; i < f.columns; ++i) {
    std::size_t column = 0;
    for (std::size_t j = 1; j < f.rows; ++j)
      column += static_cast<std::size_t>((rho[i * f.rows + j] > level) != (rho[i * f.rows + j - 1] > level));
    crossings += column;
    overturned += static_cast<std::size_t>(column >= 3);
  }
  f.overturned_fraction = static_cast<double>(overturned) / static_cast<double>(f.columns);
  f.mean_crossings = static_cast<double>(crossings) / static_cast<double>(f.columns);
  return f;
}

}  // namespace rsph::analysis
