#pragma once
// The new cells at level faces of a multi-level lattice (multilevel.hpp): a face cell's new cell is its
// Voronoi cell among the new sites (2D) or the interval between the midpoints to its neighbours (1D), and each
// old cell's share of the face region is handed to the face cells by its exact overlaps with them.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/multilevel_lattice.hpp"
#include "rsph/regularize/remap.hpp"

#include <algorithm>
#include <numeric>
#include <span>
#include <vector>

namespace rsph::regularize::detail {

/// What the face cells receive from the old cells that meet them (one per thread in 2D).
template <int D>
struct FaceSums {
  std::vector<Conserved<D>> cell;

  std::size_t size() const { return cell.size(); }
  void resize(std::size_t n) { cell.assign(n, Conserved<D>{}); }

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
      cell[k] += Conserved<D>{dm, Vec<D>(dm * p.v[a]), dm * specific_energy, omega};
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
    for (auto& s : sums) s.resize(s.size());
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
/// finest cell a face cell owns; a cell the overlap pass did not build (reach -1) is left out.
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
    if (reach[a] < 0.0) continue;
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
    cells.cell[c] = Conserved<D>{};
    for (const auto& s : sums) cells.cell[c] += s.cell[k];
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

/// `only` (ascending, empty for all): the old particles whose intervals hand out (on many ranks, a rank's own).
template <bool E>
void remap_face_cells(const ParticleSet<1, E>& p, const Box<1>& box, const lattice::Uniform1D& fine,
                      const RemapParams& params, const CellGrid<1>& grid, const Footprint<1>& fp, const Faces& faces,
                      Sums<1>& cells, std::vector<double>& volume, std::span<const std::uint32_t> only = {}) {
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
    if (!only.empty() && !std::binary_search(only.begin(), only.end(), static_cast<std::uint32_t>(a))) return;
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
    cells.cell[c] = sums[0].cell[k];
  }
}

}  // namespace rsph::regularize::detail
