#pragma once
// What the second-order remap (remap_second.hpp) is told and keeps: its parameters, each old cell's
// reconstruction, the pieces listed per thread, and the scratch kept from one remap to the next.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/neighbors/cell_list.hpp"
#include "rsph/regularize/second_order/cells.hpp"
#include "rsph/regularize/second_order/cells3d.hpp"
#include "rsph/regularize/second_order/reconstruction.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace rsph::regularize {

/// The second-order remap's parameters.
struct SecondOrderParams {
  /// A new particle whose thermal energy u = E/m - v^2/2 comes out below this fraction of the least u of the
  /// old cells that feed it is refilled with those cells handed out at first order (which cannot fall
  /// below it: first-order u is at least the feeders' mass-weighted mean).
  double thermal_floor = 0.5;
  /// Barth-Jespersen limiting of every gradient; off only to study the unlimited reconstruction.
  bool limit = true;

  void validate() const {
    require(thermal_floor >= 0.0 && thermal_floor < 1.0,
            "second-order remap: the thermal floor must lie in [0, 1) (got " + std::to_string(thermal_floor) + ")");
  }
};

namespace second_order {

/// One old cell's unlimited reconstruction, points relative to its particle, and the ranges of its fields
/// over the cell and its neighbours.
template <int D>
struct Reconstruction {
  Vec<D> g_rho = Vec<D>::Zero();  ///< about the centroid
  Vec<D> x_m = Vec<D>::Zero();    ///< mass centroid of the unlimited density, the velocity fit's reference
  Mat<D> G_v = Mat<D>::Zero();    ///< row k: the gradient of v_k, about the mass centroid
  Vec<D> g_e = Vec<D>::Zero();    ///< specific total energy, about the mass centroid
  FieldRanges<D> range;           ///< over the cell and its neighbours
  std::uint8_t limited = 0;       ///< set by the last hand-out if the limiter cut any gradient
};

/// What the shares of one old cell are computed from.
template <int D>
struct OldCell {
  double m = 0.0, e = 0.0;  ///< mass and specific total energy
  Vec<D> v = Vec<D>::Zero();
  Reconstruction<D>* r = nullptr;
};

/// The pieces of the old cells one thread listed, in the order of its cells.
template <int D>
struct Pieces {
  std::vector<std::size_t> flat;
  std::vector<PieceMoments<D>> moments;
  void clear() {
    flat.clear();
    moments.clear();
  }
};

/// The limiter's scratch for one old cell's pieces.
template <int D>
struct HandOutScratch {
  std::vector<Vec<D>> offsets, W;
  std::vector<double> m;
};

/// Scratch kept from one second-order remap to the next.
template <int D>
struct Workspace {
  CellStore<D> cells;
  CellsByThread by_thread;        ///< 2D
  FacesByThread faces_by_thread;  ///< 3D
  neighbors::CellList<D> lookup;
  std::vector<Reconstruction<D>> recon;
  std::vector<std::uint8_t> first_order, bad;
  std::vector<std::vector<double>> u_min;  ///< per thread: the least u of the old cells feeding each new cell
  /// per thread, then reduced into the first: each new cell's bounds, the union of the ranges of the old
  /// cells that overlap it (each over the cell and its neighbours)
  std::vector<std::vector<FieldRanges<D>>> bounds;
  struct alignas(64) PerThread {
    Pieces<D> pieces;
    HandOutScratch<D> scratch;
  };
  std::vector<PerThread> threads;
  /// Where each old cell's pieces are: the thread that listed them, the first and how many.
  std::vector<std::uint32_t> piece_thread, piece_first, piece_count;
};

}  // namespace second_order
}  // namespace rsph::regularize
