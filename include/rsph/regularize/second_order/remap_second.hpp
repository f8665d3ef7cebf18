#pragma once
// The second-order remap: eqs. (6)-(9) with each old cell's density, velocity and specific total energy
// reconstructed linearly instead of taken constant. Every overlap receives the integral of the reconstruction
// over it, by its area and its first and second moments, so that mass, momentum and total energy stay
// conserved old cell by old cell, and a field linear in space is carried over exactly.
//
//   rho(x) = rho_o + g_rho . (x - x_c)        about the cell's centroid x_c: the cell keeps its mass
//   v(x)   = v_o + G_v (x - x_m)              about the cell's mass centroid x_m = x_c + I g_rho / m_o
//   e(x)   = e_o + g_e . (x - x_m)            (I: the cell's central second moments): it keeps its
//                                             momentum and total energy
// For a piece P with moments A, M1 = int x, M2 = int x x^T:
//   m_P = rho_o A + g_rho . (M1 - A x_c),   W_P = int_P rho (x - x_m) = rho_o (M1 - A x_m) + S^T g_rho,
//   S = int_P (x - x_c)(x - x_m)^T,         (m v)_P = m_P v_o + G_v W_P,   E_P = m_P e_o + g_e . W_P,
// and the W_P of a cell sum to zero. Gradients come from least squares over the Voronoi neighbours, limited
// (Barth-Jespersen) so that no vertex of the cell leaves the range of the cell and its neighbours.
#include "rsph/regularize/remap.hpp"
#include "rsph/regularize/second_order/cells.hpp"
#include "rsph/regularize/second_order/cells3d.hpp"
#include "rsph/regularize/second_order/on_owners.hpp"
#include "rsph/regularize/second_order/pieces.hpp"
#include "rsph/regularize/second_order/reconstruction.hpp"
#include "rsph/regularize/second_order/workspace.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::regularize {

namespace second_order {

template <int D>
double specific_total_energy(double u, const Vec<D>& v) {
  return u + 0.5 * v.squaredNorm();
}

/// Density gradients about the centroids, the density's range over each cell and its neighbours, and the
/// mass centroids the gradients give, for the first n_fit cells (the others' reconstructions cleared).
template <int D, bool E>
void reconstruct_density(const ParticleSet<D, E>& p, const CellStore<D>& s, std::vector<Reconstruction<D>>& recon,
                         std::size_t n_fit) {
  run_parallel(p.n_real, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      Reconstruction<D>& r = recon[a];
      r = Reconstruction<D>{};
      if (a >= n_fit || !s.built(a)) continue;
      r.x_m = s.centroid[a];
      const double rho = p.m[a] / s.volume[a];
      r.range.rho.add(rho);
      LeastSquares<D, 1> fit;
      for (const auto& f : s.faces_of(a)) {
        if (f.b == CellStore<D>::no_neighbour || !s.built(f.b)) continue;
        const double rho_b = p.m[f.b] / s.volume[f.b];
        r.range.rho.add(rho_b);
        fit.add(Vec<D>(f.d + s.centroid[f.b] - s.centroid[a]), f.length, Eigen::Matrix<double, 1, 1>(rho_b - rho));
      }
      Eigen::Matrix<double, D, 1> g;
      if (p.m[a] <= 0.0 || !fit.solve(g)) continue;
      r.g_rho = g;
      r.x_m = s.centroid[a] + s.inertia[a] * r.g_rho / p.m[a];
    }
  });
}

