// A lattice without a spacing: the regularizer says what it lacks.
#include "rsph/rsph.hpp"
struct NoSpacing {
  static constexpr int dim = 2;
};
int main() {
  using namespace rsph;
  regularize::LatticeRegularizer<NoSpacing, schedule::EveryNSteps> reg(NoSpacing{}, schedule::EveryNSteps{});
  (void)reg;
}
