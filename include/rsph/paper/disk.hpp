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

/// Where a planet's wake crosses a ring of a Sigma map against linear theory: azimuths relative to the planet.
struct WakeCrossing {
  double r = 0.0, phi_theory = 0.0, phi_measured = 0.0;
  /// phi_measured - phi_theory, wrapped into [-pi, pi].
  double offset() const { return std::remainder(phi_measured - phi_theory, 2.0 * std::numbers::pi); }
};

/// The wake's crest on a Sigma map on `grid` (phi_0 the planet's azimuth), traced ring by ring away from the
/// orbit a on both sides, over r_lo <= r <= r_hi and at least `clear` from the orbit (the planet's own well left
/// out): on the first ring the largest Sigma within `window` radians of linear theory's wake (wake_azimuth), on
/// each next ring the largest within `window` of the last crest moved on by theory's turn between the rings. A
/// crest that winds less or more than theory's drifts from it ring by ring, as a massive planet's does.
inline std::vector<WakeCrossing> wake_crossings(const PolarGrid& grid, const std::vector<double>& sigma, double a,
                                                double aspect, double r_lo, double r_hi, double clear, double window) {
  const double two_pi = 2.0 * std::numbers::pi;
  std::vector<WakeCrossing> out;
  auto trace = [&](std::ptrdiff_t first, std::ptrdiff_t step) {
    double centre = 0.0, last_theory = 0.0;
    bool started = false;
    for (std::ptrdiff_t i = first; i >= 0 && i < static_cast<std::ptrdiff_t>(grid.n_r); i += step) {
      const auto row = static_cast<std::size_t>(i);
      const double r = grid.r(row);
      if (r < r_lo || r > r_hi) break;
      const double theory = wake_azimuth(r, a, aspect);
      centre = started ? centre + (theory - last_theory) : theory;
      last_theory = theory;
      WakeCrossing c{r, std::remainder(theory, two_pi), 0.0};
      double best = -1.0;
      for (std::size_t j = 0; j < grid.n_phi; ++j) {
        const double value = sigma[row * grid.n_phi + j];
        if (std::abs(std::remainder(grid.phi(j) - centre, two_pi)) <= window && value > best) {
          best = value;
          c.phi_measured = grid.phi(j);
        }
      }
      centre += std::remainder(c.phi_measured - centre, two_pi);
      started = true;
      out.push_back(c);
    }
  };
  std::ptrdiff_t outer = 0, inner = -1;  // the first rings clear of the orbit on either side
  while (outer < static_cast<std::ptrdiff_t>(grid.n_r) && grid.r(static_cast<std::size_t>(outer)) < a + clear) ++outer;
  for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(grid.n_r); ++i)
    if (grid.r(static_cast<std::size_t>(i)) <= a - clear) inner = i;
  if (inner >= 0) trace(inner, -1);
  trace(outer, 1);
  std::sort(out.begin(), out.end(), [](const WakeCrossing& x, const WakeCrossing& y) { return x.r < y.r; });
  return out;
}

/// The root mean square of the crossings' offsets from theory (0 for none).
inline double rms_offset(const std::vector<WakeCrossing>& crossings) {
  double sum = 0.0;
  for (const auto& c : crossings) sum += c.offset() * c.offset();
  return crossings.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(crossings.size()));
}

}  // namespace rsph::paper
