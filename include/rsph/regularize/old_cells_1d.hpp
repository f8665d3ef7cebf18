#pragma once
// The old cells of a 1D remap: the intervals between midpoints to the neighbours, and their overlaps on the
// lattice's cells.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

namespace rsph::regularize::detail {

/// 1D old cells: the intervals between midpoints to the neighbours (walls and periodic wrap at the ends,
/// a closing radius on open ends). Calls visit(a, left, right, overlaps, V_o) with the overlaps on the cells of
/// `grid` as (flat index, length), in order of position, and V_o their sum in their order (as in 2D).
template <class Lattice, bool E, class Visit>
void for_each_old_interval(const ParticleSet<1, E>& p, const Box<1>& box, const Lattice& lattice,
                           const RemapParams& params, const CellGrid<1>& grid, Visit&& visit) {
  const std::size_t n_old = p.n_real;
  std::vector<std::uint32_t> order(n_old);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return p.x[a][0] < p.x[b][0]; });
  const double L = box.hi[0] - box.lo[0];
  std::vector<Overlap> overlaps;
  for (std::size_t k = 0; k < n_old; ++k) {
    const std::uint32_t a = order[k];
    const double xa = p.x[a][0];
    if (box.edge[0] != Edge::open && (xa < box.lo[0] || xa > box.hi[0]))  // message built only on failure
      throw InputError("regularization: particle " + std::to_string(a) + " lies outside the domain");
    double left, right;
    const double R = params.closing_radius_in_h * p.h[a];
    if (k > 0)
      left = 0.5 * (xa + p.x[order[k - 1]][0]);
    else if (box.periodic(0))
      left = 0.5 * (xa + p.x[order[n_old - 1]][0] - L);
    else if (box.edge[0] == Edge::reflecting)
      left = box.lo[0];
    else
      left = xa - R;
    if (k + 1 < n_old)
      right = 0.5 * (xa + p.x[order[k + 1]][0]);
    else if (box.periodic(0))
      right = 0.5 * (xa + p.x[order[0]][0] + L);
    else if (box.edge[0] == Edge::reflecting)
      right = box.hi[0];
    else
      right = xa + R;
    if (box.edge[0] == Edge::open) {
      left = std::max(left, xa - R);
      right = std::min(right, xa + R);
    }
    if (!(right > left))
      throw InputError("regularization: particle " + std::to_string(a) + " coincides with another particle");
    overlaps.clear();
    double V_o = 0.0;
    const auto r = lattice.cells_touching(box, Vec<1>(left), Vec<1>(right));
    for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i) {
      const auto [c0, c1] = lattice.cell(box, i);
      const double omega = std::min(right, c1) - std::max(left, c0);
      if (omega <= 0.0) continue;
      std::int64_t f = grid.flat({i});
      if (f < 0) f = grid.flat({std::clamp(i, grid.range.lo[0], grid.range.hi[0])});  // sliver beyond a wall
      overlaps.emplace_back(static_cast<std::size_t>(f), omega);
      V_o += omega;
    }
    visit(static_cast<std::size_t>(a), left, right, overlaps, V_o);
  }
}

}  // namespace rsph::regularize::detail
