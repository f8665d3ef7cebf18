#pragma once
// The conservative remap of eqs. (6)-(9): old particles -> new lattice particles through the exact
// overlaps Omega_n^o of old Voronoi cells and new lattice cells.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/core/scratch.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/voronoi.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/region.hpp"

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

struct RemapParams {
  double h_over_dx = 1.2;  ///< new h = (h/Delta) Delta
  /// A new cell covered by old cells over less than this fraction of its area gets no particle; its
  /// share goes to the fullest neighbouring cell, so mass stays exactly conserved.
  double min_fill = 1e-9;
  /// Open edges: an old cell is closed by a disc of this radius in units of the particle's h.
  double closing_radius_in_h = 2.0;
  /// A new cell whose mass is below this fraction of the largest new mass is handed on like a nearly
  /// empty one: it keeps far tails of an open flow from spawning particles of negligible mass.
  double min_mass_ratio = 0.0;

  void validate() const {
    require(h_over_dx > 0.0, "regularization: h/Delta must be positive (got " + std::to_string(h_over_dx) + ")");
    require(min_fill >= 0.0 && min_fill < 1.0, "regularization: min_fill must lie in [0, 1)");
    require(closing_radius_in_h > 0.0, "regularization: the closing radius must be positive");
    require(min_mass_ratio >= 0.0 && min_mass_ratio < 1.0, "regularization: min_mass_ratio must lie in [0, 1)");
  }
};

/// What one regularization did.
struct RemapStats {
  std::size_t n_before = 0, n_after = 0;
  double kinetic_converted = 0.0;    ///< kinetic energy turned into heat (or dissipated, without u)
  double max_volume_mismatch = 0.0;  ///< max over old cells of |sum_n Omega_n^o - V_o| / V_o
  std::size_t dropped_cells = 0;     ///< nearly empty new cells whose share was handed on
  /// New particles per resolution level (one entry on a uniform lattice).
  std::vector<std::size_t> per_level;
  /// Multi-level lattices: blocks whose criterion asked for more than the finest level, and the level asked.
  std::size_t capped_blocks = 0;
  int requested_level = 0;
  /// Second-order remap: old cells handed out at first order because a new particle they feed would have
  /// fallen below the thermal floor, and the passes over the overlaps that took (1 when none fell).
  std::size_t first_order_cells = 0;
  int passes = 1;
  /// Second-order remap: old cells whose gradient the limiter cut (phi < 1 for rho, a velocity component or e).
  std::size_t limited_cells = 0;
};

namespace detail {

/// An old cell's overlap with one new cell: (flat index of the new cell, Omega_n^o).
using Overlap = std::pair<std::size_t, double>;

/// Per-thread sums over old particles for each new cell of a dense index grid.
template <int D>
struct alignas(64) Sums {          // one per thread: aligned so that no two threads write to one cache line
  std::vector<double> m, E, fill;  // eq. (6) numerator, total energy m (e + v^2/2), covered volume
  std::vector<Vec<D>> mv;          // eq. (8) numerator
  double max_mismatch = 0.0;

  void resize(std::size_t n) {
    m.assign(n, 0.0);
    E.assign(n, 0.0);
    fill.assign(n, 0.0);
    mv.assign(n, Vec<D>::Zero());
    max_mismatch = 0.0;
  }
  /// Adds old particle (m_o, v_o, e_o) to the cells `idx` with overlaps `omega`; V_o, the sum of the omega
  /// (eq. 7), hands its mass m_o out exactly. `exact_volume` is the cell's own area, for the log.
  void add(std::span<const Overlap> overlaps, double V_o, double m_o, const Vec<D>& v_o, double e_o,
           double exact_volume) {
    if (!(V_o > 0.0)) throw NumericalError("regularization: an old cell overlaps no new cell");
    max_mismatch = std::max(max_mismatch, std::abs(V_o - exact_volume) / exact_volume);
    const double density = m_o / V_o;
    const double specific_energy = e_o + 0.5 * v_o.squaredNorm();
    for (const auto& [n, omega] : overlaps) {
      const double dm = density * omega;  // eq. (6)
      m[n] += dm;
      mv[n] += dm * v_o;             // eq. (8)
      E[n] += dm * specific_energy;  // eq. (9) plus kinetic energy, so total energy is conserved
      fill[n] += omega;
    }
  }
  /// Adds a share (mass, momentum, total energy, covered volume) to cell n: the second-order remap's shares
  /// are integrals of each old cell's reconstruction over the overlaps.
  void add_share(std::size_t n, double dm, const Vec<D>& dmv, double dE, double omega) {
    m[n] += dm;
    mv[n] += dmv;
    E[n] += dE;
    fill[n] += omega;
  }
  /// Adds o's sums of the cells [begin, end); the mismatch is merged by the caller.
  void merge(const Sums& o, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      m[i] += o.m[i];
      E[i] += o.E[i];
      fill[i] += o.fill[i];
      mv[i] += o.mv[i];
    }
  }
};

