#pragma once
// Scenes that start on a lattice of levels in factors of two: the state is laid on the finest lattice
// everywhere, then remapped once onto the levels the density-jump criterion picks.
#include "rsph/rsph.hpp"

#include <cstdint>
#include <string>

namespace rsph::examples {

/// The level lattice's parameters, one set for every scene that refines by density jumps.
struct DensityJumpLevels {
  int levels = 0;               ///< finest level L (0: one level)
  int block_cells = 2;          ///< level-0 cells per block and axis
  double refine_above = 0.1;    ///< relative density jump between level-0 cells that refines a block
  double coarsen_below = 0.03;  ///< ... and below which it returns to level 0
  double h_ramp = 2.0;          ///< coarser spacings over which h rises towards a coarser block

  /// `scene` names the caller in the messages; levels above max_levels are refused.
  void validate(const std::string& scene, int max_levels) const {
    require(levels >= 0 && levels <= max_levels,
            scene + ": --levels must lie in [0, " + std::to_string(max_levels) + "]");
    require(block_cells >= 1, scene + ": --block-cells must be at least 1");
  }
  /// Finest cells along one side of a block.
  std::int64_t fine_cells_per_block() const { return (std::int64_t{1} << levels) * block_cells; }
};

/// The lattice of `c` whose finest spacing is dx_finest, with p remapped onto it (rho = m / V).
template <int D, bool E>
lattice::MultiLevel<D, refine::DensityJump> start_on_levels(ParticleSet<D, E>& p, const Box<D>& box, double dx_finest,
                                                            const DensityJumpLevels& c,
                                                            const regularize::RemapParams& remap) {
  lattice::MultiLevel<D, refine::DensityJump> ml(dx_finest * static_cast<double>(std::int64_t{1} << c.levels), c.levels,
                                                 c.block_cells,
                                                 refine::DensityJump{c.refine_above, c.coarsen_below, c.levels});
  ml.h_ramp = c.h_ramp;
  geometry::LocalVoronoi builder;
  regularize::remap_onto_lattice(p, box, ml, builder, remap);
  return ml;
}

}  // namespace rsph::examples