/// Velocity and specific total energy gradients about the mass centroids, and their ranges, for the first n_fit
/// cells.
template <int D, bool E>
void reconstruct_motion(const ParticleSet<D, E>& p, const CellStore<D>& s, std::vector<Reconstruction<D>>& recon,
                        std::size_t n_fit) {
  using Fields = Eigen::Matrix<double, D + 1, 1>;  // v, then e
  auto fields = [&](std::size_t b) {
    Fields q;
    q.template head<D>() = p.v[b];
    if constexpr (E)
      q[D] = specific_total_energy<D>(p.u[b], p.v[b]);
    else
      q[D] = 0.0;
    return q;
  };
  run_parallel(n_fit, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      Reconstruction<D>& r = recon[a];
      const Fields qa = fields(a);
      auto extend = [&](const Fields& q) {
        for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) r.range.v[k].add(q[static_cast<int>(k)]);
        r.range.e.add(q[D]);
      };
      extend(qa);
      LeastSquares<D, D + 1> fit;
      for (const auto& f : s.faces_of(a)) {
        if (f.b == CellStore<D>::no_neighbour || !s.built(f.b)) continue;
        const Fields qb = fields(f.b);
        extend(qb);
        fit.add(Vec<D>(f.d + recon[f.b].x_m - r.x_m), f.length, Fields(qb - qa));
      }
      Eigen::Matrix<double, D, D + 1> g;
      if (p.m[a] <= 0.0 || !fit.solve(g)) continue;
      r.G_v = g.template leftCols<D>().transpose();
      if constexpr (E) r.g_e = g.col(D);
    }
  });
}

/// Hands old cell o out over its pieces. The cell's volume, centroid and moments are taken from the pieces
/// themselves, so its mass and the W_P sum to it exactly whatever round-off crumbs were dropped. With
/// `bounds` (one per new cell), each gradient is scaled (Barth-Jespersen) so that no piece's mean density,
/// velocity or energy leaves the bounds of the new cell it lands in: the range of the old cells that overlap
/// that cell and of their neighbours.
template <int D>
void hand_out(const OldCell<D>& o, std::span<const std::size_t> flat, std::span<const PieceMoments<D>> moments,
              double exact_volume, const FieldRanges<D>* bounds, HandOutScratch<D>& pc, detail::Sums<D>& sums) {
  PieceMoments<D> whole;
  for (const auto& pm : moments) whole += pm;
  if (!(whole.area > 0.0)) throw NumericalError("regularization: an old cell overlaps no new cell");
  sums.max_mismatch = std::max(sums.max_mismatch, std::abs(whole.area - exact_volume) / exact_volume);
  Reconstruction<D>& r = *o.r;
  const std::size_t n = moments.size();
  const double rho = o.m / whole.area;
  const Vec<D> x_c = whole.first / whole.area;
  const Mat<D> inertia = whole.second - whole.area * x_c * x_c.transpose();
  pc.offsets.resize(n);
  pc.W.resize(n);
  pc.m.resize(n);
  auto bound = [&](auto field) {
    return std::pair{[&, field](std::size_t k) { return field(bounds[flat[k]]).lo; },
                     [&, field](std::size_t k) { return field(bounds[flat[k]]).hi; }};
  };
  double phi = 1.0;
  Vec<D> g_rho = r.g_rho;
  if (bounds) {  // the pieces' mean densities are rho at their centroids
    for (std::size_t k = 0; k < n; ++k) pc.offsets[k] = moments[k].first / moments[k].area - x_c;
    const auto [lo, hi] = bound([](const FieldRanges<D>& b) { return b.rho; });
    g_rho *= phi = barth_jespersen<D>(rho, g_rho, pc.offsets, lo, hi);
  }
  const Vec<D> x_m = o.m > 0.0 ? Vec<D>(x_c + inertia * g_rho / o.m) : x_c;
  for (std::size_t k = 0; k < n; ++k) {
    const PieceMoments<D>& pm = moments[k];
    pc.m[k] = rho * pm.area + g_rho.dot(pm.first - pm.area * x_c);
    const Mat<D> S =
        pm.second - pm.first * x_m.transpose() - x_c * pm.first.transpose() + pm.area * x_c * x_m.transpose();
    pc.W[k] = rho * (pm.first - pm.area * x_m) + S.transpose() * g_rho;
  }
  Mat<D> G_v = r.G_v;
  Vec<D> g_e = r.g_e;
  if (bounds) {  // the pieces' mean velocities and energies are the fields at their mass centroids
    for (std::size_t k = 0; k < n; ++k) pc.offsets[k] = pc.m[k] > 0.0 ? Vec<D>(pc.W[k] / pc.m[k]) : Vec<D>::Zero();
    for (std::size_t i = 0; i < static_cast<std::size_t>(D); ++i) {
      const auto [lo, hi] = bound([i](const FieldRanges<D>& b) { return b.v[i]; });
      const double phi_i =
          barth_jespersen<D>(o.v[static_cast<int>(i)], G_v.row(static_cast<int>(i)).transpose(), pc.offsets, lo, hi);
      G_v.row(static_cast<int>(i)) *= phi_i;
      phi = std::min(phi, phi_i);
    }
    const auto [lo, hi] = bound([](const FieldRanges<D>& b) { return b.e; });
    const double phi_e = barth_jespersen<D>(o.e, g_e, pc.offsets, lo, hi);
    g_e *= phi_e;
    phi = std::min(phi, phi_e);
  }
  r.limited = phi < 1.0;
  for (std::size_t k = 0; k < n; ++k)
    sums.cell[flat[k]] +=
        Conserved<D>{pc.m[k], Vec<D>(pc.m[k] * o.v + G_v * pc.W[k]), pc.m[k] * o.e + g_e.dot(pc.W[k]), moments[k].area};
}