/// Zeroes the per-thread sums, each thread its own, and, once they are filled, reduces them into the first,
/// split by cells: each cell still adds the threads' sums in thread order, so the result is the serial
/// reduction's to the bit. On two threads the serial passes over the grid had cost a tenth of the remap.
template <int D>
void clear_sums(std::vector<Sums<D>>& sums, std::size_t n_cells) {
  sums.resize(static_cast<std::size_t>(max_threads()));
  rsph::run_parallel(sums.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) sums[t].resize(n_cells);
  });
}
template <int D>
void reduce_sums(std::vector<Sums<D>>& sums) {
  if (sums.size() < 2) return;
  rsph::run_parallel(sums[0].m.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t t = 1; t < sums.size(); ++t) sums[0].merge(sums[t], begin, end);
  });
  for (std::size_t t = 1; t < sums.size(); ++t)
    sums[0].max_mismatch = std::max(sums[0].max_mismatch, sums[t].max_mismatch);
}

}  // namespace detail

/// Scratch a remap fills and empties: kept by a regularizer from one remap to the next, so that a run
/// does not fault in fresh pages for every regularization (that cost as much as the overlaps).
template <int D>
struct RemapWorkspace {
  std::vector<detail::Sums<D>> sums;  ///< per thread
  std::vector<std::uint8_t> keep;
  std::vector<std::size_t> order;
  std::vector<double> closing;
  /// Distance from each old particle to its cell's farthest vertex, when the overlap pass is asked for it
  /// (the multi-level remap finds the few cells that meet a 2:1 face by it).
  std::vector<double> reach;
};

namespace detail {

inline std::int64_t wrap_index(std::int64_t i, std::int64_t period) {
  if (i >= 0 && i < period) return i;  // almost always: spare the integer division
  if (i >= period && i < 2 * period) return i - period;
  if (i < 0 && i >= -period) return i + period;
  i %= period;
  return i < 0 ? i + period : i;
}

/// The dense block of candidate new cells a remap accumulates into: an index range per axis, wrapped
/// on periodic axes.
template <int D>
struct CellGrid {
  IndexRange<D> range;
  std::array<std::int64_t, D> count{}, periods{};
  std::size_t n_cells = 0;

  /// Flat index of a cell, wrapping periodic axes; -1 outside the grid.
  std::int64_t flat(std::array<std::int64_t, D> idx) const {
    std::int64_t f = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      std::int64_t i = idx[kk];
      if (periods[kk] > 0) i = wrap_index(i, periods[kk]);
      i -= range.lo[kk];
      if (i < 0 || i >= count[kk]) return -1;
      f = f * count[kk] + i;
    }
    return f;
  }
  /// One integer division per axis but the last (f lies in the grid): the new set asks this of every cell.
  std::array<std::int64_t, D> unflat(std::size_t f) const {
    std::array<std::int64_t, D> idx;
    for (int k = 0; k + 1 < D; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      const std::size_t rest = f / static_cast<std::size_t>(count[kk]);
      idx[kk] = range.lo[kk] + static_cast<std::int64_t>(f - rest * static_cast<std::size_t>(count[kk]));
      f = rest;
    }
    idx[D - 1] = range.lo[D - 1] + static_cast<std::int64_t>(f);
    return idx;
  }
};

