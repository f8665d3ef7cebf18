#pragma once
// The conservative remap of eqs. (6)-(9): old particles -> new lattice particles through the exact
// overlaps Omega_n^o of old Voronoi cells and new lattice cells. Written once for every dimension: the old
// cells and their overlaps come from old_cells_1d.hpp (intervals), old_cells_2d.hpp (polygons) and
// old_cells_3d.hpp (polyhedra); the sums (sums.hpp), the hand-on of nearly empty cells and the new particles
// are the same in all.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/polyhedron.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/old_cells_1d.hpp"
#include "rsph/regularize/old_cells_2d.hpp"
#include "rsph/regularize/old_cells_3d.hpp"
#include "rsph/regularize/old_cells_sites.hpp"
#include "rsph/regularize/owner_sums.hpp"
#include "rsph/regularize/region.hpp"
#include "rsph/regularize/remap_params.hpp"
#include "rsph/regularize/sums.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace rsph::regularize {

namespace detail {

/// Visits every old particle's closed Voronoi cell (2D or 3D) with its overlaps on the cells of `grid`:
/// action(thread, a, cell, overlaps, V_o, cell_volume), the cell relative to x_a, overlaps as (flat index,
/// Omega) and V_o their sum, in their order. The builder may restart (wider periodic images): action.restart()
/// then forgets what it saw. `only` (ascending, empty for all) names the particles whose cells are visited.
template <class Lattice, class Builder, int D, bool E, class Grid, class Region, class Action>
void for_each_old_cell(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                       const Grid& grid, const Region& region, RemapWorkspace<D>& workspace, Action& action,
                       std::span<const std::uint32_t> only = {}) {
  auto visitor = old_cell_visitor(p, box, lattice, grid, region, action);
  builder.build(p.x, box, workspace.closing, visitor, only);
}

/// The distance from an old cell's particle to the cell's farthest vertex.
inline double cell_reach(const geometry::ConvexPolygon& cell) {
  return geometry::max_radius(cell, geometry::Point::Zero());
}
inline double cell_reach(const geometry::ConvexPolyhedron& cell) {
  return std::sqrt(geometry::max_radius2_origin(cell));
}

/// The radius of the disc that closes each old cell at open edges (none when no axis is open).
template <int D, bool E>
void set_closing_radii(const ParticleSet<D, E>& p, const Box<D>& box, const RemapParams& params,
                       std::vector<double>& closing) {
  closing.clear();
  if (std::find(box.edge.begin(), box.edge.end(), Edge::open) != box.edge.end()) {
    closing.resize(p.n_real);
    for (std::size_t a = 0; a < p.n_real; ++a) closing[a] = params.closing_radius_in_h * p.h[a];
  }
}

/// The action of accumulate_overlaps: each old cell's overlaps added to its thread's sums.
template <int D, bool E>
struct AddToSums {
  std::vector<Sums<D>>* sums;
  const ParticleSet<D, E>* p;
  std::vector<double>* reach;  ///< null unless asked for
  void restart() {
    for (auto& s : *sums) s.reset(s.size(), s.sparse);
  }
  template <class Cell>
  void operator()(int thread, std::size_t a, const Cell& cell, std::span<const Overlap> ov, double V_o,
                  double cell_area) {
    if (reach) (*reach)[a] = cell_reach(cell);
    const double e_o = [&] {
      if constexpr (E)
        return p->u[a];
      else
        return 0.0;
    }();
    (*sums)[static_cast<std::size_t>(thread)].add(ov, V_o, p->m[a], p->v[a], e_o, cell_area);
  }
};

/// Eqs. (6)-(9) before the division: for every cell of `grid` (a CellGrid, or the SiteCells of a per-site
/// lattice), the sums over old particles o of
/// (m_o / V_o) Omega_n^o times 1, v_o and the specific total energy, and the covered volume.
/// The sums land in workspace.sums[0], dense over the grid or, past params.dense_cells_per_particle cells per
/// particle and where `allow_sparse`, sparse (sums.hpp). With `record_reach`, workspace.reach receives each
/// old cell's farthest vertex distance (-1 for a cell not built).
template <class Lattice, class Builder, int D, bool E, class Grid, class Region>
Sums<D>& accumulate_overlaps(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                             const RemapParams& params, const Grid& grid, const Region& region,
                             RemapWorkspace<D>& workspace, bool record_reach = false, bool allow_sparse = true,
                             std::span<const std::uint32_t> only = {}) {
  static_assert(check_closing_region<Region, D>());
  static_assert(D > 1 || !Region::clips, "closing regions are for 2D and 3D cells");
  const std::size_t n_old = p.n_real;
  auto& sums = workspace.sums;
  const bool sparse = allow_sparse && sum_sparsely(grid.n_cells, n_old, params.dense_cells_per_particle);
  if (!sparse) check_dense_sums_fit<D>(grid.n_cells, n_old);
  clear_sums(sums, grid.n_cells, sparse);
  auto specific_energy = [&](std::size_t a) {
    if constexpr (E)
      return p.u[a];
    else
      return 0.0;
  };

  if (record_reach) workspace.reach.assign(n_old, -1.0);  // -1: not built (`only` leaves it out)
  if constexpr (D == 1) {
    for_each_old_interval(p, box, lattice, params, grid,
                          [&](std::size_t a, double left, double right, const auto& overlaps, double V_o) {
                            if (!only.empty() && !std::binary_search(only.begin(), only.end(), std::uint32_t(a)))
                              return;
                            if (record_reach) workspace.reach[a] = std::max(p.x[a][0] - left, right - p.x[a][0]);
                            sums[0].add(overlaps, V_o, p.m[a], p.v[a], specific_energy(a), right - left);
                          });
  } else {
    set_closing_radii(p, box, params, workspace.closing);
    AddToSums<D, E> add{&sums, &p, record_reach ? &workspace.reach : nullptr};
    for_each_old_cell(p, box, lattice, builder, grid, region, workspace, add, only);
  }

  reduce_sums(sums);
  return sums[0];
}

/// Hands the share of every new cell that gets no particle on, so mass stays exactly conserved: a cell
/// covered over less than min_fill of its volume, or lighter than min_mass_ratio of the heaviest, goes to
/// its fullest kept neighbour or, lacking one, to its heaviest neighbour that outweighs it (passes repeat,
/// so shares flow towards kept cells along rising mass); a cell with no such neighbour keeps its particle.
/// `volume(c)` is the volume of cell c; `for_each_neighbour(c, f)` calls f(g) for the cells g next to c.
/// Fills the keep flags; `handed_on` counts the cells whose share moved.
/// `part`: on many ranks, the heaviest is every rank's. `elsewhere` (empty in one process): the cells another
/// rank keeps, whose hand-on is read here and counted there.
template <int D, class Volume, class ForEachNeighbour>
void hand_on_sparse_cells(Sums<D>& S, const RemapParams& params, Volume&& volume, ForEachNeighbour&& for_each_neighbour,
                          std::size_t& handed_on, std::vector<std::uint8_t>& keep, const RankPart& part = {},
                          std::span<const std::uint8_t> elsewhere = {}) {
  const std::size_t n_cells = S.size();
  keep.resize(n_cells);
  double heaviest = 0.0;
  if (params.min_mass_ratio > 0.0) {
    for (const auto& c : S.cell) heaviest = std::max(heaviest, c.m);
    heaviest = part.max(heaviest);
  }
  const double min_mass = params.min_mass_ratio > 0.0 ? params.min_mass_ratio * heaviest : 0.0;
  rsph::run_parallel(n_cells, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c)
      keep[c] = S.cell[c].volume > params.min_fill * volume(c) && S.cell[c].m > 0.0 && S.cell[c].m >= min_mass;
  });
  // Among kept neighbours covered alike (full ones, mostly) the first in the neighbours' geometric order takes
  // the share: a later one must be fuller by more than round-off, so that the choice does not hang on the order
  // in which the overlaps were summed (the same on every rank of a decomposed run).
  constexpr double fuller = 1.0 + 1e-9;
  auto best_neighbour = [&](std::size_t c) {
    std::int64_t kept_best = -1, heavy_best = -1;
    double best_fill = 0.0, best_mass = S.cell[c].m;
    for_each_neighbour(c, [&](std::size_t g) {
      if (keep[g] && S.cell[g].volume > best_fill * fuller) {
        kept_best = static_cast<std::int64_t>(g);
        best_fill = S.cell[g].volume;
      }
      if (!keep[g] && S.cell[g].m > best_mass) {
        heavy_best = static_cast<std::int64_t>(g);
        best_mass = S.cell[g].m;
      }
    });
    return kept_best >= 0 ? kept_best : heavy_best;
  };
  handed_on = 0;
  std::vector<double> moved_fill;  // allocated only when some share moves
  for (bool moved = true; moved;) {
    moved = false;
    for (std::size_t c = 0; c < n_cells; ++c) {
      if (keep[c] || S.cell[c].m == 0.0) continue;
      const std::int64_t best = best_neighbour(c);
      if (best < 0) continue;
      const auto b = static_cast<std::size_t>(best);
      Conserved<D> share = S.cell[c];  // mass, momentum and energy move; the volume follows below
      share.volume = 0.0;
      S.cell[b] += share;
      if (moved_fill.empty()) moved_fill.assign(n_cells, 0.0);
      moved_fill[b] += S.cell[c].volume + moved_fill[c];  // the volume goes with the mass (rho = m / volume)
      moved_fill[c] = 0.0;
      S.cell[c] = Conserved<D>{0.0, Vec<D>::Zero(), 0.0, S.cell[c].volume};
      handed_on += elsewhere.empty() || !elsewhere[c];
      moved = true;
    }
  }
  for (std::size_t c = 0; c < n_cells; ++c) {
    if (!keep[c] && S.cell[c].m > 0.0) keep[c] = 1;  // no neighbour to take its share
    if (!moved_fill.empty()) S.cell[c].volume += moved_fill[c];
  }
}