template <int D, bool E>
OldCell<D> old_cell(const ParticleSet<D, E>& p, std::vector<Reconstruction<D>>& recon, std::size_t a) {
  OldCell<D> o;
  o.m = p.m[a];
  o.v = p.v[a];
  if constexpr (E) o.e = specific_total_energy<D>(p.u[a], p.v[a]);
  o.r = &recon[a];
  return o;
}

/// One pass over the first n_old old cells' pieces: every piece's shares into the per-thread sums (reduced into
/// sums[0]), and, with u, the least u of the cells feeding each new cell (into ws.u_min[0]).
template <int D, bool E>
void hand_out_all(const ParticleSet<D, E>& p, std::size_t n_old, bool limit, std::size_t n_cells, Workspace<D>& ws,
                  std::vector<detail::Sums<D>>& sums) {
  detail::clear_sums(sums, n_cells);
  const auto n_threads = static_cast<std::size_t>(max_threads());
  if constexpr (E) {
    ws.u_min.resize(n_threads);
    for (auto& u : ws.u_min) u.assign(n_cells, std::numeric_limits<double>::max());
  }
  run_parallel(n_old, [&](int t, std::size_t begin, std::size_t end) {
    const auto tt = static_cast<std::size_t>(t);
    for (std::size_t a = begin; a < end; ++a) {
      if (!ws.cells.built(a)) continue;
      const auto& listed = ws.threads[ws.piece_thread[a]].pieces;
      const std::span<const std::size_t> flat(listed.flat.data() + ws.piece_first[a], ws.piece_count[a]);
      const std::span<const PieceMoments<D>> moments(listed.moments.data() + ws.piece_first[a], ws.piece_count[a]);
      hand_out<D>(old_cell(p, ws.recon, a), flat, moments, ws.cells.volume[a],
                  limit && !ws.first_order[a] ? ws.bounds[0].data() : nullptr, ws.threads[tt].scratch, sums[tt]);
      if constexpr (E)
        for (const std::size_t c : flat) ws.u_min[tt][c] = std::min(ws.u_min[tt][c], p.u[a]);
    }
  });
  detail::reduce_sums(sums);
  if constexpr (E)
    run_parallel(n_cells, [&](int, std::size_t begin, std::size_t end) {
      for (std::size_t t = 1; t < ws.u_min.size(); ++t)
        for (std::size_t c = begin; c < end; ++c) ws.u_min[0][c] = std::min(ws.u_min[0][c], ws.u_min[t][c]);
    });
}

/// Marks the new cells whose thermal energy falls below the floor; returns how many.
template <int D>
std::size_t mark_cold_cells(const detail::Sums<D>& S, const std::vector<double>& u_min, double floor,
                            std::vector<std::uint8_t>& bad) {
  bad.assign(S.size(), 0);
  std::size_t n = 0;
  for (std::size_t c = 0; c < S.size(); ++c) {
    const Conserved<D>& sum = S.cell[c];
    if (!(sum.m > 0.0)) continue;
    const Vec<D> v = sum.mv / sum.m;
    const double u = sum.E / sum.m - 0.5 * v.squaredNorm();
    bad[c] = u < floor * u_min[c];
    n += bad[c];
  }
  return n;
}

