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
#include <type_traits>
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

  /// Saves or restores the blocks' levels through a checkpoint archive (io/checkpoint.hpp).
  template <class Archive>
  void checkpoint(Archive& ar) {
    std::vector<std::int64_t> blocks;
    std::vector<int> levels;
    for (const auto& [block, level] : levels_) {
      blocks.insert(blocks.end(), block.begin(), block.end());
      levels.push_back(level);
    }
    ar("lattice_blocks", blocks);
    ar("lattice_levels", levels);
    if (ar.saving()) return;
    require(blocks.size() == D * levels.size(), "checkpoint: the lattice's block levels are misshapen");
    levels_.clear();
    for (std::size_t k = 0; k < levels.size(); ++k) {
      std::array<std::int64_t, D> block;
      std::copy_n(blocks.begin() + static_cast<std::ptrdiff_t>(D * k), D, block.begin());
      levels_.emplace(block, levels[k]);
    }
  }

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

/// The new cells of every block at its level, in block order and lattice order within a block: each
/// cell's footprint on the finest grid (its lowest finest index, grid-relative, and its span in finest
/// cells per axis), its level, and per finest cell its owner.
template <int D>
struct Footprint {
  std::vector<std::uint32_t> owner;
  std::vector<std::array<std::int64_t, D>> first_fine;
  std::vector<std::int64_t> span;
  std::vector<int> level;
  Vec<D> origin;  ///< lower corner of the grid
  double dx = 0;  ///< the finest spacing

  std::size_t size() const { return span.size(); }
  Vec<D> site(std::size_t c) const {
    Vec<D> x;
    for (int k = 0; k < D; ++k)
      x[k] =
          origin[k] +
          (static_cast<double>(first_fine[c][static_cast<std::size_t>(k)]) + 0.5 * static_cast<double>(span[c])) * dx;
    return x;
  }
};

/// Steps a D-dimensional counter through [lo, hi) per axis, axis 0 fastest; false once it has passed them all.
template <int D>
bool next_index(std::array<std::int64_t, D>& i, std::int64_t lo, std::int64_t hi) {
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    if (++i[k] < hi) return true;
    i[k] = lo;
  }
  return false;
}

/// What the face cells receive from the old cells that meet them (one per thread in 2D).
template <int D>
struct FaceSums {
  std::vector<double> m, energy, fill;
  std::vector<Vec<D>> mv;

  void resize(std::size_t n) {
    m.assign(n, 0.0);
    energy.assign(n, 0.0);
    fill.assign(n, 0.0);
    mv.assign(n, Vec<D>::Zero());
  }

  /// Old particle a's share A_F of the face region, handed to the candidate face cells `cand` in proportion
  /// to its exact overlaps `om` with their cells (summing to A_poly), scaled so that the face cells receive
  /// exactly the share the finest-cell pass gave; round-off slivers only go to best_face whole.
  template <bool E, class Index>
  void hand_out(const ParticleSet<D, E>& p, std::size_t a, double V_o, double A_F, double A_poly,
                std::int32_t best_face, const std::vector<Index>& cand, const std::vector<double>& om) {
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
  }
};

/// The face cells an old cell's overlaps on the finest cells fall in, and those near each (near(k, push)):
/// returns A_F, the old cell's area in face cells; best_face the one it overlaps most; cand the
/// candidates, sorted and unique.
template <class Overlaps, class Index, class Near>
double face_candidates(const Overlaps& ov, const std::vector<std::uint32_t>& owner,
                       const std::vector<std::int32_t>& face_of, Near&& near, std::vector<Index>& cand,
                       std::int32_t& best_face) {
  double A_F = 0.0, best = 0.0;
  best_face = -1;
  cand.clear();
  for (const auto& [f, omega] : ov) {
    const std::int32_t k = face_of[owner[f]];
    if (k < 0) continue;
    A_F += omega;
    if (omega > best) {
      best = omega;
      best_face = k;
    }
    cand.push_back(static_cast<Index>(k));
    near(k, [&](Index q) { cand.push_back(q); });
  }
  std::sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  return A_F;
}