/// Replaces `p` by one new particle per kept cell, in the order of `cells`: eq. (6) mass, eq. (8)
/// velocity, and u taking up the kinetic energy the averaging removed (eq. 9); rho is set to the mass over
/// the covered volume (a kernel-summed density overwrites it). `place(c)` gives the
/// site and smoothing length of cell c. The statistics count the first `n_own` old particles (on many ranks this
/// rank's own, before the others' it gathered) and every new one.
template <int D, bool E, class Place>
void emit_particles(ParticleSet<D, E>& p, const Sums<D>& S, const std::vector<std::uint8_t>& keep,
                    const std::vector<std::size_t>& cells, Place&& place, RemapStats& stats,
                    std::size_t n_own = std::numeric_limits<std::size_t>::max()) {
  stats.n_before = std::min(n_own, p.n_real);
  double ke_before = 0.0;
  for (std::size_t a = 0; a < stats.n_before; ++a) ke_before += 0.5 * p.m[a] * p.v[a].squaredNorm();
  auto emitted = [&](std::size_t c) { return keep[c] && S.cell[c].m > 0.0; };
  // Written in parallel, each thread a contiguous run of `cells`, in the order of `cells` whatever the thread
  // count. The old particles are spent (their sums are in S): the new ones take over their storage, every
  // field written once (clearing it first would write the whole set twice).
  std::vector<double> ke_after(static_cast<std::size_t>(max_threads()), 0.0);
  p.n_real = run_parallel_packed(
      cells.size(),
      [&](std::size_t begin, std::size_t end) {
        std::size_t n = 0;
        for (std::size_t k = begin; k < end; ++k) n += emitted(cells[k]);
        return n;
      },
      [&](std::size_t n_new) {
        p.ghost_source.clear();
        p.resize_all(n_new);
      },
      [&](int t, std::size_t begin, std::size_t end, std::size_t first) {
        std::size_t a = first;
        double ke_sum = 0.0;
        for (std::size_t k = begin; k < end; ++k) {
          const std::size_t c = cells[k];
          if (!emitted(c)) continue;
          const Conserved<D>& sum = S.cell[c];
          const double m_n = sum.m;
          const Vec<D> v_n = sum.mv / m_n;  // eq. (8)
          const double ke = 0.5 * m_n * v_n.squaredNorm();
          ke_sum += ke;
          const auto [site, h] = place(c);
          p.m[a] = m_n;
          p.x[a] = site;
          p.v[a] = v_n;
          p.h[a] = h;
          p.rho[a] = m_n / sum.volume;  // the remapped density, for schemes that do not sum eq. (2)
          if constexpr (E) p.u[a] = std::max(0.0, (sum.E - ke) / m_n);  // eq. (9) plus the converted kinetic energy
          ++a;
        }
        ke_after[static_cast<std::size_t>(t)] = ke_sum;
        p.clear_all_but_state(first, a);  // as whole runs: faster than a store each in the loop
      });
  stats.n_after = p.n_real;
  stats.kinetic_converted = ke_before;
  for (double ke : ke_after) stats.kinetic_converted -= ke;
}