/// Takes every old cell with a piece in a marked cell of the grid (`marked`, one flag per cell) to first
/// order; returns how many were newly taken.
template <int D>
std::size_t take_to_first_order(std::size_t n_old, const std::vector<std::uint8_t>& marked, Workspace<D>& ws) {
  std::size_t taken = 0;
  for (std::size_t a = 0; a < n_old; ++a) {
    if (ws.first_order[a]) continue;
    const auto& listed = ws.threads[ws.piece_thread[a]].pieces;
    bool feeds = false;
    for (std::size_t k = ws.piece_first[a], end = k + ws.piece_count[a]; k < end; ++k)
      feeds |= marked[listed.flat[k]] != 0;
    if (!feeds) continue;
    ws.first_order[a] = 1;
    auto& r = ws.recon[a];
    r.g_rho.setZero();
    r.G_v.setZero();
    r.g_e.setZero();
    ++taken;
  }
  return taken;
}

/// Hands the first n_old old cells out into ws.sums[0], again and again while a new particle falls below the
/// thermal floor, each time with the cells that feed one at first order. `owners`: on many ranks, the sums are
/// completed over the ranks after each pass, and every rank takes as many passes.
template <int D, bool E, class Owners = InOneProcess>
void hand_out_above_floor(const ParticleSet<D, E>& p, std::size_t n_old, const SecondOrderParams& second,
                          std::size_t n_cells, RemapWorkspace<D>& ws, Workspace<D>& w2, RemapStats& stats,
                          Owners&& owners = Owners{}) {
  for (stats.passes = 1;; ++stats.passes) {
    hand_out_all(p, n_old, second.limit, n_cells, w2, ws.sums);
    if constexpr (!E) {
      owners.complete_sums(ws.sums[0], nullptr);
      break;
    } else {
      owners.complete_sums(ws.sums[0], &w2.u_min[0]);
      if (!owners.any(mark_cold_cells(ws.sums[0], w2.u_min[0], second.thermal_floor, w2.bad))) break;
      const std::size_t taken = take_to_first_order(n_old, w2.bad, w2);
      stats.first_order_cells += taken;
      if (!owners.any(taken)) break;  // every feeder is at first order already: nothing left to fall back on
    }
  }
}

/// The old cells among the first n_own (on many ranks, this rank's own: a remap may build other ranks' cells too)
/// that the limiter cut in the last hand-out.
template <int D>
std::size_t limited_among(const Workspace<D>& ws, std::size_t n_own) {
  std::size_t n = 0;
  for (std::size_t a = 0; a < std::min(n_own, ws.recon.size()); ++a) n += ws.recon[a].limited;
  return n;
}

/// The old cells among the first n_own that hand out at first order.
template <int D>
std::size_t first_order_among(const Workspace<D>& ws, std::size_t n_own) {
  return static_cast<std::size_t>(std::count(
      ws.first_order.begin(),
      ws.first_order.begin() + static_cast<std::ptrdiff_t>(std::min(n_own, ws.first_order.size())), std::uint8_t{1}));
}