/// The face cells: those with another level in the one-cell ring of finest cells around their footprint;
/// face_of gives each new cell's index among them (-1 for others).
struct Faces {
  std::vector<std::int32_t> face_of;
  std::vector<std::size_t> cells;
};

template <int D, class OtherLevelBeside>
Faces find_faces(std::size_t n_cells, OtherLevelBeside&& other_level_beside) {
  Faces f;
  f.face_of.assign(n_cells, -1);
  for (std::size_t c = 0; c < n_cells; ++c)
    if (other_level_beside(c)) {
      f.face_of[c] = static_cast<std::int32_t>(f.cells.size());
      f.cells.push_back(c);
    }
  return f;
}

/// Owner of the grid-relative finest cell (i, j), -1 beyond the grid.
inline std::int64_t owner_at(const CellGrid<2>& grid, const Footprint<2>& fp, std::int64_t i, std::int64_t j) {
  const std::int64_t fl = grid.flat({grid.range.lo[0] + i, grid.range.lo[1] + j});
  return fl < 0 ? -1 : static_cast<std::int64_t>(fp.owner[static_cast<std::size_t>(fl)]);
}

/// The 2D face cells' Voronoi cells among the new sites (relative to their own site, with bounds for a
/// quick test before clipping), and the face cells near each, which an old cell touching it may also overlap.
struct FaceCells2 {
  std::vector<geometry::ConvexPolygon> polygon;
  std::vector<Vec<2>> site;
  std::vector<geometry::Bounds> bounds;
  std::vector<std::vector<std::uint32_t>> nearby;
};

/// Face cell k's Voronoi cell among the new sites within two spans, clipped to walls; its volume into volume[c].
inline void build_face_cell(const Box<2>& box, const CellGrid<2>& grid, const Footprint<2>& fp, const Faces& faces,
                            std::size_t k, FaceCells2& fc, std::vector<double>& volume) {
  using geometry::ConvexPolygon;
  const double dx = fp.dx;
  const std::size_t c = faces.cells[k];
  const std::int64_t s = fp.span[c], reach = 2 * s, i0 = fp.first_fine[c][0], j0 = fp.first_fine[c][1];
  const Vec<2> xc = fp.site(c);
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
      const std::int64_t o = owner_at(grid, fp, i, j);
      if (o < 0 || static_cast<std::size_t>(o) == c) continue;
      // the neighbour's site, shifted by the periods its finest cell was wrapped across
      const auto g = grid.unflat(static_cast<std::size_t>(grid.flat({grid.range.lo[0] + i, grid.range.lo[1] + j})));
      const Vec<2> shift(static_cast<double>(grid.range.lo[0] + i - g[0]) * dx,
                         static_cast<double>(grid.range.lo[1] + j - g[1]) * dx);
      const Vec<2> d = fp.site(static_cast<std::size_t>(o)) + shift - xc;
      bool repeat = false;
      for (const auto& [q, dq] : seen) repeat = repeat || (q == o && (dq - d).squaredNorm() < 1e-12 * dx * dx);
      if (repeat) continue;
      seen.emplace_back(o, d);
      if (geometry::detail::cut_by_bisector(*cell, d, *scratch)) std::swap(cell, scratch);
      if (faces.face_of[static_cast<std::size_t>(o)] >= 0)
        fc.nearby[k].push_back(static_cast<std::uint32_t>(faces.face_of[static_cast<std::size_t>(o)]));
    }
  // drop repeated vertices (a cut through a vertex leaves one), which would be edges without a normal
  ConvexPolygon& out = fc.polygon[k];
  out.clear();
  for (int v = 0; v < cell->n; ++v) {
    const Vec<2>& q = (*cell)[v];
    if (out.n > 0 && (q - out[out.n - 1]).squaredNorm() <= 1e-24 * dx * dx) continue;
    out.push(q);
  }
  while (out.n > 1 && (out[0] - out[out.n - 1]).squaredNorm() <= 1e-24 * dx * dx) --out.n;
  fc.site[k] = xc;
  fc.bounds[k] = geometry::bounds(out);
  volume[c] = geometry::area(*cell);
}