/// The candidate cells: the whole box on closed axes, the particles' extent plus the closing radius on
/// open ones, there rounded out to whole multiples of `align` cells (counted from box.lo).
template <class Lattice, int D, bool E>
CellGrid<D> candidate_grid(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice,
                           const RemapParams& params, std::int64_t align = 1) {
  CellGrid<D> g;
  g.periods = lattice.periods(box);
  const std::size_t n_old = p.n_real;
  Vec<D> lo, hi;
  double max_h = 0.0;
  for (std::size_t a = 0; a < n_old; ++a) max_h = std::max(max_h, p.h[a]);
  for (int k = 0; k < D; ++k) {
    if (box.edge[k] == Edge::open) {
      lo[k] = std::numeric_limits<double>::max();
      hi[k] = std::numeric_limits<double>::lowest();
      for (std::size_t a = 0; a < n_old; ++a) {
        lo[k] = std::min(lo[k], p.x[a][k]);
        hi[k] = std::max(hi[k], p.x[a][k]);
      }
      lo[k] -= params.closing_radius_in_h * max_h * 1.1;
      hi[k] += params.closing_radius_in_h * max_h * 1.1;
    } else {
      lo[k] = box.lo[k];
      hi[k] = box.hi[k];
    }
  }
  g.range = lattice.cells_touching(box, lo, hi);
  g.n_cells = 1;
  for (int k = 0; k < D; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (g.periods[kk] > 0) {
      g.range.lo[kk] = 0;
      g.range.hi[kk] = g.periods[kk] - 1;
    } else if (box.edge[k] == Edge::reflecting) {
      // rows whose sites lie inside the walls
      while (lattice.site(box, g.range.lo)[k] < box.lo[k]) ++g.range.lo[kk];
      auto top = g.range.lo;
      top[kk] = g.range.hi[kk];
      while (lattice.site(box, top)[k] > box.hi[k]) top[kk] = --g.range.hi[kk];
    } else if (align > 1) {
      auto floor_div = [](std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
      g.range.lo[kk] = floor_div(g.range.lo[kk], align) * align;
      g.range.hi[kk] = (floor_div(g.range.hi[kk], align) + 1) * align - 1;
    }
    g.count[kk] = g.range.hi[kk] - g.range.lo[kk] + 1;
    g.n_cells *= static_cast<std::size_t>(g.count[kk]);
  }
  // The sums take (3 + D) doubles per cell and thread: refuse a grid that would not fit rather than ask for it.
  const double gib = static_cast<double>(g.n_cells) * static_cast<double>((3 + D) * sizeof(double)) *
                     static_cast<double>(std::max(1, max_threads())) / double(1u << 30);
  require(g.n_cells < (std::size_t{1} << 31) && gib <= 4.0,
          "regularization: the particles span " + std::to_string(g.n_cells) + " lattice cells (" +
              std::to_string(n_old) + " particles; the remap's sums would take " + std::to_string(gib) +
              " GiB): a particle far from the rest on an open axis?");
  return g;
}

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

/// Axis k's part of the flat index of 2D lattice index i in `grid`: wrapped on periodic axes, clamped at
/// walls (a round-off sliver beyond a wall); -1 outside the grid.
inline std::int64_t axis_part(const CellGrid<2>& grid, const Box<2>& box, int k, std::int64_t i) {
  const auto kk = static_cast<std::size_t>(k);
  if (grid.periods[kk] > 0) i = wrap_index(i, grid.periods[kk]);
  i -= grid.range.lo[kk];
  if (box.edge[k] == Edge::reflecting) i = std::clamp<std::int64_t>(i, 0, grid.count[kk] - 1);
  if (i < 0 || i >= grid.count[kk]) return -1;
  return k == 0 ? i : i * grid.count[0];
}
/// Whether lattice index idx lies beyond a wall (outside the grid along a reflecting axis).
inline bool beyond_wall(const CellGrid<2>& grid, const Box<2>& box, std::array<std::int64_t, 2> idx) {
  for (int k = 0; k < 2; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (box.edge[k] == Edge::reflecting &&
        (idx[kk] < grid.range.lo[kk] || idx[kk] >= grid.range.lo[kk] + grid.count[kk]))
      return true;
  }
  return false;
}

/// Cells that are not rectangles do not tile a box with walls: `part`, an old cell's overlap with the
/// lattice cell idx beyond a wall (relative to xo), goes to the nearest sites inside among idx's
/// neighbours, each taking the piece nearer to it than to the others, just as the old cells, clipped to
/// the box, are the Voronoi cells of the sites inside. A lattice set then maps onto itself at walls too.
/// Calls f(index inside, piece) for each; a box one row wide (no site inside next to it) gives the whole
/// part to idx, whose flat index is clamped.
template <class Lattice, class F>
void share_beyond_wall(const Lattice& lattice, const CellGrid<2>& grid, const Box<2>& box,
                       std::array<std::int64_t, 2> idx, const geometry::ConvexPolygon& part, const Vec<2>& xo, F&& f) {
  std::array<std::array<std::int64_t, 2>, 8> nbs;
  std::array<Vec<2>, 8> at;
  std::size_t n = 0;
  for (std::int64_t dj = -1; dj <= 1; ++dj)
    for (std::int64_t di = -1; di <= 1; ++di) {
      const std::array<std::int64_t, 2> nb{idx[0] + di, idx[1] + dj};
      if ((di == 0 && dj == 0) || beyond_wall(grid, box, nb)) continue;
      nbs[n] = nb;
      at[n++] = lattice.site(box, nb) - xo;
    }
  if (n == 0) {
    f(idx, part);
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    geometry::ConvexPolygon piece = part;
    for (std::size_t m = 0; m < n && piece.n >= 3; ++m)
      if (m != k)  // nearer to at[k] than to at[m]
        geometry::clip_halfplane(piece, at[m] - at[k], 0.5 * (at[m].squaredNorm() - at[k].squaredNorm()));
    f(nbs[k], piece);
  }
}

/// What the overlaps need of a lattice's cells beyond their sites: nothing for rectangles (the grid lines),
/// the sides of the cell shape for the others.
struct NoSides {};
template <class Lattice>
using CellSides = std::conditional_t<Lattice::rectangular_cells, NoSides, geometry::Sides>;

template <class Lattice>
CellSides<Lattice> cell_sides(const Lattice& lattice) {
  if constexpr (Lattice::rectangular_cells) {
    return {};
  } else {
    static_assert(
        requires { lattice.cell_shape(); },
        "a lattice whose cells are not rectangles needs `geometry::ConvexPolygon cell_shape() const`: the "
        "cell around its site, every cell being that shape moved to its site");
    const geometry::ConvexPolygon shape = lattice.cell_shape();
    require(shape.n >= 3 && shape.n <= geometry::Sides::capacity,
            "regularization: a lattice's cell shape needs 3 to 32 sides");
    return geometry::sides_of(shape);
  }
}

/// The builder's visitor behind for_each_old_cell: each old cell's overlaps on the lattice cells of `grid`,
/// listed in per-thread scratch and handed to the action.
template <class Lattice, bool E, class Region, class Action>
struct OldCellVisitor {
  const ParticleSet<2, E>* p;
  const Lattice* lattice;
  const Box<2>* box;
  const CellGrid<2>* grid;
  const Region* region;
  Action* action;
  struct alignas(64) Scratch {  // per thread, a cache line apart
    std::vector<Overlap> overlaps;
    std::vector<double> lines, omegas;
    std::vector<std::int64_t> parts;
  };
  std::vector<Scratch> scratch;
  [[no_unique_address]] CellSides<Lattice> sides;

  std::int64_t axis_part(int k, std::int64_t i) const { return detail::axis_part(*grid, *box, k, i); }
  bool beyond_wall(std::array<std::int64_t, 2> idx) const { return detail::beyond_wall(*grid, *box, idx); }
  /// share_beyond_wall's pieces as (index inside, area); returns how many.
  using Share = std::pair<std::array<std::int64_t, 2>, double>;
  std::size_t share_beyond_wall(std::array<std::int64_t, 2> idx, const geometry::ConvexPolygon& part, const Vec<2>& xo,
                                std::array<Share, 8>& shares) const {
    std::size_t n = 0;
    detail::share_beyond_wall(*lattice, *grid, *box, idx, part, xo,
                              [&](std::array<std::int64_t, 2> nb, const geometry::ConvexPolygon& piece) {
                                shares[n++] = {nb, geometry::area(piece)};
                              });
    return n;
  }
  void restart() { action->restart(); }
  void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
    if constexpr (Region::clips) {
      geometry::ConvexPolygon closed = cell;
      region->clip(p->x[a], closed);
      add_cell(thread, a, closed);
    } else {
      add_cell(thread, a, cell);
    }
  }

  /// The overlaps listed so far for one cell: how many, and V_o their sum in their order.
  struct Listed {
    std::size_t n = 0;
    double V_o = 0.0;
  };

  void add_cell(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
    auto& own = scratch[static_cast<std::size_t>(thread)];
    const Vec<2> xo = p->x[a];
    geometry::Bounds cb;
    const double cell_area = geometry::area_and_bounds(cell, cb);
    const auto r = lattice->cells_touching(*box, Vec<2>(cb.lo + xo), Vec<2>(cb.hi + xo));
    Listed listed;  // own.overlaps is scratch that keeps its size
    if constexpr (Lattice::rectangular_cells)
      list_on_rectangles(own, a, cell, cell_area, r, xo, listed);
    else
      list_on_shapes(own, a, cell, cell_area, r, xo, listed);
    (*action)(thread, a, cell, std::span<const Overlap>(own.overlaps.data(), listed.n), listed.V_o, cell_area);
  }

  static NumericalError beyond_grid(std::size_t a) {
    return NumericalError("regularization: an old cell reaches beyond the lattice grid (particle " + std::to_string(a) +
                          ")");
  }

  [[gnu::always_inline]] inline void add_overlap(Scratch& own, Listed& l, std::size_t a, std::int64_t col_part,
                                                 std::int64_t row_part, double omega) const {
    if ((col_part | row_part) < 0) throw beyond_grid(a);
    grown(own.overlaps, l.n + 1)[l.n] = {static_cast<std::size_t>(col_part + row_part), omega};
    ++l.n;
    l.V_o += omega;
  }

  /// Rectangular lattice cells: all overlaps in one pass over the cell's edges; round-off crumbs in cells
  /// the old cell only touches (|omega| ~ 1e-16 of its area) are dropped, and V_o = sum omega keeps mass
  /// exact.
  [[gnu::always_inline]] inline void list_on_rectangles(Scratch& own, std::size_t a,
                                                        const geometry::ConvexPolygon& cell, double cell_area,
                                                        const IndexRange<2>& r, const Vec<2>& xo, Listed& l) const {
    const auto n_i = static_cast<int>(r.hi[0] - r.lo[0] + 1), n_j = static_cast<int>(r.hi[1] - r.lo[1] + 1);
    double* xs = grown(own.lines, static_cast<std::size_t>(n_i + n_j + 2));
    for (int c = 0; c <= n_i; ++c) xs[c] = lattice->line(*box, 0, r.lo[0] + c, xo[0]);
    double* ys = xs + n_i + 1;
    for (int c = 0; c <= n_j; ++c) ys[c] = lattice->line(*box, 1, r.lo[1] + c, xo[1]);
    double* omegas = grown(own.omegas, static_cast<std::size_t>(n_i) * static_cast<std::size_t>(n_j));
    geometry::grid_overlaps(cell, xs, n_i, ys, n_j, omegas);
    // The flat index is a column part plus a row part: each is wrapped (periodic) or clamped (walls)
    // once per cell instead of once per overlap.
    std::int64_t* cols = grown(own.parts, static_cast<std::size_t>(n_i + n_j));
    std::int64_t* rows = cols + n_i;
    for (int i = 0; i < n_i; ++i) cols[i] = axis_part(0, r.lo[0] + i);
    for (int j = 0; j < n_j; ++j) rows[j] = axis_part(1, r.lo[1] + j);
    // Each overlap is written and kept by advancing the count, without a branch (whether a cell of the grid
    // holds more than a crumb is a coin toss); so is the check that a kept one lies inside the grid.
    const double crumb = 1e-13 * cell_area;
    auto* out = grown(own.overlaps, static_cast<std::size_t>(n_i) * static_cast<std::size_t>(n_j));
    std::int64_t outside = 0;
    std::size_t n_ov = l.n;
    double V_o = l.V_o;
    for (int i = 0; i < n_i; ++i)
      for (int j = 0; j < n_j; ++j) {
        const double omega = omegas[i * n_j + j];
        const bool kept = omega > crumb;
        out[n_ov] = {static_cast<std::size_t>(cols[i] + rows[j]), omega};
        outside |= kept ? cols[i] | rows[j] : 0;
        V_o += kept ? omega : 0.0;
        n_ov += kept;
      }
    if (outside < 0) throw beyond_grid(a);
    l.n = n_ov;
    l.V_o = V_o;
  }

  /// Cells of another shape: every lattice cell is the lattice's shape moved to its site, so all have the
  /// same side normals; the old cell's extent along each, taken once, tells for each candidate which sides
  /// cut the old cell and whether one keeps them apart, before any clipping (many in the rectangular index
  /// range are).
  [[gnu::always_inline]] inline void list_on_shapes(Scratch& own, std::size_t a, const geometry::ConvexPolygon& cell,
                                                    double cell_area, const IndexRange<2>& r, const Vec<2>& xo,
                                                    Listed& l) const {
    std::array<double, geometry::Sides::capacity> reach_lo, reach_hi;
    for (int k = 0; k < sides.n; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      reach_lo[kk] = std::numeric_limits<double>::max();
      reach_hi[kk] = std::numeric_limits<double>::lowest();
      for (int v = 0; v < cell.n; ++v) {
        const double d = sides.normal[kk].dot(cell[v]);
        reach_lo[kk] = std::min(reach_lo[kk], d);
        reach_hi[kk] = std::max(reach_hi[kk], d);
      }
    }
    for (std::int64_t j = r.lo[1]; j <= r.hi[1]; ++j)
      for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i) {
        const Vec<2> site = lattice->site(*box, {i, j}) - xo;
        std::uint32_t cutting = 0;
        bool apart = false;
        for (int k = 0; k < sides.n; ++k) {
          const auto kk = static_cast<std::size_t>(k);
          const double offset = sides.offset[kk] + sides.normal[kk].dot(site);
          apart |= reach_lo[kk] >= offset;
          cutting |= static_cast<std::uint32_t>(reach_hi[kk] > offset) << k;
        }
        if (apart) continue;
        if (beyond_wall({i, j})) {
          std::array<Share, 8> shares;
          const std::size_t n_shares = share_beyond_wall(
              {i, j},
              geometry::with_part_within_sides(
                  cell, sides, cutting, [&](std::size_t k) { return sides.offset[k] + sides.normal[k].dot(site); },
                  [](const geometry::ConvexPolygon& part) { return part; }),
              xo, shares);
          for (std::size_t k = 0; k < n_shares; ++k)
            if (shares[k].second > 0.0)
              add_overlap(own, l, a, axis_part(0, shares[k].first[0]), axis_part(1, shares[k].first[1]),
                          shares[k].second);
          continue;
        }
        const double omega = cutting == 0 ? cell_area : geometry::area_within_sides(cell, sides, site, cutting);
        if (omega > 0.0) add_overlap(own, l, a, axis_part(0, i), axis_part(1, j), omega);
      }
  }
};

