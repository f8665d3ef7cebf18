#pragma once
// Variable resolution in factors of two, as in adaptive mesh refinement: space is tiled by blocks of
// block_cells^D level-0 cells; each block carries one level l, with spacing Delta_l = Delta_0 / 2^l and
// h_l = (h/Delta) Delta_l; neighbouring blocks (diagonals and periodic images included) differ by at
// most one level. The remap of eqs. (6)-(9) onto it stays exactly conservative: overlaps are taken on
// the finest lattice and summed into each coarser cell, which is a union of finest cells.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/refinement.hpp"
#include "rsph/regularize/remap.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <string>
#include <vector>

namespace rsph {
namespace lattice {

/// The uniform lattice of one level: square in 2D, uniform in 1D.
template <int D>
using LevelLattice = std::conditional_t<D == 1, Uniform1D, Square>;

/// A multi-level lattice of blocks; `criterion` sets each block's level at every regularization.
template <int D, class Criterion>
struct MultiLevel {
  static_assert(D == 1 || D == 2, "multi-level lattices are built in 1D and 2D");
  static_assert(refine::check_criterion<Criterion, D>());
  static constexpr int dim = D;
  static constexpr int deepest_supported = 10;

  double spacing;   ///< Delta_0, the coarsest level's spacing
  int max_level;    ///< the finest level L
  int block_cells;  ///< level-0 cells per block and axis
  Criterion criterion;
  /// Width, in spacings of the coarser level, over which h of a finer block rises towards the coarser
  /// block's h next to it (0: h jumps at the block face).
  double h_ramp = 0.0;

  MultiLevel(double spacing_0, int finest_level, int cells_per_block, Criterion c)
      : spacing(spacing_0), max_level(finest_level), block_cells(cells_per_block), criterion(std::move(c)) {}

  void validate() const {
    require(spacing > 0.0, "multi-level lattice: the level-0 spacing must be positive");
    require(max_level >= 0 && max_level <= deepest_supported, "multi-level lattice: the finest level must lie in [0, " +
                                                                  std::to_string(deepest_supported) + "] (got " +
                                                                  std::to_string(max_level) + ")");
    require(block_cells >= 1, "multi-level lattice: a block needs at least one level-0 cell per axis");
    require(h_ramp >= 0.0 && h_ramp <= block_cells,
            "multi-level lattice: the h ramp must lie in [0, block_cells] coarser spacings");
    if constexpr (requires { criterion.validate(); }) criterion.validate();
  }
  double spacing_at(int level) const { return spacing / static_cast<double>(std::int64_t{1} << level); }
  LevelLattice<D> finest() const { return {spacing_at(max_level)}; }

  /// Levels of the blocks at the last regularization, by block index (hysteresis reads them).
  const std::map<std::array<std::int64_t, D>, int>& levels() const { return levels_; }
  int previous_level(const std::array<std::int64_t, D>& block) const {
    const auto it = levels_.find(block);
    return it == levels_.end() ? refine::no_previous_level : it->second;
  }
  void store_levels(std::map<std::array<std::int64_t, D>, int> levels) { levels_ = std::move(levels); }

 private:
  std::map<std::array<std::int64_t, D>, int> levels_;
};

}  // namespace lattice

namespace regularize {
namespace detail {

/// Calls f(g, off) for every block g next to block b (diagonals and periodic images included; b itself
/// with off = 0), where off is g's offset from b in blocks.
template <int D, class F>
void for_each_neighbour_block(const refine::BlockField<D>& field, std::size_t b, F&& f) {
  const auto bi = field.block_index(b);
  std::array<std::int64_t, D> off;
  off.fill(-1);
  for (;;) {
    std::size_t g = 0;
    bool inside = true;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      std::int64_t i = bi[kk] + off[kk];
      if (field.periods[kk] > 0)
        i = ((i % field.blocks[kk]) + field.blocks[kk]) % field.blocks[kk];
      else if (i < 0 || i >= field.blocks[kk])
        inside = false;
      g = g * static_cast<std::size_t>(field.blocks[kk]) + static_cast<std::size_t>(std::max<std::int64_t>(i, 0));
    }
    if (inside) f(g, off);
    std::size_t k = 0;
    for (; k < static_cast<std::size_t>(D); ++k) {
      if (++off[k] <= 1) break;
      off[k] = -1;
    }
    if (k == static_cast<std::size_t>(D)) break;
  }
}

/// Raises levels until neighbouring blocks differ by at most one (refinement wins over coarsening).
template <int D>
void balance_two_to_one(const refine::BlockField<D>& field, std::vector<int>& level) {
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t b = 0; b < field.n_blocks(); ++b) {
      int need = level[b];
      for_each_neighbour_block(field, b, [&](std::size_t g, const auto&) { need = std::max(need, level[g] - 1); });
      if (need > level[b]) {
        level[b] = need;
        changed = true;
      }
    }
  }
}

