#pragma once
// The viscously spreading ring (Lynden-Bell & Pringle 1974; §4 of the paper): the analytic surface
// density (eq. 16), the velocities (eqs. 17-18), and the chi^2 fit of an effective viscous time.
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace rsph::paper {

/// e^-z I_nu(z), the exponentially scaled modified Bessel function of the first kind: I_nu itself
/// overflows for z > 700, and eq. (16) reaches z = 2x / tau* ~ 100 already at tau* = 0.018.
/// Series through std::cyl_bessel_i below z = 25, Hankel's asymptotic expansion above (relative
/// error < 1e-15 there: its terms fall below that before they start to grow).
inline double scaled_bessel_i(double nu, double z) {
  require(z >= 0.0 && nu >= 0.0, "scaled_bessel_i: needs z >= 0 and nu >= 0");
  if (z < 25.0) return std::cyl_bessel_i(nu, z) * std::exp(-z);
  const double mu = 4.0 * nu * nu;
  double term = 1.0, sum = 1.0;
  for (int k = 1; k < 60; ++k) {
    const double next = -term * (mu - (2.0 * k - 1.0) * (2.0 * k - 1.0)) / (k * 8.0 * z);
    if (std::abs(next) >= std::abs(term)) break;  // the asymptotic series starts to diverge
    term = next;
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum)) break;
  }
  return sum / std::sqrt(2.0 * std::numbers::pi * z);
}

/// The ring of mass M started as a delta function at R_0, spreading with kinematic viscosity nu
/// around a point mass GM; tau* = 12 nu t / R_0^2 (+ the start offset when t counts from tau*_0).
struct ViscousRing {
  double M = 1.0;
  double R0 = 1.0;
  double GM = 1.0;
  double nu = 4.8e-5;

  void validate() const {
    require(M > 0.0 && R0 > 0.0 && GM > 0.0, "viscous ring: M, R_0 and GM must be positive");
    require(nu > 0.0, "viscous ring: the viscosity nu must be positive (got " + std::to_string(nu) + ")");
  }

  /// ln Sigma(tau*, x) of eq. (16), finite wherever Sigma underflows.
  double log_sigma(double tau, double x) const {
    if (x <= 0.0) return -std::numeric_limits<double>::infinity();
    const double z = 2.0 * x / tau;
    // I_1/4(z) exp(-(1 + x^2) / tau) = [e^-z I_1/4(z)] exp(-(1 - x)^2 / tau)
    return std::log(M / (std::numbers::pi * R0 * R0)) - std::log(tau) - 0.25 * std::log(x) +
           std::log(scaled_bessel_i(0.25, z)) - (1.0 - x) * (1.0 - x) / tau;
  }
  /// eq. (16)
  double sigma(double tau, double x) const { return std::exp(log_sigma(tau, x)); }

  /// The largest Sigma(tau*, x), by a scan at 1e-4 R_0 over 0 < x < 3 (the ring never peaks beyond).
  double peak_sigma(double tau) const {
    double peak = 0.0;
    for (double x = 1e-4; x < 3.0; x += 1e-4) peak = std::max(peak, sigma(tau, x));
    return peak;
  }

  /// eq. (17): Keplerian azimuthal velocity at radius R.
  double v_phi(double R) const { return std::sqrt(GM / R); }

  /// eq. (18): v_R = -3 / (Sigma sqrt(R)) d/dR [nu Sigma sqrt(R)] = -3 nu d/dR ln(Sigma sqrt(R)),
  /// differentiated in the logarithm, which stays finite far out in the tails.
  double v_R(double tau, double R) const {
    const double x = R / R0, dx = 1e-6 * std::max(1.0, x);
    const double dlnS_dx = (log_sigma(tau, x + dx) - log_sigma(tau, x - dx)) / (2.0 * dx);
    return -3.0 * nu * (dlnS_dx + 0.5 / x) / R0;
  }

  double tau_at(double t, double tau0) const { return tau0 + 12.0 * nu * t / (R0 * R0); }
  double time_at(double tau, double tau0) const { return (tau - tau0) * R0 * R0 / (12.0 * nu); }
};

/// The tau* whose eq. (16) best fits the profile (x_i, sigma_i) in least squares, over [tau_lo, tau_hi]:
/// a logarithmic scan, then golden-section refinement around the best scan point.
inline double fit_viscous_time(const ViscousRing& ring, const std::vector<double>& x, const std::vector<double>& sigma,
                               double tau_lo, double tau_hi) {
  require(x.size() == sigma.size() && !x.empty(), "ring fit: need a non-empty profile");
  require(tau_hi > tau_lo && tau_lo > 0.0, "ring fit: need 0 < tau_lo < tau_hi");
  auto chi2 = [&](double tau) {
    double s = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double d = sigma[i] - ring.sigma(tau, x[i]);
      s += d * d;
    }
    return s;
  };
  constexpr int n_scan = 200;
  const double q = std::pow(tau_hi / tau_lo, 1.0 / n_scan);
  int best = 0;
  double best_chi2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n_scan; ++i) {
    const double c = chi2(tau_lo * std::pow(q, i));
    if (c < best_chi2) {
      best_chi2 = c;
      best = i;
    }
  }
  double a = tau_lo * std::pow(q, std::max(0, best - 1)), b = tau_lo * std::pow(q, std::min(n_scan, best + 1));
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = chi2(c), fd = chi2(d);
  while (b - a > 1e-10 * b) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - g * (b - a);
      fc = chi2(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + g * (b - a);
      fd = chi2(d);
    }
  }
  return 0.5 * (a + b);
}

}  // namespace rsph::paper