/// The visitor of the second pass over the old cells (2D): each old cell's share of the face region,
/// handed out by its exact overlaps with the face cells.
template <bool E>
struct FaceHandOut {
  const ParticleSet<2, E>* p;
  const Box<2>* box;
  const Footprint<2>* fp;
  const Faces* faces;
  const FaceCells2* fc;
  std::vector<FaceSums<2>> sums;
  std::vector<std::vector<std::uint32_t>> candidates;
  std::vector<std::vector<double>> omegas;

  void restart() {
    for (auto& s : sums) s.resize(s.m.size());
  }
  void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell, std::span<const Overlap> ov,
                  double V_o, double) {
    const auto t = static_cast<std::size_t>(thread);
    auto& cand = candidates[t];
    std::int32_t best_face = -1;
    const auto near = [&](std::int32_t k, auto&& push) {
      for (const std::uint32_t q : fc->nearby[static_cast<std::size_t>(k)]) push(q);
    };
    const double A_F = face_candidates(ov, fp->owner, faces->face_of, near, cand, best_face);
    if (!(A_F > 0.0)) return;
    const Vec<2> xo = p->x[a];
    auto& om = omegas[t];
    om.assign(cand.size(), 0.0);
    double A_poly = 0.0;
    const geometry::Bounds cb = geometry::bounds(cell);
    for (std::size_t i = 0; i < cand.size(); ++i) {
      const std::size_t k = cand[i];
      Vec<2> d = fc->site[k] - xo;  // nearest periodic image of the face site
      for (int ax = 0; ax < 2; ++ax)
        if (box->edge[ax] == Edge::periodic) {
          const double L = box->hi[ax] - box->lo[ax];
          d[ax] -= L * std::round(d[ax] / L);
        }
      const geometry::Bounds& wb = fc->bounds[k];
      if (((wb.lo + d).array() > cb.hi.array()).any() || ((wb.hi + d).array() < cb.lo.array()).any())
        continue;  // apart: no overlap, and no clip needed to say so
      geometry::ConvexPolygon window = fc->polygon[k];
      for (int v = 0; v < window.n; ++v) window.v[static_cast<std::size_t>(v)] += d;
      om[i] = geometry::intersection_area(cell, window);
      A_poly += om[i];
    }
    sums[t].hand_out(*p, a, V_o, A_F, A_poly, best_face, cand, om);
  }
};

/// The old cells that may meet a face cell: those whose disc of reach (from the overlap pass) touches a
/// finest cell a face cell owns.
template <bool E>
std::vector<std::uint32_t> old_cells_near_faces(const ParticleSet<2, E>& p, const Box<2>& box,
                                                const lattice::Square& fine, const CellGrid<2>& grid,
                                                const Footprint<2>& fp, const Faces& faces,
                                                const std::vector<double>& reach) {
  require(reach.size() == p.n_real, "multi-level remap: the overlap pass did not record the cells' reach");
  std::vector<std::uint8_t> in_face(grid.n_cells);  // per finest cell: owned by a face cell
  for (std::size_t f = 0; f < grid.n_cells; ++f) in_face[f] = faces.face_of[fp.owner[f]] >= 0;
  std::vector<std::uint32_t> near_faces;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const auto r = fine.cells_touching(box, p.x[a] - Vec<2>::Constant(reach[a]), p.x[a] + Vec<2>::Constant(reach[a]));
    bool meets = false;
    for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i)
      for (std::int64_t j = r.lo[1]; j <= r.hi[1]; ++j) {
        const std::int64_t fl = grid.flat({i, j});
        meets |= fl >= 0 && in_face[static_cast<std::size_t>(fl)];
      }
    if (meets) near_faces.push_back(static_cast<std::uint32_t>(a));
  }
  return near_faces;
}

