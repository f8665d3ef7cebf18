#pragma once
// Least-squares fits shared by the measurements (growth and decay rates, wave periods).
#include "rsph/core/errors.hpp"

#include <vector>

namespace rsph::analysis {

/// Slope of the least-squares line through (x_i, y_i); needs two distinct x.
inline double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y) {
  require(x.size() == y.size() && x.size() >= 2, "least-squares slope: need two or more points");
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  const double d = n * sxx - sx * sx;
  require(d > 0.0, "least-squares slope: all x are equal");
  return (n * sxy - sx * sy) / d;
}

}  // namespace rsph::analysis
