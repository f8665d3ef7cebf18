#include "linear_wave/scene.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

TEST_CASE("eq. (11) with Delta t = P_w returns gamma of a synthetic damped wave", "[linear_wave]") {
  for (double gamma : {0.0, 1e-4, 3e-3, -2e-3}) {
    std::vector<double> t, s;
    const double omega = 2.0 * std::numbers::pi / 0.8;  // P_w = 0.8
    for (int i = 0; i <= 100 * 800; ++i) {
      t.push_back(i * 1e-3);
      s.push_back(1e-3 * std::exp(-gamma * omega * t.back()) * std::cos(omega * t.back() - 0.7));
    }
    CHECK(analysis::damping_rate(t, s, 0.8, 100) == Approx(gamma).margin(2e-6));
    CHECK(analysis::phase_error(t, s, 0.8) == Approx(0.0).margin(1e-6));
    CHECK(analysis::phase_error(t, s, 0.8 / 1.01) == Approx(0.01).epsilon(1e-4));  // a 1 % slow wave
  }
}

namespace {
scenes::LinearWaveResult wave(double r, double alpha, double h_over_dx = 1.2, double jitter = 0.0,
                              bool quintic = true) {
  scenes::LinearWaveParams s;
  s.wavelength_cells = 24;
  s.periods = 20;
  s.r = r;
  s.alpha = alpha;
  s.h_over_dx = h_over_dx;
  s.jitter = jitter;
  auto none = [](const auto&) {};
  return quintic ? scenes::run_linear_wave<kernel::QuinticSpline>(s, none)
                 : scenes::run_linear_wave<kernel::CubicSpline>(s, none);
}
}  // namespace

TEST_CASE("linear waves: RSPH damping falls as r grows; SPH with alpha = 0.1 damps at least as much as r = 4.25",
          "[linear_wave]") {
  const auto r075 = wave(0.75, 0.0), r425 = wave(4.25, 0.0), r1625 = wave(16.25, 0.0);
  const auto sph01 = wave(0.0, 0.1), sph0 = wave(0.0, 0.0);
  INFO("gamma: r=0.75 " << r075.gamma << ", r=4.25 " << r425.gamma << ", r=16.25 " << r1625.gamma << ", SPH a=0.1 "
                        << sph01.gamma << ", SPH a=0 " << sph0.gamma);
  CHECK(r075.gamma > r425.gamma);
  CHECK(r425.gamma > r1625.gamma);
  CHECK(r075.gamma > 1e-3);
  // negligible at r >~ 10: within the time-stepping drift of inviscid SPH
  CHECK(std::abs(r1625.gamma - sph0.gamma) < 1e-4);
  CHECK(sph01.gamma >= r425.gamma);
  for (const auto* w : {&r075, &r425, &r1625, &sph01, &sph0}) CHECK(std::abs(w->phase_error) < 0.01);
  CHECK(r425.regularizations == 4);
}

TEST_CASE("plain SPH is linearly stable at h/Delta = 1.2 and unstable away from it", "[linear_wave]") {
  auto growth = [](const scenes::LinearWaveResult& w) {
    return std::max(w.noise_final / w.noise_initial, std::max(w.amplitude_growth, 1.0 / w.amplitude_growth));
  };
  const auto stable_q = wave(0.0, 0.0, 1.2, 1e-4, true), stable_c = wave(0.0, 0.0, 1.2, 1e-4, false);
  const auto unstable_q = wave(0.0, 0.0, 1.5, 1e-4, true), unstable_c = wave(0.0, 0.0, 2.0, 1e-4, false);
  INFO("growth: quintic 1.2 " << growth(stable_q) << ", cubic 1.2 " << growth(stable_c) << ", quintic 1.5 "
                              << growth(unstable_q) << ", cubic 2.0 " << growth(unstable_c));
  CHECK(growth(stable_q) < 2.0);
  CHECK(growth(stable_c) < 2.0);
  CHECK(growth(unstable_q) > 10.0);
  CHECK(growth(unstable_c) > 10.0);
}
