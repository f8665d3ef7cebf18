#pragma once
// The second-order remap onto multi-level lattices: the second-order sums on the finest cells, then the
// multi-level remap's levels, face cells and emission (multilevel.hpp). The face cells take their shares by a
// first-order hand-out over their Voronoi cells, so the old cells that reach a face cell hand out at first
// order everywhere: each old cell stays exactly conservative.
#include "rsph/regularize/multilevel.hpp"
#include "rsph/regularize/second_order/remap_second.hpp"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph::regularize {

template <int D, class Criterion, class Builder, bool E, class Region = region::Unbounded>
RemapStats remap_second_order(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                              Builder& builder, const RemapParams& params, const SecondOrderParams& second,
                              const Region& region = {}, RemapWorkspace<D>* workspace = nullptr,
                              second_order::Workspace<D>* ws2 = nullptr, const RankPart& part = {}) {
  ml.validate();
  second.validate();
  RemapWorkspace<D> local;
  second_order::Workspace<D> local2;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  second_order::Workspace<D>& w2 = ws2 ? *ws2 : local2;
  const auto fine = ml.finest();
  detail::check_remap_input(p, fine, params, part);
  detail::check_whole_blocks(box, ml);
  const auto grids = detail::level_grids(p, box, ml, params, part);
  const auto& grid = grids.local;
  auto sums_on = [&](const detail::CellGrid<D>& g, RemapStats& stats) -> detail::Sums<D>& {
    auto& S = second_order::second_order_sums(p, box, fine, builder, params, second, region, g, ws, w2, stats, false,
                                              part.cells);
    if constexpr (D == 2) ws.reach = w2.cells.reach;  // the face hand-out builds again the cells reaching a face
    if (part.on_ranks()) stats.limited_cells = second_order::limited_among(w2, part.own);  // others' built here too
    return S;
  };
  auto at_faces = [&](const auto& fp, const detail::Faces& faces, RemapStats& stats) -> detail::Sums<D>& {
    std::vector<std::uint8_t> in_face(grid.n_cells);
    for (std::size_t f = 0; f < grid.n_cells; ++f) in_face[f] = faces.face_of[fp.owner[f]] >= 0;
    const std::size_t taken = second_order::take_to_first_order(p.n_real, in_face, w2);
    if (taken > 0) {
      stats.first_order_cells += taken;
      second_order::hand_out_above_floor(p, p.n_real, second, grid.n_cells, ws, w2, stats);
    }
    return ws.sums[0];
  };
  auto stats = detail::remap_onto_levels(p, box, ml, builder, params, region, ws, grids, sums_on, at_faces, part);
  if (part.on_ranks()) stats.first_order_cells = second_order::first_order_among(w2, part.own);
  return stats;
}

}  // namespace rsph::regularize
