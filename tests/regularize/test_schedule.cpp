#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace rsph;

namespace {

using Kernel = kernel::CubicSpline;
using RSPH = Simulation<2, Kernel, eos::IdealGas,
                        regularize::LatticeRegularizer<lattice::Square, schedule::Adaptive<Kernel, 2>>>;

// A periodic lattice of spacing scale * Delta, with h = 1.2 Delta: scale < 1 compresses, > 1 expands.
ParticleSet<2, true> scaled_lattice(int n, double scale) {
  ParticleSet<2, true> p;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      p.add(dx * dx, Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), 1.2 * dx / scale, 1.0);
    }
  return p;
}

bool adaptive_fires(double scale, schedule::Adaptive<Kernel, 2> adaptive) {
  Box<2> box;
  box.edge = {Edge::periodic, Edge::periodic};
  RSPH sim(scaled_lattice(24, scale), box, eos::IdealGas{1.4},
           regularize::LatticeRegularizer<lattice::Square, schedule::Adaptive<Kernel, 2>>(lattice::Square{1.0 / 24},
                                                                                          adaptive),
           TimeStepParams{});
  StepInfo info;
  info.neighbors = &sim.neighbor_list();
  auto& schedule = sim.regularizer().schedule();
  const bool fires = schedule.due(sim.particles(), box, info);
  info.number_density = sim.number_density();  // the driver's eq. (A1) sums decide the same
  REQUIRE(schedule.due(sim.particles(), box, info) == fires);
  return fires;
}

}  // namespace

TEST_CASE("Appendix A neighbour numbers: N(h/Delta = 1.1) = 9.5 and N(5) = 308 as the paper says", "[schedule]") {
  // N = V(h) n with n = (lattice sum - W(0)) / Delta^2: the paper's N_min and N_max are these values.
  auto N_of = [](double eta) { return schedule::Adaptive<Kernel, 2>::lattice_neighbour_number(eta); };
  CHECK(N_of(1.1) == Approx(9.5).margin(0.1));
  CHECK(N_of(5.0) == Approx(308.0).margin(1.0));
  CHECK(N_of(0.9) == Approx(4.5).margin(0.1));  // §5
  CHECK(N_of(3.0) == Approx(107.0).margin(1.0));
}

TEST_CASE("Appendix A in 3D: bounds from h/Delta on a cubic lattice; the schedule fires as the lattice deforms",
          "[schedule][3d]") {
  using A3 = schedule::Adaptive<Kernel, 3>;
  // the ball of radius 2h holds (4/3) pi (2 h/Delta)^3 sites, less the particle's own weight
  const double N_11 = A3::lattice_neighbour_number(1.1), N_5 = A3::lattice_neighbour_number(5.0);
  CHECK(N_11 == Approx(4.0 / 3.0 * M_PI * std::pow(2.2, 3) * (1.0 - kernel::W<Kernel, 3>(0.0, 1.1))).epsilon(0.05));
  CHECK(N_5 == Approx(4.0 / 3.0 * M_PI * 1000.0).epsilon(0.01));
  const A3 bounds = A3::for_h_over_dx(1.1, 1.5, 0.4, 128);
  CHECK(bounds.N_min == Approx(N_11));
  using RSPH3 = Simulation<3, Kernel, eos::IdealGas, regularize::LatticeRegularizer<lattice::Cubic, A3>>;
  auto fires = [&](double scale) {
    const int n = 8;
    const double dx = 1.0 / n;
    ParticleSet<3, true> p;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          p.add(dx * dx * dx, Vec<3>((i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx), Vec<3>::Zero(), 1.2 * dx / scale,
                1.0);
    Box<3> box;
    box.edge = {Edge::periodic, Edge::periodic, Edge::periodic};
    RSPH3 sim(std::move(p), box, eos::IdealGas{5.0 / 3.0},
              regularize::LatticeRegularizer<lattice::Cubic, A3>(lattice::Cubic{dx}, bounds), TimeStepParams{});
    StepInfo info;
    info.neighbors = &sim.neighbor_list();
    return sim.regularizer().schedule().due(sim.particles(), box, info);
  };
  CHECK_FALSE(fires(1.0));  // h/Delta = 1.2
  CHECK(fires(1.25));       // expanded: h/Delta = 0.96
  CHECK(fires(0.7));        // compressed: h/Delta = 1.7
}

TEST_CASE("the adaptive schedule fires on compressed and expanded lattices and is quiet on a regular one",
          "[schedule]") {
  schedule::Adaptive<Kernel, 2> a{9.5, 20.0, 0.4, 128};  // N_max low enough to see h/Delta = 1.5
  CHECK_FALSE(adaptive_fires(1.0, a));                   // h/Delta = 1.2: N = 12.4
  CHECK(adaptive_fires(1.25, a));                        // expanded: h/Delta = 0.96
  CHECK(adaptive_fires(0.8, a));                         // compressed: h/Delta = 1.5
  schedule::Adaptive<Kernel, 2> paper{9.5, 308.0, 0.4, 128};
  CHECK_FALSE(adaptive_fires(1.0, paper));
  CHECK(adaptive_fires(0.2, paper));  // h/Delta = 6
}

TEST_CASE("the density pass sums eq. (A1) exactly as the schedule's own pass does", "[schedule]") {
  Box<2> box;
  box.edge = {Edge::periodic, Edge::periodic};
  auto p = scaled_lattice(24, 1.0);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    p.x[a] += Vec<2>(0.011 * std::sin(37.0 * a), 0.013 * std::cos(53.0 * a));  // off the lattice
    p.x[a] -= p.x[a].array().floor().matrix();
    if (p.x[a][1] < 0.5) p.h[a] *= 1.3;  // two smoothing lengths
  }
  RSPH sim(p, box, eos::IdealGas{1.4},
           regularize::LatticeRegularizer<lattice::Square, schedule::Adaptive<Kernel, 2>>(
               lattice::Square{1.0 / 24}, schedule::Adaptive<Kernel, 2>{}),
           TimeStepParams{});
  const auto& schedule = sim.regularizer().schedule();
  const auto N = schedule.neighbour_numbers(sim.particles(), sim.neighbor_list());
  const auto& n = sim.number_density();
  double worst = 0.0;
  for (std::size_t a = 0; a < N.size(); ++a)
    worst = std::max(worst, std::abs(schedule.interaction_volume(sim.particles().h[a]) * n[a] - N[a]) / N[a]);
  CHECK(worst < 1e-13);
}