/// Visits every old particle's closed Voronoi cell (2D) with its overlaps on the cells of `grid`:
/// action(thread, a, cell, overlaps, V_o, cell_area), the cell relative to x_a, overlaps as (flat index,
/// Omega) and V_o their sum, in their order. The builder may restart (wider periodic images): action.restart() then
/// forgets what it saw.
template <class Lattice, class Builder, bool E, class Region, class Action>
void for_each_old_cell(const ParticleSet<2, E>& p, const Box<2>& box, const Lattice& lattice, Builder& builder,
                       const CellGrid<2>& grid, const Region& region, RemapWorkspace<2>& workspace, Action& action,
                       std::span<const std::uint32_t> only = {}) {
  using Visitor = OldCellVisitor<Lattice, E, Region, Action>;
  Visitor visitor{&p,
                  &lattice,
                  &box,
                  &grid,
                  &region,
                  &action,
                  std::vector<typename Visitor::Scratch>(static_cast<std::size_t>(geometry::builder_threads())),
                  cell_sides(lattice)};
  builder.build(p.x, box, workspace.closing, visitor, only);
}

/// The radius of the disc that closes each old cell at open edges (none when no axis is open).
template <bool E>
void set_closing_radii(const ParticleSet<2, E>& p, const Box<2>& box, const RemapParams& params,
                       std::vector<double>& closing) {
  closing.clear();
  if (box.edge[0] == Edge::open || box.edge[1] == Edge::open) {
    closing.resize(p.n_real);
    for (std::size_t a = 0; a < p.n_real; ++a) closing[a] = params.closing_radius_in_h * p.h[a];
  }
}

