// A lattice of rectangular cells that does not say where its grid lines are: the regularizer names the member.
#include "rsph/rsph.hpp"
struct NoLines {
  static constexpr int dim = 3;
  static constexpr bool rectangular_cells = true;
  double spacing = 0.1;
  double cell_volume() const { return 1e-3; }
  rsph::IndexRange<3> cells_touching(const rsph::Box<3>&, const rsph::Vec<3>&, const rsph::Vec<3>&) const { return {}; }
  rsph::Vec<3> site(const rsph::Box<3>&, std::array<std::int64_t, 3>) const { return rsph::Vec<3>::Zero(); }
  std::array<std::int64_t, 3> periods(const rsph::Box<3>&) const { return {0, 0, 0}; }
};
int main() {
  using namespace rsph;
  regularize::LatticeRegularizer<NoLines, schedule::EveryNSteps> reg(NoLines{}, schedule::EveryNSteps{});
  (void)reg;
}
