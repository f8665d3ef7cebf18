#pragma once
// The second-order remap onto multi-level lattices: the second-order sums on the finest cells, then the
// multi-level remap's levels, face cells and emission (multilevel.hpp). The face cells take their shares by a
// first-order hand-out over their Voronoi cells, so the old cells that reach a face cell hand out at first
// order everywhere: each old cell stays exactly conservative.
#include "rsph/regularize/multilevel.hpp"
#include "rsph/regularize/second_order/remap_second.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
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
  // On many ranks, the remap by owners on the finest cells: the fits, the limiter's bounds and the thermal floor
  // read what the other ranks' cells hold (on_owners.hpp), and each rank keeps the complete sums of the finest cells
  // it keeps, so that the ranks' sums add up to one process's (multilevel.hpp sums them into the new cells).
  using Owners = second_order::ByOwners<D, detail::GridCells<D, decltype(fine)>>;
  std::optional<Owners> owners;
  if (part.by_owners()) owners.emplace(part, detail::GridCells<D, decltype(fine)>{&grids.whole, &grid, &box, &fine});
  auto hand_out = [&](RemapStats& stats) {
    if (owners) {
      second_order::hand_out_above_floor(p, part.own, second, grid.n_cells, ws, w2, stats, *owners);
      owners->keep_kept_only(ws.sums[0]);
    } else {
      second_order::hand_out_above_floor(p, p.n_real, second, grid.n_cells, ws, w2, stats);
    }
  };
  auto sums_on = [&](const detail::CellGrid<D>& g, RemapStats& stats) -> detail::Sums<D>& {
    if (owners) {
      second_order::second_order_sums(p, box, fine, builder, params, second, region, g, ws, w2, stats, false,
                                      part.cells, *owners);
      owners->keep_kept_only(ws.sums[0]);
    } else {
      second_order::second_order_sums(p, box, fine, builder, params, second, region, g, ws, w2, stats, false,
                                      part.cells);
    }
    ws.reach = w2.cells.reach;  // the face hand-out builds again the cells reaching a face
    if (part.on_ranks()) stats.limited_cells = second_order::limited_among(w2, part.own);
    return ws.sums[0];
  };
  auto at_faces = [&](const auto& fp, const detail::Faces& faces, RemapStats& stats) -> detail::Sums<D>& {
    std::vector<std::uint8_t> in_face(grid.n_cells);
    for (std::size_t f = 0; f < grid.n_cells; ++f) in_face[f] = faces.face_of[fp.owner[f]] >= 0;
    const std::size_t taken = second_order::take_to_first_order(std::min(part.own, p.n_real), in_face, w2);
    if (owners ? owners->any(taken) : taken > 0) {  // every rank hands out again where any rank took a cell
      stats.first_order_cells += taken;
      hand_out(stats);
    }
    return ws.sums[0];
  };
  auto stats = detail::remap_onto_levels(p, box, ml, builder, params, region, ws, grids, sums_on, at_faces, part);
  if (part.on_ranks()) stats.first_order_cells = second_order::first_order_among(w2, part.own);
  return stats;
}

}  // namespace rsph::regularize
