#pragma once
// The Sedov-Taylor point explosion in a uniform gas at rest (Sedov 1959; Taylor 1950): the self-similar
// solution behind a strong shock, in planar (j = 1), cylindrical (j = 2) and spherical (j = 3) symmetry.
//
// With R(t) = xi0 (E t^2 / rho0)^(1/(j+2)), its speed U = dR/dt = 2 R / ((j + 2) t) and lambda = r / R, the
// flow is v = U f(lambda), rho = rho0 g(lambda), P = rho0 U^2 h(lambda). The Euler equations become three
// ordinary differential equations in lambda (continuity, momentum, entropy), integrated here from the
// strong-shock jump at lambda = 1 inwards; the energy integral
//   E = sigma_j rho0 U^2 R^j int_0^1 (g f^2 / 2 + h / (gamma - 1)) lambda^(j-1) d lambda
// then fixes xi0: nothing is a typed constant.
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace rsph::analysis {

/// The similarity functions at one lambda = r / R.
struct SedovPoint {
  double lambda = 0.0, f = 0.0, g = 0.0, h = 0.0;
};

/// The flow at one radius and time.
struct SedovState {
  double rho = 0.0, v = 0.0, P = 0.0;
};

class SedovTaylor {
 public:
  /// `j`: 1 planar, 2 cylindrical, 3 spherical; E the blast's energy (in planar symmetry per unit area, in
  /// cylindrical per unit length), rho0 the ambient density.
  SedovTaylor(int j, double gamma, double E = 1.0, double rho0 = 1.0) : j_(j), gamma_(gamma), E_(E), rho0_(rho0) {
    require(j >= 1 && j <= 3, "Sedov-Taylor: the symmetry must be 1 (planar), 2 (cylindrical) or 3 (spherical)");
    require(gamma > 1.0 && std::isfinite(gamma), "Sedov-Taylor: gamma must exceed 1");
    require(E > 0.0 && std::isfinite(E) && rho0 > 0.0 && std::isfinite(rho0),
            "Sedov-Taylor: the energy and the ambient density must be positive");
    integrate();
    xi0_ = std::pow(energy_integral(), -1.0 / (j_ + 2.0));
  }

  double xi0() const { return xi0_; }
  /// R(t) = xi0 (E t^2 / rho0)^(1/(j+2)).
  double shock_radius(double t) const { return xi0_ * std::pow(E_ * t * t / rho0_, 1.0 / (j_ + 2.0)); }
  /// The time at which the shock reaches radius R.
  double time_at_radius(double R) const { return std::sqrt(rho0_ / E_) * std::pow(R / xi0_, 0.5 * (j_ + 2.0)); }
  /// rho, v, P at radius r >= 0 and time t > 0 (the ambient gas, at rest with P = 0, outside the shock).
  SedovState at(double r, double t) const {
    const double R = shock_radius(t);
    if (r > R) return {rho0_, 0.0, 0.0};
    const double U = 2.0 * R / ((j_ + 2.0) * t);
    const SedovPoint s = similarity(r / R);
    return {rho0_ * s.g, U * s.f, rho0_ * U * U * s.h};
  }
  /// f, g, h at lambda in [0, 1], interpolated linearly in lambda from the integrated table (the centre's
  /// limits below the table's first point: f = lambda / gamma, h constant, g falling as a power of lambda).
  SedovPoint similarity(double lambda) const {
    const auto& t = table_;
    if (lambda >= 1.0) return t.back();
    if (lambda <= t.front().lambda) {
      const SedovPoint& a = t.front();
      return {lambda, lambda / gamma_, a.g * std::pow(lambda / a.lambda, centre_slope_), a.h};
    }
    const auto it =
        std::lower_bound(t.begin(), t.end(), lambda, [](const SedovPoint& p, double l) { return p.lambda < l; });
    const SedovPoint& b = *it;
    const SedovPoint& a = *(it - 1);
    const double w = (lambda - a.lambda) / (b.lambda - a.lambda);
    return {lambda, a.f + w * (b.f - a.f), a.g + w * (b.g - a.g), a.h + w * (b.h - a.h)};
  }
  /// sigma_j int_0^1 g lambda^(j-1) d lambda over sigma_j / j: the swept-up mass over the mass the sphere
  /// held before the blast, 1 for an exact solution.
  double mass_ratio() const {
    return j_ * integral([](const SedovPoint& p) { return p.g; });
  }
  /// The strong-shock density jump (gamma + 1) / (gamma - 1).
  double density_jump() const { return (gamma_ + 1.0) / (gamma_ - 1.0); }

 private:
  using State = std::array<double, 3>;  // f, g, h

  /// d(f, g, h)/d lambda from continuity, momentum and entropy (with a = -j/2 from U ~ t^(-j/(j+2))).
  State derivative(double lambda, const State& s) const {
    const double f = s[0], g = s[1], h = s[2];
    const double a = -0.5 * j_, w = f - lambda, c2 = gamma_ * h / g;
    const double df = (-a * f * w + c2 * (j_ - 1.0) * f / lambda + 2.0 * a * h / g) / (w * w - c2);
    const double dg = -g * (df + (j_ - 1.0) * f / lambda) / w;
    const double dh = h * (gamma_ * dg / g - 2.0 * a / w);
    return {df, dg, dh};
  }

  /// Classical fourth-order Runge-Kutta in ln lambda from the shock to lambda = 1e-3.
  void integrate() {
    State s{2.0 / (gamma_ + 1.0), density_jump(), 2.0 / (gamma_ + 1.0)};  // the strong-shock jump
    const int steps = 12000;
    const double x_end = std::log(1e-3), dx = x_end / steps;
    auto rhs = [&](double x, const State& y) {
      const double l = std::exp(x);
      State d = derivative(l, y);
      for (double& v : d) v *= l;  // d/d ln lambda
      return d;
    };
    auto axpy = [](const State& y, double c, const State& k) {
      return State{y[0] + c * k[0], y[1] + c * k[1], y[2] + c * k[2]};
    };
    std::vector<SedovPoint> t{{1.0, s[0], s[1], s[2]}};
    for (int i = 0; i < steps; ++i) {
      const double x = i * dx;
      const State k1 = rhs(x, s), k2 = rhs(x + dx / 2, axpy(s, dx / 2, k1)), k3 = rhs(x + dx / 2, axpy(s, dx / 2, k2)),
                  k4 = rhs(x + dx, axpy(s, dx, k3));
      for (int c = 0; c < 3; ++c) s[c] += dx / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
      require(std::isfinite(s[0]) && std::isfinite(s[1]) && std::isfinite(s[2]) && s[1] >= 0.0,
              "Sedov-Taylor: the similarity equations left their solution");
      t.push_back({std::exp(x + dx), s[0], s[1], s[2]});
    }
    std::reverse(t.begin(), t.end());
    table_ = std::move(t);
    const SedovPoint &a = table_[0], &b = table_[1];
    centre_slope_ = a.g > 0.0 && b.g > 0.0 ? std::log(b.g / a.g) / std::log(b.lambda / a.lambda) : 0.0;
  }

  /// int_0^1 q(point) lambda^(j-1) d lambda by the trapezoid rule over the table (the part below its
  /// first point, O(1e-3^j), left out).
  template <class Q>
  double integral(Q&& q) const {
    double sum = 0.0;
    for (std::size_t i = 1; i < table_.size(); ++i) {
      const SedovPoint &a = table_[i - 1], &b = table_[i];
      const double qa = q(a) * std::pow(a.lambda, j_ - 1), qb = q(b) * std::pow(b.lambda, j_ - 1);
      sum += 0.5 * (qa + qb) * (b.lambda - a.lambda);
    }
    return sum;
  }

  /// E / (rho0 R^(j+2) / t^2) at xi0 = 1: sigma_j (2 / (j+2))^2 int (g f^2 / 2 + h / (gamma - 1)) lambda^(j-1).
  double energy_integral() const {
    const double sigma = j_ == 1 ? 2.0 : (j_ == 2 ? 2.0 * std::numbers::pi : 4.0 * std::numbers::pi);
    const double k = 2.0 / (j_ + 2.0);
    return sigma * k * k * integral([&](const SedovPoint& p) { return 0.5 * p.g * p.f * p.f + p.h / (gamma_ - 1.0); });
  }

  int j_;
  double gamma_, E_, rho0_;
  double xi0_ = 0.0, centre_slope_ = 0.0;
  std::vector<SedovPoint> table_;
};

}  // namespace rsph::analysis