/// The face cells' sums replace theirs in `cells`: the threads' in a fixed order, independent of scheduling.
template <int D>
void replace_face_sums(const Faces& faces, const std::vector<FaceSums<D>>& sums, Sums<D>& cells) {
  for (std::size_t k = 0; k < faces.cells.size(); ++k) {
    const std::size_t c = faces.cells[k];
    cells.m[c] = 0.0;
    cells.E[c] = 0.0;
    cells.fill[c] = 0.0;
    cells.mv[c] = Vec<D>::Zero();
    for (const auto& s : sums) {
      cells.m[c] += s.m[k];
      cells.E[c] += s.energy[k];
      cells.fill[c] += s.fill[k];
      cells.mv[c] += s.mv[k];
    }
  }
}

/// New cells at level faces (2D). Old cells are Voronoi cells; the new cell of a site whose one-cell ring
/// holds a cell of another level is taken as its Voronoi cell among the new sites too (as Fig. 1 of the
/// paper draws both), not its lattice square, so that a set on the lattice remaps onto itself and a
/// uniform state stays uniform. Elsewhere the two coincide. The face cells tile the same region F as
/// their lattice squares (a union of finest cells); each old cell's share of F from the finest-cell pass
/// is handed to the face cells in proportion to its exact overlaps with their Voronoi cells, so the remap
/// stays exactly conservative. Replaces the face cells' sums in `cells` and their volumes in `volume`.
/// The face cells of a footprint (2D): new cells whose one-cell ring holds a cell of another level.
inline Faces level_faces(const CellGrid<2>& grid, const Footprint<2>& fp) {
  return find_faces<2>(fp.size(), [&](std::size_t c) {
    const std::int64_t s = fp.span[c], i0 = fp.first_fine[c][0], j0 = fp.first_fine[c][1];
    for (std::int64_t i = -1; i <= s; ++i)
      for (std::int64_t j = -1; j <= s; ++j) {
        if (i >= 0 && i < s && j >= 0 && j < s) continue;
        const std::int64_t o = owner_at(grid, fp, i0 + i, j0 + j);
        if (o >= 0 && fp.span[static_cast<std::size_t>(o)] != s) return true;
      }
    return false;
  });
}

template <class Builder, bool E, class Region>
void remap_face_cells(const ParticleSet<2, E>& p, const Box<2>& box, const lattice::Square& fine, Builder& builder,
                      const CellGrid<2>& grid, const Region& region, RemapWorkspace<2>& ws, const Footprint<2>& fp,
                      const Faces& faces, Sums<2>& cells, std::vector<double>& volume) {
  if (faces.cells.empty()) return;
  const std::size_t n_faces = faces.cells.size();
  FaceCells2 fc{std::vector<geometry::ConvexPolygon>(n_faces), std::vector<Vec<2>>(n_faces),
                std::vector<geometry::Bounds>(n_faces), std::vector<std::vector<std::uint32_t>>(n_faces)};
  for (std::size_t k = 0; k < n_faces; ++k) build_face_cell(box, grid, fp, faces, k, fc, volume);
  for (auto& list : fc.nearby) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  const auto n_threads = static_cast<std::size_t>(geometry::builder_threads());
  FaceHandOut<E> hand_out{&p,
                          &box,
                          &fp,
                          &faces,
                          &fc,
                          std::vector<FaceSums<2>>(n_threads),
                          std::vector<std::vector<std::uint32_t>>(n_threads),
                          std::vector<std::vector<double>>(n_threads)};
  for (auto& s : hand_out.sums) s.resize(n_faces);
  // Only the old cells that may meet a face cell are built again.
  const auto near_faces = old_cells_near_faces(p, box, fine, grid, fp, faces, ws.reach);
  if (!near_faces.empty())  // (an empty list would mean every cell)
    for_each_old_cell(p, box, fine, builder, grid, region, ws, hand_out, near_faces);
  replace_face_sums(faces, hand_out.sums, cells);
}

/// The 1D counterpart of the above: a face cell's new cell is the interval between the midpoints to its
/// neighbouring sites.
/// The owner of finest cell i (grid-relative) in 1D and the shift of its period; -1 beyond the grid.
inline std::int64_t owner_at(const CellGrid<1>& grid, const Footprint<1>& fp, std::int64_t i, double& shift) {
  const std::int64_t fl = grid.flat({grid.range.lo[0] + i});
  if (fl < 0) return -1;
  shift = static_cast<double>(grid.range.lo[0] + i - grid.unflat(static_cast<std::size_t>(fl))[0]) * fp.dx;
  return static_cast<std::int64_t>(fp.owner[static_cast<std::size_t>(fl)]);
}