/// Calls f(g) for the up to 3^D - 1 cells of `grid` around cell c (wrapping periodic axes).
template <int D, class F>
void for_each_grid_neighbour(const CellGrid<D>& grid, std::size_t c, F&& f) {
  for_each_cell_within(grid, c, 1, f);
}

/// The end of every remap: the shares of nearly empty cells handed on, and one new particle per kept cell (each
/// entry of S, dense or sparse), in the order of S, with h = h_over_dx * Delta. `volume(c)` is grid cell c's
/// volume, `for_each_neighbour(c, f)` calls f(g) for the grid cells next to it, `site(c)` is its site.
template <int D, bool E, class Volume, class ForEachNeighbour, class Site>
void hand_on_and_emit(ParticleSet<D, E>& p, Sums<D>& S, const RemapParams& params, double spacing, Volume&& volume,
                      ForEachNeighbour&& for_each_neighbour, Site&& site, RemapWorkspace<D>& ws, RemapStats& stats,
                      const RankPart& part = {}) {
  auto& keep = ws.keep;
  hand_on_sparse_cells<D>(
      S, params, [&](std::size_t c) { return volume(S.flat(c)); },
      [&](std::size_t c, auto&& f) {
        for_each_neighbour(S.flat(c), [&](std::size_t g) {
          if (const std::int64_t e = S.find(g); e >= 0) f(static_cast<std::size_t>(e));
        });
      },
      stats.dropped_cells, keep, part, ws.elsewhere);
  for (std::size_t c = 0; c < ws.elsewhere.size(); ++c)
    if (ws.elsewhere[c]) keep[c] = 0;  // another rank's cell: its hand-on was read, its particle is born there
  auto& order = ws.order;
  order.resize(S.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const double h_new = params.h_over_dx * spacing;
  emit_particles(
      p, S, keep, order,
      [&](std::size_t c) {
        return std::pair{site(S.flat(c)), h_new};
      },
      stats, part.own);
  stats.per_level = {stats.n_after};
}

/// The end of a remap onto one lattice of congruent cells, in lattice order.
template <class Lattice, int D, bool E>
void emit_on_lattice(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, const RemapParams& params,
                     const CellGrid<D>& grid, Sums<D>& S, RemapWorkspace<D>& ws, RemapStats& stats,
                     const RankPart& part = {}) {
  const double cell_volume = lattice.cell_volume();
  hand_on_and_emit(
      p, S, params, lattice.spacing, [&](std::size_t) { return cell_volume; },
      [&](std::size_t c, auto&& f) { for_each_grid_neighbour(grid, c, f); },
      [&](std::size_t c) { return lattice.site(box, grid.unflat(c)); }, ws, stats, part);
}

/// The end of a remap onto a lattice of per-site cells: each cell's volume for the hand-on the area a full one
/// holds, its neighbours the sites' own.
template <class Lattice, bool E, SiteCells Sites>
void emit_on_lattice(ParticleSet<2, E>& p, const Box<2>&, const Lattice& lattice, const RemapParams& params,
                     const Sites& sites, Sums<2>& S, RemapWorkspace<2>& ws, RemapStats& stats,
                     const RankPart& part = {}) {
  hand_on_and_emit(
      p, S, params, lattice.spacing, [&](std::size_t c) { return sites.nominal_area(c); },
      [&](std::size_t c, auto&& f) { sites.for_each_neighbour(c, f); }, [&](std::size_t c) { return sites.site(c); },
      ws, stats, part);
}

/// The new cells a remap sums into: the candidate grid of a lattice of congruent cells, or the sites a
/// per-site lattice places for the particles, with their cells.
template <class Lattice, int D, bool E>
auto new_cells(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, const RemapParams& params,
               const RankPart& part) {
  if constexpr (PerSiteLattice<Lattice>)
    return site_cells(p, box, lattice, params, part);
  else
    return candidate_grid(p, box, lattice, params);
}

/// The remap by owners: calls f(cells, emit_cells) with the new cells as the ranks name them and the cells the
/// emission reads. A lattice fixed by the box: the flat index on the grid of the whole set, alike on every rank
/// (GridCells), and that grid; a per-site lattice: the sites' own numbers (SitesOnRanks), and the sites. `grid`:
/// the new cells this rank sums into (new_cells).
template <class Lattice, int D, bool E, class Grid, class F>
void with_cells_of_ranks(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice,
                         const RemapParams& params, const Grid& grid, const RankPart& part, F&& f) {
  if constexpr (PerSiteLattice<Lattice>) {
    f(SitesOnRanks<Grid>{&grid}, grid);
  } else {
    const auto whole = candidate_grid(p, box, lattice, params, 1, part);
    f(GridCells<D, Lattice>{&whole, &grid, &box, &lattice}, whole);
  }
}

/// The remap's input, refused with the cause. `part`: on many ranks, a rank may hold no particles (it takes part in
/// the remap's exchanges all the same); the run must.
template <class Lattice, int D, bool E>
void check_remap_input(const ParticleSet<D, E>& p, const Lattice& lattice, const RemapParams& params,
                       const RankPart& part = {}) {
  static_assert(Lattice::dim == D, "the lattice's dimension differs from the particles'");
  params.validate();
  require(lattice.spacing > 0.0, "regularization: the lattice spacing must be positive");
  require(p.n_ghost() == 0, "regularization: remove ghosts before remapping");
  require(part.max(static_cast<double>(p.n_real)) > 0.0, "regularization: no particles to remap");
  auto refuse = [](std::size_t a, const std::string& what) {
    throw InputError("regularization: particle " + std::to_string(a) + ": " + what);
  };
  double total = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    if (!(std::isfinite(p.m[a]) && p.m[a] >= 0.0))
      refuse(a, "mass must be finite and non-negative (got " + std::to_string(p.m[a]) + ")");
    if (!p.x[a].allFinite()) refuse(a, "position is not finite");
    if (!p.v[a].allFinite()) refuse(a, "velocity is not finite");
    if constexpr (E)
      if (!(std::isfinite(p.u[a]) && p.u[a] >= 0.0))
        refuse(a, "internal energy must be finite and non-negative (got " + std::to_string(p.u[a]) + ")");
    total += p.m[a];
  }
  require(part.max(total) > 0.0, "regularization: every mass is zero: nothing to remap");
}

}  // namespace detail