/// Eqs. (6)-(9) before the division: for every cell of `grid`, the sums over old particles o of
/// (m_o / V_o) Omega_n^o times 1, v_o and the specific total energy, and the covered volume.
/// The sums land in workspace.sums[0]. With `record_reach` (2D), workspace.reach receives each old cell's
/// farthest vertex distance.
template <class Lattice, class Builder, int D, bool E, class Region>
Sums<D>& accumulate_overlaps(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                             const RemapParams& params, const CellGrid<D>& grid, const Region& region,
                             RemapWorkspace<D>& workspace, bool record_reach = false) {
  static_assert(check_closing_region<Region>());
  static_assert(D == 2 || !Region::clips, "closing regions are two-dimensional");
  const std::size_t n_old = p.n_real;
  auto& sums = workspace.sums;
  clear_sums(sums, grid.n_cells);
  auto specific_energy = [&](std::size_t a) {
    if constexpr (E)
      return p.u[a];
    else
      return 0.0;
  };

  if constexpr (D == 1) {
    for_each_old_interval(p, box, lattice, params, grid,
                          [&](std::size_t a, double left, double right, const auto& overlaps, double V_o) {
                            sums[0].add(overlaps, V_o, p.m[a], p.v[a], specific_energy(a), right - left);
                          });
  } else {
    static_assert(D == 2, "the remap supports 1D and 2D");
    set_closing_radii(p, box, params, workspace.closing);
    struct AddToSums {
      std::vector<detail::Sums<2>>* sums;
      const ParticleSet<D, E>* p;
      std::vector<double>* reach;  ///< null unless asked for
      void restart() {
        for (auto& s : *sums) s.resize(s.m.size());
      }
      void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell,
                      std::span<const detail::Overlap> ov, double V_o, double cell_area) {
        if (reach) (*reach)[a] = geometry::max_radius(cell, geometry::Point::Zero());
        const double e_o = [&] {
          if constexpr (E)
            return p->u[a];
          else
            return 0.0;
        }();
        (*sums)[static_cast<std::size_t>(thread)].add(ov, V_o, p->m[a], p->v[a], e_o, cell_area);
      }
    };
    if (record_reach) workspace.reach.resize(n_old);
    AddToSums add{&sums, &p, record_reach ? &workspace.reach : nullptr};
    for_each_old_cell(p, box, lattice, builder, grid, region, workspace, add);
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
template <int D, class Volume, class ForEachNeighbour>
void hand_on_sparse_cells(Sums<D>& S, const RemapParams& params, Volume&& volume, ForEachNeighbour&& for_each_neighbour,
                          std::size_t& handed_on, std::vector<std::uint8_t>& keep) {
  const std::size_t n_cells = S.m.size();
  keep.resize(n_cells);
  const double min_mass =
      params.min_mass_ratio > 0.0 ? params.min_mass_ratio * *std::max_element(S.m.begin(), S.m.end()) : 0.0;
  rsph::run_parallel(n_cells, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c)
      keep[c] = S.fill[c] > params.min_fill * volume(c) && S.m[c] > 0.0 && S.m[c] >= min_mass;
  });
  auto best_neighbour = [&](std::size_t c) {
    std::int64_t kept_best = -1, heavy_best = -1;
    double best_fill = 0.0, best_mass = S.m[c];
    for_each_neighbour(c, [&](std::size_t g) {
      if (keep[g] && S.fill[g] > best_fill) {
        kept_best = static_cast<std::int64_t>(g);
        best_fill = S.fill[g];
      }
      if (!keep[g] && S.m[g] > best_mass) {
        heavy_best = static_cast<std::int64_t>(g);
        best_mass = S.m[g];
      }
    });
    return kept_best >= 0 ? kept_best : heavy_best;
  };
  handed_on = 0;
  std::vector<double> moved_fill;  // allocated only when some share moves
  for (bool moved = true; moved;) {
    moved = false;
    for (std::size_t c = 0; c < n_cells; ++c) {
      if (keep[c] || S.m[c] == 0.0) continue;
      const std::int64_t best = best_neighbour(c);
      if (best < 0) continue;
      const auto b = static_cast<std::size_t>(best);
      S.m[b] += S.m[c];
      S.mv[b] += S.mv[c];
      S.E[b] += S.E[c];
      if (moved_fill.empty()) moved_fill.assign(n_cells, 0.0);
      moved_fill[b] += S.fill[c] + moved_fill[c];  // the volume goes with the mass (rho = m / volume)
      moved_fill[c] = 0.0;
      S.m[c] = 0.0;
      S.mv[c] = Vec<D>::Zero();
      S.E[c] = 0.0;
      ++handed_on;
      moved = true;
    }
  }
  for (std::size_t c = 0; c < n_cells; ++c) {
    if (!keep[c] && S.m[c] > 0.0) keep[c] = 1;  // no neighbour to take its share
    if (!moved_fill.empty()) S.fill[c] += moved_fill[c];
  }
}