/// The face cells of a footprint (1D): new cells beside a cell of another level.
inline Faces level_faces(const CellGrid<1>& grid, const Footprint<1>& fp) {
  return find_faces<1>(fp.size(), [&](std::size_t c) {
    double shift = 0.0;
    const std::int64_t l = owner_at(grid, fp, fp.first_fine[c][0] - 1, shift),
                       r = owner_at(grid, fp, fp.first_fine[c][0] + fp.span[c], shift);
    return (l >= 0 && fp.span[static_cast<std::size_t>(l)] != fp.span[c]) ||
           (r >= 0 && fp.span[static_cast<std::size_t>(r)] != fp.span[c]);
  });
}

template <bool E>
void remap_face_cells(const ParticleSet<1, E>& p, const Box<1>& box, const lattice::Uniform1D& fine,
                      const RemapParams& params, const CellGrid<1>& grid, const Footprint<1>& fp, const Faces& faces,
                      Sums<1>& cells, std::vector<double>& volume) {
  const double dx = fp.dx;
  const double L = box.hi[0] - box.lo[0];
  auto site = [&](std::size_t c) { return fp.site(c)[0]; };
  auto owner_at = [&](std::int64_t i, double& shift) { return detail::owner_at(grid, fp, i, shift); };
  if (faces.cells.empty()) return;
  const std::size_t n_faces = faces.cells.size();
  std::vector<double> lo(n_faces), hi(n_faces), face_site(n_faces);
  std::vector<std::array<std::int32_t, 2>> beside(n_faces);
  for (std::size_t k = 0; k < n_faces; ++k) {
    const std::size_t c = faces.cells[k];
    const double xc = site(c), half = 0.5 * static_cast<double>(fp.span[c]) * dx;
    double shift = 0.0;
    const std::int64_t l = owner_at(fp.first_fine[c][0] - 1, shift);
    lo[k] = l >= 0 ? 0.5 * (site(static_cast<std::size_t>(l)) + shift - xc) : -half;  // a wall or the grid's end
    beside[k][0] = l >= 0 ? faces.face_of[static_cast<std::size_t>(l)] : -1;
    const std::int64_t r = owner_at(fp.first_fine[c][0] + fp.span[c], shift);
    hi[k] = r >= 0 ? 0.5 * (site(static_cast<std::size_t>(r)) + shift - xc) : half;
    beside[k][1] = r >= 0 ? faces.face_of[static_cast<std::size_t>(r)] : -1;
    face_site[k] = xc;
    volume[c] = hi[k] - lo[k];
  }
  std::vector<FaceSums<1>> sums(1);
  sums[0].resize(n_faces);
  std::vector<std::int32_t> cand;
  std::vector<double> om;
  const auto near = [&](std::int32_t k, auto&& push) {
    for (const std::int32_t q : beside[static_cast<std::size_t>(k)])
      if (q >= 0) push(q);
  };
  auto hand_out = [&](std::size_t a, double left, double right, const auto& ov, double V_o) {
    std::int32_t best_face = -1;
    const double A_F = face_candidates(ov, fp.owner, faces.face_of, near, cand, best_face);
    if (!(A_F > 0.0)) return;
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
    sums[0].hand_out(p, a, V_o, A_F, A_poly, best_face, cand, om);
  };
  for_each_old_interval(p, box, fine, params, grid, hand_out);
  for (std::size_t k = 0; k < n_faces; ++k) {  // one pass: the sums themselves, no thread order to fix
    const std::size_t c = faces.cells[k];
    cells.m[c] = sums[0].m[k];
    cells.E[c] = sums[0].energy[k];
    cells.fill[c] = sums[0].fill[k];
    cells.mv[c] = sums[0].mv[k];
  }
}

