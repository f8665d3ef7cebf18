// A term of no known kind: the simulation lists the kinds.
#include "rsph/rsph.hpp"
struct NotATerm {};
int main() {
  using namespace rsph;
  Simulation<2, kernel::CubicSpline, eos::IdealGas, regularize::None, NotATerm> sim({}, {}, eos::IdealGas{1.4}, {}, {},
                                                                                    NotATerm{});
}