/// Remaps `p` (real particles only, no ghosts) onto `lattice`; returns the statistics. New particles
/// are stored in lattice order with h = h_over_dx * Delta; u absorbs the kinetic energy lost when the
/// gas carries it. `region` closes the cells at open edges (region.hpp).
/// `workspace` (optional) keeps scratch storage between remaps. `part`: on many ranks, the old particles whose
/// cells are built (the sites the others alone would feed are left light or empty) and the reduction over ranks.
template <class Lattice, class Builder, int D, bool E, class Region = region::Unbounded>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                              const RemapParams& params, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr, const RankPart& part = {}) {
  detail::check_remap_input(p, lattice, params, part);
  RemapWorkspace<D> local;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  const auto grid = detail::new_cells(p, box, lattice, params, part);
  auto& S = detail::accumulate_overlaps(p, box, lattice, builder, params, grid, region, ws, part.by_owners(), true,
                                        part.cells);
  RemapStats stats;
  stats.max_volume_mismatch = S.max_mismatch;
  ws.elsewhere.clear();
  if (part.by_owners()) {  // the sums travel by their cell's number as every rank names it
    const bool complete = detail::cells_complete(p, ws.reach, part);
    auto by_owners = [&](const auto& cells, const auto& emit_cells) {
      S = detail::complete_on_owners(detail::numbered_for_ranks(S, cells), cells, part, complete, ws.elsewhere);
      detail::emit_on_lattice(p, box, lattice, params, emit_cells, S, ws, stats, part);
    };
    detail::with_cells_of_ranks(p, box, lattice, params, grid, part, by_owners);
    return stats;
  }
  detail::emit_on_lattice(p, box, lattice, params, grid, S, ws, stats, part);
  return stats;
}

}  // namespace rsph::regularize