/// A block's (or a cell's) integer index per axis; not deduced from, so D comes from the other arguments.
template <int D>
using BlockIndex = std::type_identity_t<std::array<std::int64_t, static_cast<std::size_t>(D)>>;

/// Every closed axis of the box must hold a whole number of blocks.
template <int D, class Criterion>
void check_whole_blocks(const Box<D>& box, const lattice::MultiLevel<D, Criterion>& ml) {
  for (int k = 0; k < D; ++k)
    if (box.edge[k] != Edge::open) {
      const double blocks = (box.hi[k] - box.lo[k]) / (ml.spacing * ml.block_cells);
      require(std::abs(blocks - std::round(blocks)) < 1e-9 * std::max(1.0, blocks) && std::round(blocks) >= 1,
              "multi-level lattice: the box length along axis " + std::to_string(k) +
                  " must be a whole number of blocks (block size " + std::to_string(ml.spacing * ml.block_cells) + ")");
    }
}

/// The level-0 mass and volume per block cell that the criteria read, summed from the finest cells' sums;
/// block0 receives the absolute index of the grid's first block.
template <int D, class Criterion>
refine::BlockField<D> level0_field(const lattice::MultiLevel<D, Criterion>& ml, const Box<D>& box,
                                   const CellGrid<D>& grid, const Sums<D>& S, BlockIndex<D>& block0) {
  const std::int64_t ratio = std::int64_t{1} << ml.max_level;  // finest cells per level-0 cell and axis
  const std::int64_t align = ratio * ml.block_cells;           // finest cells per block and axis
  refine::BlockField<D> field;
  field.spacing = ml.spacing;
  field.cells_per_block = ml.block_cells;
  std::array<std::int64_t, D> n0{};
  std::size_t n_level0 = 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
    n0[k] = grid.count[k] / ratio;
    field.blocks[k] = grid.count[k] / align;
    block0[k] = grid.range.lo[k] / align;  // aligned: exact
    field.periods[k] = grid.periods[k] > 0 ? field.blocks[k] : 0;
    field.origin[static_cast<int>(k)] =
        box.lo[static_cast<int>(k)] + static_cast<double>(grid.range.lo[k]) * ml.finest().spacing;
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
  return field;
}

/// Block b's absolute index (the grid's blocks start at block0).
template <int D>
BlockIndex<D> absolute_block(const refine::BlockField<D>& field, const BlockIndex<D>& block0, std::size_t b) {
  auto bi = field.block_index(b);
  for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) bi[k] += block0[k];
  return bi;
}

/// Each block's level: the criterion's, capped at the finest level, then 2:1 balanced.
template <int D, class Criterion>
std::vector<int> choose_levels(const lattice::MultiLevel<D, Criterion>& ml, const refine::BlockField<D>& field,
                               const BlockIndex<D>& block0, RemapStats& stats) {
  std::vector<int> level(field.n_blocks(), 0);
  for (std::size_t b = 0; b < level.size(); ++b) {
    const int want =
        static_cast<int>(ml.criterion.level(field, b, ml.previous_level(absolute_block(field, block0, b))));
    stats.requested_level = std::max(stats.requested_level, want);
    if (want > ml.max_level) ++stats.capped_blocks;
    level[b] = std::clamp(want, 0, ml.max_level);
  }
  balance_two_to_one(field, level);
  return level;
}

template <int D>
Footprint<D> footprint(const refine::BlockField<D>& field, const std::vector<int>& level, const CellGrid<D>& grid,
                       int max_level, std::int64_t align, double dx) {
  Footprint<D> fp;
  fp.owner.resize(grid.n_cells);
  fp.origin = field.origin;
  fp.dx = dx;
  for (std::size_t b = 0; b < level.size(); ++b) {
    const auto bi = field.block_index(b);
    const std::int64_t s = std::int64_t{1} << (max_level - level[b]);
    std::array<std::int64_t, D> ci;
    ci.fill(0);
    do {
      std::array<std::int64_t, D> f0;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) f0[k] = bi[k] * align + ci[k] * s;
      const auto id = static_cast<std::uint32_t>(fp.first_fine.size());
      fp.first_fine.push_back(f0);
      fp.span.push_back(s);
      fp.level.push_back(level[b]);
      std::array<std::int64_t, D> fi;  // every finest cell of the footprint
      fi.fill(0);
      do {
        std::array<std::int64_t, D> g;
        for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) g[k] = grid.range.lo[k] + f0[k] + fi[k];
        fp.owner[static_cast<std::size_t>(grid.flat(g))] = id;
      } while (next_index<D>(fi, 0, s));
    } while (next_index<D>(ci, 0, align / s));
  }
  return fp;
}

