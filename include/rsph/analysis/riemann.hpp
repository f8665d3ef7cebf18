#pragma once
// Exact Riemann solver for the ideal-gas Euler equations (Toro 2009, ch. 4), robust to pressure
// ratios of 1e10 and more: Newton on the pressure function from the two-rarefaction guess, with a
// bisection fallback that keeps the iterate bracketed.
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace rsph::analysis {

struct GasState {
  double rho, v, P;
};

class ExactRiemann {
 public:
  ExactRiemann(GasState left, GasState right, double gamma) : L_(left), R_(right), g_(gamma) {
    require(gamma > 1.0, "Riemann solver: gamma must exceed 1");
    require(L_.rho > 0 && R_.rho > 0 && L_.P > 0 && R_.P > 0,
            "Riemann solver: densities and pressures must be positive");
    cL_ = std::sqrt(g_ * L_.P / L_.rho);
    cR_ = std::sqrt(g_ * R_.P / R_.rho);
    require(2.0 / (g_ - 1.0) * (cL_ + cR_) > R_.v - L_.v, "Riemann solver: the data create a vacuum");
    solve_star();
  }

  double p_star() const { return p_star_; }
  double v_star() const { return v_star_; }
  /// Density on either side of the contact.
  double rho_star_left() const { return star_density(L_, p_star_); }
  double rho_star_right() const { return star_density(R_, p_star_); }

  /// Speed of the right-moving shock (when the right wave is a shock).
  double right_shock_speed() const {
    const double pr = p_star_ / R_.P;
    return R_.v + cR_ * std::sqrt((g_ + 1.0) / (2.0 * g_) * pr + (g_ - 1.0) / (2.0 * g_));
  }

  /// The state at similarity coordinate xi = (x - x0) / t (Toro §4.5).
  GasState sample(double xi) const {
    const double g = g_;
    if (xi <= v_star_) {
      if (p_star_ > L_.P) {  // left shock
        const double pr = p_star_ / L_.P;
        const double S = L_.v - cL_ * std::sqrt((g + 1) / (2 * g) * pr + (g - 1) / (2 * g));
        return xi <= S ? L_ : GasState{star_density(L_, p_star_), v_star_, p_star_};
      }
      const double head = L_.v - cL_;
      const double c_star = cL_ * std::pow(p_star_ / L_.P, (g - 1) / (2 * g));
      const double tail = v_star_ - c_star;
      if (xi <= head) return L_;
      if (xi >= tail) return {star_density(L_, p_star_), v_star_, p_star_};
      const double f = 2 / (g + 1) + (g - 1) / ((g + 1) * cL_) * (L_.v - xi);
      const double rho = L_.rho * std::pow(f, 2 / (g - 1));
      return {rho, 2 / (g + 1) * (cL_ + (g - 1) / 2 * L_.v + xi), L_.P * std::pow(f, 2 * g / (g - 1))};
    }
    if (p_star_ > R_.P) {  // right shock
      return xi >= right_shock_speed() ? R_ : GasState{star_density(R_, p_star_), v_star_, p_star_};
    }
    const double head = R_.v + cR_;
    const double c_star = cR_ * std::pow(p_star_ / R_.P, (g - 1) / (2 * g));
    const double tail = v_star_ + c_star;
    if (xi >= head) return R_;
    if (xi <= tail) return {star_density(R_, p_star_), v_star_, p_star_};
    const double f = 2 / (g + 1) - (g - 1) / ((g + 1) * cR_) * (R_.v - xi);
    const double rho = R_.rho * std::pow(f, 2 / (g - 1));
    return {rho, 2 / (g + 1) * (-cR_ + (g - 1) / 2 * R_.v + xi), R_.P * std::pow(f, 2 * g / (g - 1))};
  }

 private:
  // Toro eq. (4.6)-(4.7): f_K(p) and its derivative.
  void pressure_function(double p, const GasState& K, double c, double& f, double& df) const {
    const double g = g_;
    if (p > K.P) {
      const double A = 2 / ((g + 1) * K.rho), B = (g - 1) / (g + 1) * K.P;
      const double s = std::sqrt(A / (p + B));
      f = (p - K.P) * s;
      df = s * (1 - 0.5 * (p - K.P) / (B + p));
    } else {
      const double pr = p / K.P;
      f = 2 * c / (g - 1) * (std::pow(pr, (g - 1) / (2 * g)) - 1);
      df = 1 / (K.rho * c) * std::pow(pr, -(g + 1) / (2 * g));
    }
  }

  void solve_star() {
    const double g = g_;
    const double dv = R_.v - L_.v;
    auto F = [&](double p, double& dF) {
      double fL, dL, fR, dR;
      pressure_function(p, L_, cL_, fL, dL);
      pressure_function(p, R_, cR_, fR, dR);
      dF = dL + dR;
      return fL + fR + dv;
    };
    // Two-rarefaction guess (Toro eq. 4.46): exact when both waves are rarefactions.
    const double z = (g - 1) / (2 * g);
    double p = std::pow((cL_ + cR_ - 0.5 * (g - 1) * dv) / (cL_ / std::pow(L_.P, z) + cR_ / std::pow(R_.P, z)), 1 / z);
    p = std::max(p, 1e-300);
    // Bracket: F is increasing in p; F(0+) < 0 when there is no vacuum.
    double lo = 0.0, hi = std::max({L_.P, R_.P, p}) * 2;
    double dF;
    while (F(hi, dF) < 0) hi *= 2;
    for (int it = 0; it < 200; ++it) {
      const double Fp = F(p, dF);
      if (Fp < 0)
        lo = std::max(lo, p);
      else
        hi = std::min(hi, p);
      double next = p - Fp / dF;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (std::abs(next - p) <= 1e-15 * std::max(p, 1e-300)) {
        p = next;
        break;
      }
      p = next;
    }
    p_star_ = p;
    double fL, dL, fR, dR;
    pressure_function(p, L_, cL_, fL, dL);
    pressure_function(p, R_, cR_, fR, dR);
    v_star_ = 0.5 * (L_.v + R_.v) + 0.5 * (fR - fL);
  }

  double star_density(const GasState& K, double p) const {
    const double g = g_;
    if (p > K.P) {
      const double pr = p / K.P, q = (g - 1) / (g + 1);
      return K.rho * (pr + q) / (q * pr + 1);
    }
    return K.rho * std::pow(p / K.P, 1 / g);
  }

  GasState L_, R_;
  double g_, cL_, cR_;
  double p_star_ = 0.0, v_star_ = 0.0;
};

}  // namespace rsph::analysis
