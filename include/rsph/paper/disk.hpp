#pragma once
// Measuring a disk: the SPH surface density (interpolate.hpp) on an (r, phi) grid and averaged over phi, and
// the spiral wake of a planet in the linear theory of Ogilvie & Lubow (2002).
#include "rsph/analysis/interpolate.hpp"
#include "rsph/core/dimension.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace rsph::paper {

/// A polar grid of n_r x n_phi cell centres over [r_lo, r_hi] x [phi_0 - pi, phi_0 + pi), row-major in r.
struct PolarGrid {
  double r_lo = 0.0, r_hi = 1.0, phi_0 = 0.0;
  std::size_t n_r = 1, n_phi = 1;

  double r(std::size_t i) const { return r_lo + (static_cast<double>(i) + 0.5) * (r_hi - r_lo) / double(n_r); }
  /// Azimuth relative to phi_0, in [-pi, pi).
  double phi(std::size_t j) const {
    return -std::numbers::pi + (static_cast<double>(j) + 0.5) * 2.0 * std::numbers::pi / double(n_phi);
  }
  std::vector<Vec<2>> points() const {
    std::vector<Vec<2>> out;
    out.reserve(n_r * n_phi);
    for (std::size_t i = 0; i < n_r; ++i)
      for (std::size_t j = 0; j < n_phi; ++j) {
        const double angle = phi_0 + phi(j);
        out.emplace_back(r(i) * std::cos(angle), r(i) * std::sin(angle));
      }
    return out;
  }
};

/// The mean over phi of each row of values on `grid` (row-major in r).
inline std::vector<double> azimuthal_average(const PolarGrid& grid, const std::vector<double>& values) {
  std::vector<double> mean(grid.n_r, 0.0);
  for (std::size_t i = 0; i < grid.n_r; ++i) {
    for (std::size_t j = 0; j < grid.n_phi; ++j) mean[i] += values[i * grid.n_phi + j];
    mean[i] /= static_cast<double>(grid.n_phi);
  }
  return mean;
}

/// The wake of a planet at radius a in the linear theory of Ogilvie & Lubow (2002), drawn over the maps
/// of de Val-Borro et al. (2006): the crest travels radially at c_s while the gas shears past at
/// Omega - Omega_p, so dphi/dr = sgn(r - a) (Omega - Omega_p) / c_s. For Omega ~ r^-3/2 and
/// c_s = aspect v_K that integrates to phi = sgn(r - a) / aspect [ln(r/a) - 2/3 ((r/a)^3/2 - 1)],
/// relative to the planet and not wrapped (trailing: negative outside the orbit, positive inside).
inline double wake_azimuth(double r, double a, double aspect) {
  const double x = r / a;
  const double s = x > 1.0 ? 1.0 : -1.0;
  return s / aspect * (std::log(x) - 2.0 / 3.0 * (x * std::sqrt(x) - 1.0));
}

}  // namespace rsph::paper