/// f(o) for the owners o of the finest cells in the one-cell ring around c's footprint (repeats possible).
template <int D, class F>
void for_each_ring_neighbour(const CellGrid<D>& grid, const Footprint<D>& fp, std::size_t c, F&& f) {
  const std::int64_t s = fp.span[c];
  std::array<std::int64_t, D> off;
  off.fill(-1);
  std::uint32_t last = static_cast<std::uint32_t>(c);
  do {
    bool ring = false;
    std::array<std::int64_t, D> g;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      ring = ring || off[k] < 0 || off[k] >= s;
      g[k] = grid.range.lo[k] + fp.first_fine[c][k] + off[k];
    }
    if (ring) {
      const std::int64_t fl = grid.flat(g);
      if (fl >= 0) {
        const std::uint32_t o = fp.owner[static_cast<std::size_t>(fl)];
        if (o != c && o != last) f(static_cast<std::size_t>(o));  // repeats only cost a comparison
        last = o;
      }
    }
  } while (next_index<D>(off, -1, s + 1));
}

}  // namespace detail

namespace detail {

/// The end of the multi-level remap: nearly empty cells handed on, one particle per kept cell with h ramped
/// towards coarser blocks, and the blocks' levels stored for the next remap.
template <int D, bool E, class Criterion, class Field, class Levels>
void emit_on_levels(ParticleSet<D, E>& p, lattice::MultiLevel<D, Criterion>& ml, const RemapParams& params,
                    const CellGrid<D>& grid, const Footprint<D>& fp, const Field& field, const Levels& level,
                    const BlockIndex<D>& block0, Sums<D>& cells, const std::vector<double>& cell_volume,
                    RemapWorkspace<D>& ws, RemapStats& stats) {
  auto& keep = ws.keep;
  hand_on_sparse_cells<D>(
      cells, params, [&](std::size_t c) { return cell_volume[c]; },
      [&](std::size_t c, auto&& f) { for_each_ring_neighbour(grid, fp, c, f); }, stats.dropped_cells, keep);
  const std::size_t n_cells = fp.size();
  const std::int64_t align = (std::int64_t{1} << ml.max_level) * ml.block_cells;
  auto& order = ws.order;
  order.resize(n_cells);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<std::size_t> block_of(n_cells);
  for (std::size_t c = 0, b = 0; b < level.size(); ++b)
    for (auto n = static_cast<std::size_t>(std::pow(static_cast<double>(align >> (ml.max_level - level[b])), D)); n > 0;
         --n)
      block_of[c++] = b;
  auto place = [&](std::size_t c) {
    const Vec<D> site = fp.site(c);
    const int l = fp.level[c];
    double h = params.h_over_dx * ml.spacing_at(l);
    if (ml.h_ramp > 0.0 && l > 0) {
      // distance to the nearest coarser neighbouring block (2:1 balance: one level coarser)
      const double ramp = ml.h_ramp * ml.spacing_at(l - 1);
      const double d = distance_to_coarser_block(field, level, block_of[c], site, ramp);
      if (d < ramp) h += (params.h_over_dx * ml.spacing_at(l - 1) - h) * (1.0 - d / ramp);
    }
    return std::pair{site, h};
  };
  emit_particles(p, cells, keep, order, place, stats);
  stats.per_level.assign(static_cast<std::size_t>(ml.max_level) + 1, 0);
  for (std::size_t c = 0; c < n_cells; ++c)
    if (keep[c] && cells.m[c] > 0.0) ++stats.per_level[static_cast<std::size_t>(fp.level[c])];
  std::map<std::array<std::int64_t, D>, int> levels;
  for (std::size_t b = 0; b < level.size(); ++b) levels[absolute_block(field, block0, b)] = level[b];
  ml.store_levels(std::move(levels));
}

/// The multi-level remap around the sums on the finest cells of `grid`: sums_on(grid, stats) gives them, and
/// once the level of every block is set, at_faces(fp, faces, stats) gives them again (a second-order remap
/// takes the old cells that reach a face cell to first order, as the face cells' hand-out is). Then every
/// block's level from the criterion (capped at the finest level, 2:1 balanced), one particle per kept cell,
/// block by block and in lattice order within a block, with h = h_over_dx * Delta_l.
template <int D, class Criterion, class Builder, bool E, class Region, class SumsOn, class AtFaces>
RemapStats remap_onto_levels(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                             Builder& builder, const RemapParams& params, const Region& region, RemapWorkspace<D>& ws,
                             const CellGrid<D>& grid, SumsOn&& sums_on, AtFaces&& at_faces) {
  const auto fine = ml.finest();
  const std::int64_t align = (std::int64_t{1} << ml.max_level) * ml.block_cells;  // finest cells per block and axis
  RemapStats stats;
  const Sums<D>* S = &sums_on(grid, stats);
  stats.max_volume_mismatch = S->max_mismatch;
  std::array<std::int64_t, D> block0{};
  const auto field = level0_field(ml, box, grid, *S, block0);
  const auto level = choose_levels(ml, field, block0, stats);
  const auto fp = footprint(field, level, grid, ml.max_level, align, fine.spacing);
  Faces faces;
  if (ml.max_level > 0) {
    faces = level_faces(grid, fp);
    S = &at_faces(fp, faces, stats);
  }
  const std::size_t n_cells = fp.size();
  Sums<D> cells;  // each new cell's sums: those of its finest cells
  cells.resize(n_cells);
  for (std::size_t f = 0; f < grid.n_cells; ++f) {
    const std::size_t c = fp.owner[f];
    cells.m[c] += S->m[f];
    cells.mv[c] += S->mv[f];
    cells.E[c] += S->E[f];
    cells.fill[c] += S->fill[f];
  }
  std::vector<double> cell_volume(n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) cell_volume[c] = std::pow(ml.spacing_at(fp.level[c]), D);
  if (ml.max_level > 0) {
    if constexpr (D == 2)
      remap_face_cells(p, box, fine, builder, grid, region, ws, fp, faces, cells, cell_volume);
    else
      remap_face_cells(p, box, fine, params, grid, fp, faces, cells, cell_volume);
  }
  emit_on_levels(p, ml, params, grid, fp, field, level, block0, cells, cell_volume, ws, stats);
  return stats;
}

}  // namespace detail