/// Replaces `p` by one new particle per kept cell, in the order of `cells`: eq. (6) mass, eq. (8)
/// velocity, and u taking up the kinetic energy the averaging removed (eq. 9); rho is set to the mass over
/// the covered volume (a kernel-summed density overwrites it). `place(c)` gives the
/// site and smoothing length of cell c.
template <int D, bool E, class Place>
void emit_particles(ParticleSet<D, E>& p, const Sums<D>& S, const std::vector<std::uint8_t>& keep,
                    const std::vector<std::size_t>& cells, Place&& place, RemapStats& stats) {
  double ke_before = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) ke_before += 0.5 * p.m[a] * p.v[a].squaredNorm();
  stats.n_before = p.n_real;
  auto emitted = [&](std::size_t c) { return keep[c] && S.m[c] > 0.0; };
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
          const double m_n = S.m[c];
          const Vec<D> v_n = S.mv[c] / m_n;  // eq. (8)
          const double ke = 0.5 * m_n * v_n.squaredNorm();
          ke_sum += ke;
          const auto [site, h] = place(c);
          p.m[a] = m_n;
          p.x[a] = site;
          p.v[a] = v_n;
          p.h[a] = h;
          p.rho[a] = m_n / S.fill[c];  // the remapped density, for schemes that do not sum eq. (2)
          if constexpr (E) p.u[a] = std::max(0.0, (S.E[c] - ke) / m_n);  // eq. (9) plus the converted kinetic energy
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
  const auto idx = grid.unflat(c);
  std::array<std::int64_t, D> off;
  off.fill(-1);
  for (;;) {
    std::array<std::int64_t, D> nb;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) nb[k] = idx[k] + off[k];
    const std::int64_t g = grid.flat(nb);
    if (g >= 0 && static_cast<std::size_t>(g) != c) f(static_cast<std::size_t>(g));
    std::size_t k = 0;
    for (; k < static_cast<std::size_t>(D); ++k) {
      if (++off[k] <= 1) break;
      off[k] = -1;
    }
    if (k == static_cast<std::size_t>(D)) break;
  }
}