/// Distance from x (in block b) to the nearest block next to b on a coarser level than b; `none` when
/// no neighbour is coarser.
template <int D>
double distance_to_coarser_block(const refine::BlockField<D>& field, const std::vector<int>& level, std::size_t b,
                                 const Vec<D>& x, double none) {
  double best = none;
  const Vec<D> lo = field.block_lo(b);
  for_each_neighbour_block(field, b, [&](std::size_t g, const std::array<std::int64_t, D>& off) {
    if (level[g] >= level[b]) return;
    // the neighbour's box, placed next to b (periodic images included)
    double d2 = 0.0;
    for (int k = 0; k < D; ++k) {
      const double a = lo[k] + static_cast<double>(off[static_cast<std::size_t>(k)]) * field.block_size();
      const double gap = std::max({a - x[k], 0.0, x[k] - (a + field.block_size())});
      d2 += gap * gap;
    }
    best = std::min(best, std::sqrt(d2));
  });
  return best;
}

/// New cells at level faces (2D). Old cells are Voronoi cells; the new cell of a site whose one-cell ring
/// holds a cell of another level is taken as its Voronoi cell among the new sites too (as Fig. 1 of the
/// paper draws both), not its lattice square, so that a set on the lattice remaps onto itself and a
/// uniform state stays uniform. Elsewhere the two coincide. The face cells tile the same region F as
/// their lattice squares (a union of finest cells); each old cell's share of F from the finest-cell pass
/// is handed to the face cells in proportion to its exact overlaps with their Voronoi cells, so the remap
/// stays exactly conservative. Replaces the face cells' sums in `cells` and their volumes in `volume`.
template <class Builder, bool E, class Region>
void remap_face_cells(const ParticleSet<2, E>& p, const Box<2>& box, const lattice::Square& fine, Builder& builder,
                      const CellGrid<2>& grid, const Region& region, RemapWorkspace<2>& ws,
                      const std::vector<std::uint32_t>& owner,
                      const std::vector<std::array<std::int64_t, 2>>& first_fine, const std::vector<std::int64_t>& span,
                      const Vec<2>& origin, Sums<2>& cells, std::vector<double>& volume) {
  using geometry::ConvexPolygon;
  const double dx = fine.spacing;
  const std::size_t n_cells = span.size();
  auto owner_at = [&](std::int64_t i, std::int64_t j) -> std::int64_t {  // grid-relative finest index
    const std::int64_t fl = grid.flat({grid.range.lo[0] + i, grid.range.lo[1] + j});
    return fl < 0 ? -1 : static_cast<std::int64_t>(owner[static_cast<std::size_t>(fl)]);
  };
  auto site = [&](std::size_t c) {
    return Vec<2>(origin[0] + (static_cast<double>(first_fine[c][0]) + 0.5 * static_cast<double>(span[c])) * dx,
                  origin[1] + (static_cast<double>(first_fine[c][1]) + 0.5 * static_cast<double>(span[c])) * dx);
  };
  // Face cells: another level in the ring of finest cells around the footprint.
  std::vector<std::int32_t> face_of(n_cells, -1);
  std::vector<std::size_t> faces;
  for (std::size_t c = 0; c < n_cells; ++c) {
    const std::int64_t s = span[c], i0 = first_fine[c][0], j0 = first_fine[c][1];
    bool face = false;
    for (std::int64_t i = -1; i <= s && !face; ++i)
      for (std::int64_t j = -1; j <= s && !face; ++j) {
        if (i >= 0 && i < s && j >= 0 && j < s) continue;
        const std::int64_t o = owner_at(i0 + i, j0 + j);
        face = o >= 0 && span[static_cast<std::size_t>(o)] != s;
      }
    if (face) {
      face_of[c] = static_cast<std::int32_t>(faces.size());
      faces.push_back(c);
    }
  }
  if (faces.empty()) return;
  // Their Voronoi cells among the new sites (relative to their own site), and the face
  // cells near each, which an old cell touching it may also overlap.
  const std::size_t n_faces = faces.size();
  std::vector<ConvexPolygon> polygon(n_faces);
  std::vector<Vec<2>> face_site(n_faces);
  std::vector<geometry::Bounds> face_bounds(n_faces);  // relative to the site: a quick test before clipping
  std::vector<std::vector<std::uint32_t>> nearby(n_faces);
  for (std::size_t k = 0; k < n_faces; ++k) {
    const std::size_t c = faces[k];
    const std::int64_t s = span[c], reach = 2 * s, i0 = first_fine[c][0], j0 = first_fine[c][1];
    const Vec<2> xc = site(c);
    const double half = 1.5 * static_cast<double>(s) * dx;
    double lo[2] = {-half, -half}, hi[2] = {half, half};
    for (int a = 0; a < 2; ++a)
      if (box.edge[a] == Edge::reflecting) {
        lo[a] = std::max(lo[a], box.lo[a] - xc[a]);
        hi[a] = std::min(hi[a], box.hi[a] - xc[a]);
      }
    ConvexPolygon buffers[2];
    ConvexPolygon* cell = &buffers[0];
    ConvexPolygon* scratch = &buffers[1];
    *cell = ConvexPolygon::rectangle(lo[0], lo[1], hi[0], hi[1]);
    std::vector<std::pair<std::int64_t, Vec<2>>> seen;
    for (std::int64_t i = i0 - reach; i < i0 + s + reach; ++i)
      for (std::int64_t j = j0 - reach; j < j0 + s + reach; ++j) {
        const std::int64_t o = owner_at(i, j);
        if (o < 0 || static_cast<std::size_t>(o) == c) continue;
        // the neighbour's site, shifted by the periods its finest cell was wrapped across
        const auto g = grid.unflat(static_cast<std::size_t>(grid.flat({grid.range.lo[0] + i, grid.range.lo[1] + j})));
        const Vec<2> shift(static_cast<double>(grid.range.lo[0] + i - g[0]) * dx,
                           static_cast<double>(grid.range.lo[1] + j - g[1]) * dx);
        const Vec<2> d = site(static_cast<std::size_t>(o)) + shift - xc;
        bool repeat = false;
        for (const auto& [q, dq] : seen) repeat = repeat || (q == o && (dq - d).squaredNorm() < 1e-12 * dx * dx);
        if (repeat) continue;
        seen.emplace_back(o, d);
        if (geometry::detail::cut_by_bisector(*cell, d, *scratch)) std::swap(cell, scratch);
        if (face_of[static_cast<std::size_t>(o)] >= 0)
          nearby[k].push_back(static_cast<std::uint32_t>(face_of[static_cast<std::size_t>(o)]));
      }
    // drop repeated vertices (a cut through a vertex leaves one), which would be edges without a normal
    ConvexPolygon& out = polygon[k];
    out.clear();
    for (int v = 0; v < cell->n; ++v) {
      const Vec<2>& q = (*cell)[v];
      if (out.n > 0 && (q - out[out.n - 1]).squaredNorm() <= 1e-24 * dx * dx) continue;
      out.push(q);
    }
    while (out.n > 1 && (out[0] - out[out.n - 1]).squaredNorm() <= 1e-24 * dx * dx) --out.n;
    face_site[k] = xc;
    face_bounds[k] = geometry::bounds(out);
    volume[c] = geometry::area(*cell);
  }
  for (auto& list : nearby) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  // Each old cell's share of F, handed out by exact overlaps with the face cells.
  struct FaceSums {
    std::vector<double> m, energy, fill;
    std::vector<Vec<2>> mv;
    void resize(std::size_t n) {
      m.assign(n, 0.0);
      energy.assign(n, 0.0);
      fill.assign(n, 0.0);
      mv.assign(n, Vec<2>::Zero());
    }
  };
  struct HandOut {
    const ParticleSet<2, E>* p;
    const Box<2>* box;
    const std::vector<std::uint32_t>* owner;
    const std::vector<std::int32_t>* face_of;
    const std::vector<ConvexPolygon>* polygon;
    const std::vector<Vec<2>>* face_site;
    const std::vector<geometry::Bounds>* face_bounds;
    const std::vector<std::vector<std::uint32_t>>* nearby;
    std::vector<FaceSums> sums;
    std::vector<std::vector<std::uint32_t>> candidates;
    std::vector<std::vector<double>> omegas;
    void restart() {
      for (auto& s : sums) s.resize(s.m.size());
    }
    void operator()(int thread, std::size_t a, const ConvexPolygon& cell, std::span<const detail::Overlap> ov,
                    double V_o, double) {
      double A_F = 0.0, best = 0.0;
      std::int32_t best_face = -1;
      auto& cand = candidates[static_cast<std::size_t>(thread)];
      cand.clear();
      for (const auto& [f, omega] : ov) {
        const std::int32_t k = (*face_of)[(*owner)[f]];
        if (k < 0) continue;
        A_F += omega;
        if (omega > best) {
          best = omega;
          best_face = k;
        }
        cand.push_back(static_cast<std::uint32_t>(k));
        for (const std::uint32_t q : (*nearby)[static_cast<std::size_t>(k)]) cand.push_back(q);
      }
      if (!(A_F > 0.0)) return;
      std::sort(cand.begin(), cand.end());
      cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
      const Vec<2> xo = p->x[a];
      auto& om = omegas[static_cast<std::size_t>(thread)];
      om.assign(cand.size(), 0.0);
      double A_poly = 0.0;
      const geometry::Bounds cb = geometry::bounds(cell);
      for (std::size_t i = 0; i < cand.size(); ++i) {
        const std::size_t k = cand[i];
        Vec<2> d = (*face_site)[k] - xo;  // nearest periodic image of the face site
        for (int ax = 0; ax < 2; ++ax)
          if (box->edge[ax] == Edge::periodic) {
            const double L = box->hi[ax] - box->lo[ax];
            d[ax] -= L * std::round(d[ax] / L);
          }
        const geometry::Bounds& wb = (*face_bounds)[k];
        if (((wb.lo + d).array() > cb.hi.array()).any() || ((wb.hi + d).array() < cb.lo.array()).any())
          continue;  // apart: no overlap, and no clip needed to say so
        ConvexPolygon window = (*polygon)[k];
        for (int v = 0; v < window.n; ++v) window.v[static_cast<std::size_t>(v)] += d;
        om[i] = geometry::intersection_area(cell, window);
        A_poly += om[i];
      }
      auto& S = sums[static_cast<std::size_t>(thread)];
      const double density = p->m[a] / V_o;
      const double specific_energy = [&] {
        if constexpr (E)
          return p->u[a] + 0.5 * p->v[a].squaredNorm();
        else
          return 0.5 * p->v[a].squaredNorm();
      }();
      auto add = [&](std::size_t k, double omega) {
        const double dm = density * omega;  // eq. (6)
        S.m[k] += dm;
        S.mv[k] += dm * p->v[a];
        S.energy[k] += dm * specific_energy;
        S.fill[k] += omega;
      };
      if (!(A_poly > 0.5 * A_F)) {  // round-off slivers only: to the face cell it overlaps most
        add(static_cast<std::size_t>(best_face), A_F);
        return;
      }
      const double scale = A_F / A_poly;  // the finest-cell pass's share, so sums stay exact
      for (std::size_t i = 0; i < cand.size(); ++i)
        if (om[i] > 0.0) add(cand[i], om[i] * scale);
    }
  };
  const auto n_threads = static_cast<std::size_t>(geometry::builder_threads());
  HandOut hand_out{&p,
                   &box,
                   &owner,
                   &face_of,
                   &polygon,
                   &face_site,
                   &face_bounds,
                   &nearby,
                   std::vector<FaceSums>(n_threads),
                   std::vector<std::vector<std::uint32_t>>(n_threads),
                   std::vector<std::vector<double>>(n_threads)};
  for (auto& s : hand_out.sums) s.resize(n_faces);
  // Only the old cells that may meet a face cell are built again: those whose disc of reach (from the
  // overlap pass) touches a finest cell a face cell owns.
  require(ws.reach.size() == p.n_real, "multi-level remap: the overlap pass did not record the cells' reach");
  std::vector<std::uint8_t> in_face(grid.n_cells);  // per finest cell: owned by a face cell
  for (std::size_t f = 0; f < grid.n_cells; ++f) in_face[f] = face_of[owner[f]] >= 0;
  std::vector<std::uint32_t> near_faces;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const double reach = ws.reach[a];
    const auto r = fine.cells_touching(box, p.x[a] - Vec<2>::Constant(reach), p.x[a] + Vec<2>::Constant(reach));
    bool meets = false;
    for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i)
      for (std::int64_t j = r.lo[1]; j <= r.hi[1]; ++j) {
        const std::int64_t fl = grid.flat({i, j});
        meets |= fl >= 0 && in_face[static_cast<std::size_t>(fl)];
      }
    if (meets) near_faces.push_back(static_cast<std::uint32_t>(a));
  }
  if (!near_faces.empty())  // (an empty list would mean every cell)
    for_each_old_cell(p, box, fine, builder, grid, region, ws, hand_out, near_faces);
  for (std::size_t k = 0; k < n_faces; ++k) {
    const std::size_t c = faces[k];
    cells.m[c] = 0.0;
    cells.E[c] = 0.0;
    cells.fill[c] = 0.0;
    cells.mv[c] = Vec<2>::Zero();
    for (const auto& s : hand_out.sums) {  // fixed order: independent of scheduling
      cells.m[c] += s.m[k];
      cells.E[c] += s.energy[k];
      cells.fill[c] += s.fill[k];
      cells.mv[c] += s.mv[k];
    }
  }
}