/// Remaps `p` onto a multi-level lattice (detail::remap_onto_levels), each old cell handing out its mean by
/// eqs. (6)-(9). Mass, momentum and total energy are conserved exactly as on a uniform lattice.
template <int D, class Criterion, class Builder, bool E, class Region = region::Unbounded>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, lattice::MultiLevel<D, Criterion>& ml,
                              Builder& builder, const RemapParams& params, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr) {
  ml.validate();
  RemapWorkspace<D> local;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  const auto fine = ml.finest();
  detail::check_remap_input(p, fine, params);
  detail::check_whole_blocks(box, ml);
  const auto grid = detail::candidate_grid(p, box, fine, params, (std::int64_t{1} << ml.max_level) * ml.block_cells);
  return detail::remap_onto_levels(
      p, box, ml, builder, params, region, ws, grid,
      [&](const detail::CellGrid<D>& g, RemapStats&) -> detail::Sums<D>& {
        // remap_face_cells picks the old cells to build again by their reach
        return detail::accumulate_overlaps(p, box, fine, builder, params, g, region, ws, ml.max_level > 0);
      },
      [&](const auto&, const detail::Faces&, RemapStats&) -> detail::Sums<D>& { return ws.sums[0]; });
}

}  // namespace regularize
}  // namespace rsph
