// A downstream program: a uniform periodic 2D gas must keep its density under plain SPH.
#include <rsph/rsph.hpp>

#include <cmath>
#include <cstdio>

int main() {
  using namespace rsph;
  ParticleSet<2, true> p;
  const int n = 16;
  const double dx = 1.0 / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) p.add(dx * dx, Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), 1.2 * dx, 1.0);
  Box<2> box;
  box.edge = {Edge::periodic, Edge::periodic};
  Simulation<2, kernel::CubicSpline, eos::IdealGas, regularize::None> sim(p, box, eos::IdealGas{1.4}, {}, {});
  for (int s = 0; s < 10; ++s) sim.step();
  const double rho = sim.particles().rho[0];
  std::printf("downstream: %zu particles, rho = %.6f after %llu steps\n", sim.particles().n_real, rho,
              static_cast<unsigned long long>(sim.steps()));
  return std::abs(rho - kernel::lattice_sum<kernel::CubicSpline, 2>(1.2)) < 1e-9 ? 0 : 1;
}
