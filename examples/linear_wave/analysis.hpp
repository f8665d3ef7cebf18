#pragma once
// The damping rate gamma of eq. (11) and the phase error of a sensor signal delta_rho(t).
#include "rsph/analysis/fit.hpp"
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace rsph::analysis {

/// eq. (11) of the paper with its Delta t read as the wave period P_w:
///   gamma = -2 / (2 pi (N - 1) N) sum_{k=1}^{N-1} ln(S_k / S_0),
/// S_k = max |delta_rho| over [k P_w, (k + 1) P_w). For delta_rho = rho_1 e^(-gamma omega t) cos(omega t - phi),
/// S_k / S_0 = e^(-gamma omega k P_w) = e^(-2 pi gamma k) (the peaks of every period sit at the same phase),
/// and sum_{k=1}^{N-1} k = N (N - 1) / 2, so this returns gamma exactly. As printed, with Delta t the time
/// step, eq. (11) would not.
inline double damping_rate(const std::vector<double>& t, const std::vector<double>& signal, double period,
                           int periods) {
  require(periods >= 2, "damping rate: need at least two periods");
  std::vector<double> S(static_cast<std::size_t>(periods), 0.0);
  for (std::size_t i = 0; i < t.size(); ++i) {
    const auto k = static_cast<long>(std::floor(t[i] / period * (1.0 + 1e-12)));
    if (k >= 0 && k < periods)
      S[static_cast<std::size_t>(k)] = std::max(S[static_cast<std::size_t>(k)], std::abs(signal[i]));
  }
  require(S[0] > 0.0, "damping rate: the signal is zero over the first period");
  double sum = 0.0;
  for (int k = 1; k < periods; ++k) sum += std::log(S[static_cast<std::size_t>(k)] / S[0]);
  return -2.0 / (2.0 * std::numbers::pi * (periods - 1) * periods) * sum;
}

/// Measured period over the expected one, minus one, from a least-squares line through the times of the
/// upward zero crossings (linear interpolation between samples). Positive: the wave is slow.
inline double phase_error(const std::vector<double>& t, const std::vector<double>& signal, double period) {
  std::vector<double> crossings;
  for (std::size_t i = 1; i < t.size(); ++i)
    if (signal[i - 1] < 0.0 && signal[i] >= 0.0)
      crossings.push_back(t[i - 1] + (t[i] - t[i - 1]) * (-signal[i - 1]) / (signal[i] - signal[i - 1]));
  require(crossings.size() >= 3, "phase error: fewer than three zero crossings");
  std::vector<double> index(crossings.size());
  for (std::size_t j = 0; j < index.size(); ++j) index[j] = static_cast<double>(j);
  return least_squares_slope(index, crossings) / period - 1.0;
}

}  // namespace rsph::analysis
