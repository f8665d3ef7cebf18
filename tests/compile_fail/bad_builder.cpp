// A cell builder without build(): the regularizer says what it lacks.
#include "rsph/rsph.hpp"
struct NoBuild {};
int main() {
  using namespace rsph;
  regularize::LatticeRegularizer<lattice::Square, schedule::EveryNSteps, NoBuild> reg(lattice::Square{0.1},
                                                                                      schedule::EveryNSteps{});
  (void)reg;
}
