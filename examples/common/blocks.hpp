#pragma once
// The sites of a block of a Cartesian lattice: how the scenes lay out their particles, in 1D, 2D and 3D alike.
#include "rsph/core/dimension.hpp"

#include <array>

namespace rsph::examples {

/// f(x, i) at the centre x of every cell i of a block of n[0] x n[1] x n[2] cells (the first D counts), its
/// corner at `lo`, spacing[k] apart along axis k: x[k] = lo[k] + (i[k] + 0.5) spacing[k]; x fastest, then y, z.
template <int D, class F>
void for_each_block_site(const std::array<int, 3>& n, const Vec<D>& lo, const Vec<D>& spacing, F&& f) {
  std::array<int, 3> i{0, 0, 0};
  for (i[2] = 0; i[2] < (D == 3 ? n[2] : 1); ++i[2])
    for (i[1] = 0; i[1] < (D >= 2 ? n[1] : 1); ++i[1])
      for (i[0] = 0; i[0] < n[0]; ++i[0]) {
        Vec<D> x;
        for (int k = 0; k < D; ++k) x[k] = lo[k] + (i[static_cast<std::size_t>(k)] + 0.5) * spacing[k];
        f(x, i);
      }
}

}  // namespace rsph::examples