TEST_CASE("the adaptive schedule fires on a local jump in neighbour number (eq. A6)", "[schedule]") {
  Box<2> box;
  box.edge = {Edge::periodic, Edge::periodic};
  auto p = scaled_lattice(24, 1.0);
  for (std::size_t a = 0; a < p.n_real; ++a)
    if (p.x[a][0] < 0.5) p.h[a] *= 1.6;
  RSPH sim(p, box, eos::IdealGas{1.4},
           regularize::LatticeRegularizer<lattice::Square, schedule::Adaptive<Kernel, 2>>(
               lattice::Square{1.0 / 24}, schedule::Adaptive<Kernel, 2>{1.0, 1000.0, 0.4, 128}),
           TimeStepParams{});
  StepInfo info;
  info.neighbors = &sim.neighbor_list();
  CHECK(sim.regularizer().schedule().due(sim.particles(), box, info));
  CHECK(sim.regularizer().schedule().last_reason == 3);
}

TEST_CASE("RSPH in a simulation: regularizes every T_reg exactly and conserves across it", "[schedule]") {
  using Reg = regularize::LatticeRegularizer<lattice::Square, schedule::EveryT>;
  using Sim = Simulation<2, Kernel, eos::IdealGas, Reg, physics::ArtificialViscosity>;
  ParticleSet<2, true> p;
  const int n = 20;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      p.add(dx * dx, Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>(0.3 + 0.05 * std::sin(6.283 * j * dx), 0.0),
            1.2 * dx, 1.0);
  Box<2> box;
  box.edge = {Edge::periodic, Edge::periodic};
  Sim sim(p, box, eos::IdealGas{1.4}, Reg(lattice::Square{dx}, schedule::EveryT{0.01}), TimeStepParams{},
          physics::ArtificialViscosity{0.0, 0.0});
  const auto start = sim.totals();
  sim.run_until(0.1);
  CHECK(sim.regularizations() == 10);
  for (const auto& r : sim.regularizer().log()) CHECK(std::fmod(r.time + 1e-12, 0.01) < 1e-9);
  const auto end = sim.totals();
  CHECK(end.mass == Approx(start.mass).epsilon(1e-13));
  CHECK((end.momentum - start.momentum).norm() < 1e-13);
  CHECK(end.total_energy() == Approx(start.total_energy()).epsilon(1e-4));
  CHECK(sim.kinetic_energy_removed() > 0.0);
}

TEST_CASE("step schedule: every c_r steps", "[schedule]") {
  schedule::EveryNSteps s{40};
  StepInfo info;
  info.steps_since_last = 39;
  ParticleSet<2, false> p;
  Box<2> box;
  CHECK_FALSE(s.due(p, box, info));
  info.steps_since_last = 40;
  CHECK(s.due(p, box, info));
  CHECK_THROWS_WITH(schedule::EveryNSteps{0}.validate(), Catch::Contains("at least 1"));
}