/// The 1D counterpart of the above: a face cell's new cell is the interval between the midpoints to its
/// neighbouring sites.
template <bool E>
void remap_face_cells(const ParticleSet<1, E>& p, const Box<1>& box, const lattice::Uniform1D& fine,
                      const RemapParams& params, const CellGrid<1>& grid, const std::vector<std::uint32_t>& owner,
                      const std::vector<std::array<std::int64_t, 1>>& first_fine, const std::vector<std::int64_t>& span,
                      const Vec<1>& origin, Sums<1>& cells, std::vector<double>& volume) {
  const double dx = fine.spacing;
  const std::size_t n_cells = span.size();
  const double L = box.hi[0] - box.lo[0];
  auto site = [&](std::size_t c) {
    return origin[0] + (static_cast<double>(first_fine[c][0]) + 0.5 * static_cast<double>(span[c])) * dx;
  };
  // the owner of finest cell i (grid-relative) and the shift of its period; -1 beyond the grid
  auto owner_at = [&](std::int64_t i, double& shift) -> std::int64_t {
    const std::int64_t fl = grid.flat({grid.range.lo[0] + i});
    if (fl < 0) return -1;
    shift = static_cast<double>(grid.range.lo[0] + i - grid.unflat(static_cast<std::size_t>(fl))[0]) * dx;
    return static_cast<std::int64_t>(owner[static_cast<std::size_t>(fl)]);
  };
  std::vector<std::int32_t> face_of(n_cells, -1);
  std::vector<std::size_t> faces;
  for (std::size_t c = 0; c < n_cells; ++c) {
    double shift = 0.0;
    const std::int64_t l = owner_at(first_fine[c][0] - 1, shift), r = owner_at(first_fine[c][0] + span[c], shift);
    if ((l >= 0 && span[static_cast<std::size_t>(l)] != span[c]) ||
        (r >= 0 && span[static_cast<std::size_t>(r)] != span[c])) {
      face_of[c] = static_cast<std::int32_t>(faces.size());
      faces.push_back(c);
    }
  }
  if (faces.empty()) return;
  const std::size_t n_faces = faces.size();
  std::vector<double> lo(n_faces), hi(n_faces), face_site(n_faces);
  std::vector<std::array<std::int32_t, 2>> beside(n_faces);
  for (std::size_t k = 0; k < n_faces; ++k) {
    const std::size_t c = faces[k];
    const double xc = site(c), half = 0.5 * static_cast<double>(span[c]) * dx;
    double shift = 0.0;
    const std::int64_t l = owner_at(first_fine[c][0] - 1, shift);
    lo[k] = l >= 0 ? 0.5 * (site(static_cast<std::size_t>(l)) + shift - xc) : -half;  // a wall or the grid's end
    beside[k][0] = l >= 0 ? face_of[static_cast<std::size_t>(l)] : -1;
    const std::int64_t r = owner_at(first_fine[c][0] + span[c], shift);
    hi[k] = r >= 0 ? 0.5 * (site(static_cast<std::size_t>(r)) + shift - xc) : half;
    beside[k][1] = r >= 0 ? face_of[static_cast<std::size_t>(r)] : -1;
    face_site[k] = xc;
    volume[c] = hi[k] - lo[k];
  }
  std::vector<double> m(n_faces, 0.0), energy(n_faces, 0.0), fill(n_faces, 0.0);
  std::vector<Vec<1>> mv(n_faces, Vec<1>::Zero());
  std::vector<std::int32_t> cand;
  std::vector<double> om;
  auto hand_out = [&](std::size_t a, double left, double right, const auto& ov, double V_o) {
    double A_F = 0.0, best = 0.0;
    std::int32_t best_face = -1;
    cand.clear();
    for (const auto& [f, omega] : ov) {
      const std::int32_t k = face_of[owner[f]];
      if (k < 0) continue;
      A_F += omega;
      if (omega > best) {
        best = omega;
        best_face = k;
      }
      cand.push_back(k);
      for (const std::int32_t q : beside[static_cast<std::size_t>(k)])
        if (q >= 0) cand.push_back(q);
    }
    if (!(A_F > 0.0)) return;
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    const double xo = p.x[a][0];
    om.assign(cand.size(), 0.0);
    double A_poly = 0.0;
    for (std::size_t i = 0; i < cand.size(); ++i) {
      const auto k = static_cast<std::size_t>(cand[i]);
      double d = face_site[k] - xo;  // nearest periodic image of the face site
      if (box.edge[0] == Edge::periodic) d -= L * std::round(d / L);
      om[i] = std::max(0.0, std::min(right, xo + d + hi[k]) - std::max(left, xo + d + lo[k]));
      A_poly += om[i];
    }
    const double density = p.m[a] / V_o;
    const double specific_energy = [&] {
      if constexpr (E)
        return p.u[a] + 0.5 * p.v[a].squaredNorm();
      else
        return 0.5 * p.v[a].squaredNorm();
    }();
    auto add = [&](std::size_t k, double omega) {
      const double dm = density * omega;  // eq. (6)
      m[k] += dm;
      mv[k] += dm * p.v[a];
      energy[k] += dm * specific_energy;
      fill[k] += omega;
    };
    if (!(A_poly > 0.5 * A_F)) {  // round-off slivers only: to the face cell it overlaps most
      add(static_cast<std::size_t>(best_face), A_F);
      return;
    }
    const double scale = A_F / A_poly;  // the finest-cell pass's share, so sums stay exact
    for (std::size_t i = 0; i < cand.size(); ++i)
      if (om[i] > 0.0) add(static_cast<std::size_t>(cand[i]), om[i] * scale);
  };
  for_each_old_interval(p, box, fine, params, grid, hand_out);
  for (std::size_t k = 0; k < n_faces; ++k) {
    const std::size_t c = faces[k];
    cells.m[c] = m[k];
    cells.E[c] = energy[k];
    cells.fill[c] = fill[k];
    cells.mv[c] = mv[k];
  }
}

}  // namespace detail

