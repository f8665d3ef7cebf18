// GradH<2> in a 1D simulation: refused at compile time, not at run time.
#include "rsph/rsph.hpp"
int main() {
  using namespace rsph;
  using Sim = Simulation<1, kernel::CubicSpline, eos::IdealGas, regularize::None, physics::GradH<2>>;
  Sim sim({}, {}, eos::IdealGas{1.4}, {}, {}, physics::GradH<2>{});
}
