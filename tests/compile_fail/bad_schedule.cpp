// A schedule without due(): the regularizer says what it lacks.
#include "rsph/rsph.hpp"
struct NoDue {};
int main() {
  using namespace rsph;
  using Reg = regularize::LatticeRegularizer<lattice::Square, NoDue>;
  Simulation<2, kernel::CubicSpline, eos::IdealGas, Reg> sim({}, {}, eos::IdealGas{1.4},
                                                             Reg(lattice::Square{0.1}, NoDue{}), {});
  sim.step();
}