/// Remaps `p` onto a multi-level lattice: sets every block's level from the criterion (capped at the
/// finest level, 2:1 balanced), then builds one particle per kept cell, block by block and in lattice
/// order within a block, with h = h_over_dx * Delta_l. Mass, momentum and total energy are conserved
/// exactly as on a uniform lattice.
template <int D, class Criterion, class Builder, bool E, class Region = region::Unbounded>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                              Builder& builder, const RemapParams& params, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr) {
  ml.validate();
  RemapWorkspace<D> local;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  const auto fine = ml.finest();
  detail::check_remap_input(p, fine, params);
  const std::int64_t ratio = std::int64_t{1} << ml.max_level;  // finest cells per level-0 cell and axis
  const std::int64_t align = ratio * ml.block_cells;           // finest cells per block and axis
  for (int k = 0; k < D; ++k)
    if (box.edge[k] != Edge::open) {
      const double blocks = (box.hi[k] - box.lo[k]) / (ml.spacing * ml.block_cells);
      require(std::abs(blocks - std::round(blocks)) < 1e-9 * std::max(1.0, blocks) && std::round(blocks) >= 1,
              "multi-level lattice: the box length along axis " + std::to_string(k) +
                  " must be a whole number of blocks (block size " + std::to_string(ml.spacing * ml.block_cells) + ")");
    }
  const auto grid = detail::candidate_grid(p, box, fine, params, align);
  // remap_face_cells picks the old cells to build again by their reach
  auto& S = detail::accumulate_overlaps(p, box, fine, builder, params, grid, region, ws, ml.max_level > 0);
  RemapStats stats;
  stats.max_volume_mismatch = S.max_mismatch;

  // Level-0 sums for the criteria.
  refine::BlockField<D> field;
  field.spacing = ml.spacing;
  field.cells_per_block = ml.block_cells;
  std::array<std::int64_t, D> n0{}, block0{};
  std::size_t n_level0 = 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    n0[k] = grid.count[k] / ratio;
    field.blocks[k] = grid.count[k] / align;
    block0[k] = grid.range.lo[k] / align;  // aligned: exact
    field.periods[k] = grid.periods[k] > 0 ? field.blocks[k] : 0;
    field.origin[static_cast<int>(k)] =
        box.lo[static_cast<int>(k)] + static_cast<double>(grid.range.lo[k]) * fine.spacing;
    n_level0 *= static_cast<std::size_t>(n0[k]);
  }
  field.mass.assign(n_level0, 0.0);
  field.volume.assign(n_level0, 0.0);
  for (std::size_t f = 0; f < grid.n_cells; ++f) {
    if (S.fill[f] == 0.0) continue;
    const auto idx = grid.unflat(f);
    std::size_t c = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      c = c * static_cast<std::size_t>(n0[kk]) + static_cast<std::size_t>((idx[kk] - grid.range.lo[kk]) / ratio);
    }
    field.mass[c] += S.m[f];
    field.volume[c] += S.fill[f];
  }

  // Levels: criterion, cap, 2:1 balance.
  const std::size_t n_blocks = field.n_blocks();
  std::vector<int> level(n_blocks, 0);
  auto absolute = [&](std::size_t b) {
    auto bi = field.block_index(b);
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) bi[k] += block0[k];
    return bi;
  };
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const int want = static_cast<int>(ml.criterion.level(field, b, ml.previous_level(absolute(b))));
    stats.requested_level = std::max(stats.requested_level, want);
    if (want > ml.max_level) ++stats.capped_blocks;
    level[b] = std::clamp(want, 0, ml.max_level);
  }
  detail::balance_two_to_one(field, level);

  // Cells of every block at its level; owner maps each finest cell to its cell.
  detail::Sums<D> cells;
  std::vector<std::uint32_t> owner(grid.n_cells);
  std::vector<std::array<std::int64_t, D>> first_fine;  // lowest finest-cell index (grid-relative) per cell
  std::vector<std::int64_t> span;                       // finest cells per axis per cell
  std::vector<int> cell_level;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const auto bi = field.block_index(b);
    const std::int64_t s = std::int64_t{1} << (ml.max_level - level[b]);
    const std::int64_t per_axis = align / s;
    std::array<std::int64_t, D> ci;
    ci.fill(0);
    for (;;) {
      std::array<std::int64_t, D> f0;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) f0[k] = bi[k] * align + ci[k] * s;
      const auto id = static_cast<std::uint32_t>(first_fine.size());
      first_fine.push_back(f0);
      span.push_back(s);
      cell_level.push_back(level[b]);
      // every finest cell of the footprint
      std::array<std::int64_t, D> fi;
      fi.fill(0);
      for (;;) {
        std::array<std::int64_t, D> g;
        for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) g[k] = grid.range.lo[k] + f0[k] + fi[k];
        owner[static_cast<std::size_t>(grid.flat(g))] = id;
        std::size_t k = 0;
        for (; k < static_cast<std::size_t>(D); ++k) {
          if (++fi[k] < s) break;
          fi[k] = 0;
        }
        if (k == static_cast<std::size_t>(D)) break;
      }
      std::size_t k = 0;
      for (; k < static_cast<std::size_t>(D); ++k) {
        if (++ci[k] < per_axis) break;
        ci[k] = 0;
      }
      if (k == static_cast<std::size_t>(D)) break;
    }
  }
  const std::size_t n_cells = first_fine.size();
  cells.resize(n_cells);
  for (std::size_t f = 0; f < grid.n_cells; ++f) {
    const std::size_t c = owner[f];
    cells.m[c] += S.m[f];
    cells.mv[c] += S.mv[f];
    cells.E[c] += S.E[f];
    cells.fill[c] += S.fill[f];
  }

  std::vector<double> cell_volume(n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) cell_volume[c] = std::pow(ml.spacing_at(cell_level[c]), D);
  if (ml.max_level > 0) {
    if constexpr (D == 2)
      detail::remap_face_cells(p, box, fine, builder, grid, region, ws, owner, first_fine, span, field.origin, cells,
                               cell_volume);
    else
      detail::remap_face_cells(p, box, fine, params, grid, owner, first_fine, span, field.origin, cells, cell_volume);
  }
  auto volume = [&](std::size_t c) { return cell_volume[c]; };
  auto for_each_neighbour = [&](std::size_t c, auto&& f) {
    // owners of the finest cells in the one-cell ring around c's footprint
    const std::int64_t s = span[c];
    std::array<std::int64_t, D> off;
    off.fill(-1);
    std::uint32_t last = static_cast<std::uint32_t>(c);
    for (;;) {
      bool ring = false;
      std::array<std::int64_t, D> g;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
        ring = ring || off[k] < 0 || off[k] >= s;
        g[k] = grid.range.lo[k] + first_fine[c][k] + off[k];
      }
      if (ring) {
        const std::int64_t fl = grid.flat(g);
        if (fl >= 0) {
          const std::uint32_t o = owner[static_cast<std::size_t>(fl)];
          if (o != c && o != last) f(static_cast<std::size_t>(o));  // repeats only cost a comparison
          last = o;
        }
      }
      std::size_t k = 0;
      for (; k < static_cast<std::size_t>(D); ++k) {
        if (++off[k] <= s) break;
        off[k] = -1;
      }
      if (k == static_cast<std::size_t>(D)) break;
    }
  };
  auto& keep = ws.keep;
  detail::hand_on_sparse_cells<D>(cells, params, volume, for_each_neighbour, stats.dropped_cells, keep);

  auto& order = ws.order;
  order.resize(n_cells);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<std::size_t> block_of(n_cells);
  {
    std::size_t c = 0;
    for (std::size_t b = 0; b < n_blocks; ++b) {
      const auto n = static_cast<std::size_t>(std::pow(static_cast<double>(align >> (ml.max_level - level[b])), D));
      for (std::size_t i = 0; i < n; ++i) block_of[c++] = b;
    }
  }
  auto place = [&](std::size_t c) {
    const double dx = fine.spacing;
    Vec<D> site;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k)
      site[static_cast<int>(k)] = field.origin[static_cast<int>(k)] +
                                  (static_cast<double>(first_fine[c][k]) + 0.5 * static_cast<double>(span[c])) * dx;
    const int l = cell_level[c];
    double h = params.h_over_dx * ml.spacing_at(l);
    if (ml.h_ramp > 0.0 && l > 0) {
      // distance to the nearest coarser neighbouring block (2:1 balance: one level coarser)
      const double ramp = ml.h_ramp * ml.spacing_at(l - 1);
      const double d = detail::distance_to_coarser_block(field, level, block_of[c], site, ramp);
      if (d < ramp) h += (params.h_over_dx * ml.spacing_at(l - 1) - h) * (1.0 - d / ramp);
    }
    return std::pair{site, h};
  };
  detail::emit_particles(p, cells, keep, order, place, stats);

  stats.per_level.assign(static_cast<std::size_t>(ml.max_level) + 1, 0);
  for (std::size_t c = 0; c < n_cells; ++c)
    if (keep[c] && cells.m[c] > 0.0) ++stats.per_level[static_cast<std::size_t>(cell_level[c])];
  std::map<std::array<std::int64_t, D>, int> levels;
  for (std::size_t b = 0; b < n_blocks; ++b) levels[absolute(b)] = level[b];
  ml.store_levels(std::move(levels));
  return stats;
}

}  // namespace regularize
}  // namespace rsph