/// The end of a remap onto one lattice: the shares of nearly empty cells handed on, and one new particle per
/// kept cell of `grid`, in lattice order, with h = h_over_dx * Delta.
template <class Lattice, int D, bool E>
void emit_on_lattice(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, const RemapParams& params,
                     const CellGrid<D>& grid, Sums<D>& S, RemapWorkspace<D>& ws, RemapStats& stats) {
  const double cell_volume = lattice.cell_volume();
  auto& keep = ws.keep;
  hand_on_sparse_cells<D>(
      S, params, [&](std::size_t) { return cell_volume; },
      [&](std::size_t c, auto&& f) { for_each_grid_neighbour(grid, c, f); }, stats.dropped_cells, keep);
  auto& order = ws.order;
  order.resize(grid.n_cells);
  std::iota(order.begin(), order.end(), std::size_t{0});
  const double h_new = params.h_over_dx * lattice.spacing;
  emit_particles(
      p, S, keep, order,
      [&](std::size_t c) {
        return std::pair{lattice.site(box, grid.unflat(c)), h_new};
      },
      stats);
  stats.per_level = {stats.n_after};
}

template <class Lattice, int D, bool E>
void check_remap_input(const ParticleSet<D, E>& p, const Lattice& lattice, const RemapParams& params) {
  static_assert(Lattice::dim == D, "the lattice's dimension differs from the particles'");
  params.validate();
  require(lattice.spacing > 0.0, "regularization: the lattice spacing must be positive");
  require(p.n_ghost() == 0, "regularization: remove ghosts before remapping");
  require(p.n_real > 0, "regularization: no particles to remap");
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
  require(total > 0.0, "regularization: every mass is zero: nothing to remap");
}

}  // namespace detail

/// Remaps `p` (real particles only, no ghosts) onto `lattice`; returns the statistics. New particles
/// are stored in lattice order with h = h_over_dx * Delta; u absorbs the kinetic energy lost when the
/// gas carries it. `region` closes the cells at open edges (region.hpp).
/// `workspace` (optional) keeps scratch storage between remaps.
template <class Lattice, class Builder, int D, bool E, class Region = region::Unbounded>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                              const RemapParams& params, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr) {
  detail::check_remap_input(p, lattice, params);
  RemapWorkspace<D> local;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  const auto grid = detail::candidate_grid(p, box, lattice, params);
  auto& S = detail::accumulate_overlaps(p, box, lattice, builder, params, grid, region, ws);
  RemapStats stats;
  stats.max_volume_mismatch = S.max_mismatch;
  detail::emit_on_lattice(p, box, lattice, params, grid, S, ws, stats);
  return stats;
}

}  // namespace rsph::regularize
