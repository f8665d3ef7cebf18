#pragma once
// Keeping a drifted particle inside the box: mirrored back at a reflecting wall, wrapped on a periodic axis.
#include "rsph/core/dimension.hpp"

namespace rsph::boundary {

/// A particle that crossed a reflecting wall is mirrored back (its half-step velocity reversed along that
/// axis); one that left a periodic axis re-enters on the other side.
template <int D>
void keep_inside(const Box<D>& box, Vec<D>& x, Vec<D>& v_half) {
  for (int k = 0; k < D; ++k) {
    if (box.edge[k] == Edge::reflecting) {
      if (x[k] < box.lo[k]) {
        x[k] = 2.0 * box.lo[k] - x[k];
        v_half[k] = -v_half[k];
      }
      if (x[k] > box.hi[k]) {
        x[k] = 2.0 * box.hi[k] - x[k];
        v_half[k] = -v_half[k];
      }
    }
  }
  box.wrap(x);
}

}  // namespace rsph::boundary