/// The second-order sums on the cells of `grid`: every old cell built and kept, its gradients fitted, its
/// pieces listed and handed out; lands in ws.sums[0], dense over the grid or, past
/// params.dense_cells_per_particle cells per particle and where `allow_sparse`, over the cells that receive a
/// piece (sums.hpp). `owners`: on many ranks, the remap by owners (the cells of `only`, this rank's own, built;
/// the neighbours' geometry, the bounds and the sums completed by the other ranks).
template <class Lattice, class Builder, int D, bool E, class Region, class Grid, class Owners = InOneProcess>
detail::Sums<D>& second_order_sums(const ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice,
                                   Builder& builder, const RemapParams& params, const SecondOrderParams& second,
                                   const Region& region, const Grid& grid, RemapWorkspace<D>& ws, Workspace<D>& w2,
                                   RemapStats& stats, bool allow_sparse = true,
                                   std::span<const std::uint32_t> only = {}, Owners&& owners = Owners{}) {
  if constexpr (D == 1)
    collect_cells(p, box, lattice, params, grid, w2.cells);
  else if constexpr (D == 2)
    collect_cells(p, box, builder, params, region, ws.closing, w2.by_thread, w2.lookup, w2.cells, only);
  else
    collect_cells_and_pieces(p, box, lattice, builder, params, region, grid, ws.closing, w2, only);
  if constexpr (D < 3) list_pieces(p, box, lattice, params, grid, w2);
  const std::size_t n_fit = owners.own(p.n_real);  // the cells handed out here
  owners.share_geometry(w2.cells);
  w2.recon.resize(p.n_real);
  reconstruct_density(p, w2.cells, w2.recon, n_fit);
  owners.share_mass_centroids(w2.recon);
  reconstruct_motion(p, w2.cells, w2.recon, n_fit);
  const bool sparse = allow_sparse && detail::sum_sparsely(grid.n_cells, p.n_real, params.dense_cells_per_particle);
  std::vector<std::size_t> cells;
  if (sparse)
    cells = compact_piece_cells(w2);
  else
    detail::check_dense_sums_fit<D>(grid.n_cells, p.n_real);
  const std::size_t n_cells = sparse ? cells.size() : grid.n_cells;
  owners.find_touched(p, w2, n_fit, n_cells, sparse ? &cells : nullptr);
  if (second.limit) {
    gather_bounds(n_fit, n_cells, w2);
    owners.complete_bounds(w2.bounds[0]);
  }
  w2.first_order.assign(p.n_real, 0);
  hand_out_above_floor(p, n_fit, second, n_cells, ws, w2, stats, owners);
  stats.limited_cells += limited_among(w2, n_fit);
  stats.max_volume_mismatch = ws.sums[0].max_mismatch;
  if (sparse) ws.sums[0].index_by(std::move(cells));
  return ws.sums[0];
}

}  // namespace second_order

/// The second-order remap of `p` onto `lattice`: as remap_onto_lattice (the same new particles, the same
/// hand-on of nearly empty cells), each old cell handing out its linear reconstruction instead of its
/// mean. `ws2` (optional) keeps the cells and reconstructions' storage between remaps. `part`: on many ranks, the
/// old particles whose cells are built (2D and 3D: a cell not built has no volume, hands out nothing and is no
/// neighbour in the fits) and the reduction over ranks.
template <class Lattice, class Builder, int D, bool E, class Region = region::Unbounded>
RemapStats remap_second_order(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                              const RemapParams& params, const SecondOrderParams& second, const Region& region = {},
                              RemapWorkspace<D>* workspace = nullptr, second_order::Workspace<D>* ws2 = nullptr,
                              const RankPart& part = {}) {
  static_assert(check_closing_region<Region, D>());
  static_assert(D > 1 || !Region::clips, "closing regions are for 2D and 3D cells");
  detail::check_remap_input(p, lattice, params, part);
  second.validate();
  RemapWorkspace<D> local;
  second_order::Workspace<D> local2;
  RemapWorkspace<D>& ws = workspace ? *workspace : local;
  second_order::Workspace<D>& w2 = ws2 ? *ws2 : local2;
  const auto grid = detail::new_cells(p, box, lattice, params, part);
  RemapStats stats;
  ws.elsewhere.clear();
  if (part.by_owners()) {  // the sums travel by their cell's number as every rank names it
    auto by_owners = [&](const auto& cells, const auto& emit_cells) {
      second_order::ByOwners<D, std::decay_t<decltype(cells)>> owners(part, cells);
      const auto& S = second_order::second_order_sums(p, box, lattice, builder, params, second, region, grid, ws, w2,
                                                      stats, true, part.cells, owners);
      auto kept = owners.kept_sums(S, ws.elsewhere);
      detail::emit_on_lattice(p, box, lattice, params, emit_cells, kept, ws, stats, part);
    };
    detail::with_cells_of_ranks(p, box, lattice, params, grid, part, by_owners);
    return stats;
  }
  second_order::second_order_sums(p, box, lattice, builder, params, second, region, grid, ws, w2, stats, true,
                                  part.cells);
  detail::emit_on_lattice(p, box, lattice, params, grid, ws.sums[0], ws, stats, part);
  return stats;
}

}  // namespace rsph::regularize
