#pragma once
// The conservative remap of eqs. (6)-(9): old particles -> new lattice particles through the exact
// overlaps Omega_n^o of old Voronoi cells and new lattice cells.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/voronoi.hpp"
#include "rsph/regularize/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
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
};

namespace detail {

/// Per-thread sums over old particles for each new cell of a dense index grid.
template <int D>
struct Sums {
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
  /// Adds old particle (m_o, v_o, e_o) to the cells `idx` with overlaps `omega`; V_o = sum omega
  /// (eq. 7), so its mass m_o is handed out exactly. `exact_volume` is the cell's own area, for the log.
  void add(const std::vector<std::pair<std::size_t, double>>& overlaps, double m_o, const Vec<D>& v_o, double e_o,
           double exact_volume) {
    double V_o = 0.0;
    for (const auto& ov : overlaps) V_o += ov.second;
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
  void merge(const Sums& o) {
    for (std::size_t i = 0; i < m.size(); ++i) {
      m[i] += o.m[i];
      E[i] += o.E[i];
      fill[i] += o.fill[i];
      mv[i] += o.mv[i];
    }
    max_mismatch = std::max(max_mismatch, o.max_mismatch);
  }
};

inline std::int64_t wrap_index(std::int64_t i, std::int64_t period) {
  i %= period;
  return i < 0 ? i + period : i;
}

}  // namespace detail

/// Remaps `p` (real particles only, no ghosts) onto `lattice`; returns the statistics. New particles
/// are stored in lattice order with h = h_over_dx * Delta; u absorbs the kinetic energy lost when the
/// gas carries it.
template <class Lattice, class Builder, int D, bool E>
RemapStats remap_onto_lattice(ParticleSet<D, E>& p, const Box<D>& box, const Lattice& lattice, Builder& builder,
                              const RemapParams& params) {
  static_assert(Lattice::dim == D, "the lattice's dimension differs from the particles'");
  params.validate();
  require(lattice.spacing > 0.0, "regularization: the lattice spacing must be positive");
  require(p.n_ghost() == 0, "regularization: remove ghosts before remapping");
  require(p.n_real > 0, "regularization: no particles to remap");
  const std::size_t n_old = p.n_real;
  const auto periods = lattice.periods(box);

  // Dense grid of candidate new cells.
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
  IndexRange<D> range = lattice.cells_touching(box, lo, hi);
  std::array<std::int64_t, D> count;
  std::size_t n_cells = 1;
  for (int k = 0; k < D; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (periods[kk] > 0) {
      range.lo[kk] = 0;
      range.hi[kk] = periods[kk] - 1;
    } else if (box.edge[k] == Edge::reflecting) {
      // rows whose sites lie inside the walls
      while (lattice.site(box, range.lo)[k] < box.lo[k]) ++range.lo[kk];
      auto top = range.lo;
      top[kk] = range.hi[kk];
      while (lattice.site(box, top)[k] > box.hi[k]) top[kk] = --range.hi[kk];
    }
    count[kk] = range.hi[kk] - range.lo[kk] + 1;
    n_cells *= static_cast<std::size_t>(count[kk]);
  }
  require(n_cells < (std::size_t{1} << 31), "regularization: the lattice would have more than 2^31 cells");
  // Flat index of a cell, wrapping periodic axes; -1 outside the grid.
  auto flat = [&](std::array<std::int64_t, D> idx) -> std::int64_t {
    std::int64_t f = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      std::int64_t i = idx[kk];
      if (periods[kk] > 0) i = detail::wrap_index(i, periods[kk]);
      i -= range.lo[kk];
      if (i < 0 || i >= count[kk]) return -1;
      f = f * count[kk] + i;
    }
    return f;
  };

  const int n_threads = geometry::builder_threads();
  std::vector<detail::Sums<D>> sums(static_cast<std::size_t>(n_threads));
  for (auto& s : sums) s.resize(n_cells);
  auto specific_energy = [&](std::size_t a) {
    if constexpr (E)
      return p.u[a];
    else
      return 0.0;
  };

  if constexpr (D == 1) {
    // 1D cells: the intervals between midpoints to the neighbours (walls and periodic wrap at the ends).
    std::vector<std::uint32_t> order(n_old);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return p.x[a][0] < p.x[b][0]; });
    const double L = box.hi[0] - box.lo[0];
    std::vector<std::pair<std::size_t, double>> overlaps;
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
      const auto r = lattice.cells_touching(box, Vec<1>(left), Vec<1>(right));
      for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i) {
        const auto [c0, c1] = lattice.cell(box, i);
        const double omega = std::min(right, c1) - std::max(left, c0);
        if (omega <= 0.0) continue;
        std::int64_t f = flat({i});
        if (f < 0) f = flat({std::clamp(i, range.lo[0], range.hi[0])});  // round-off sliver beyond a wall
        overlaps.emplace_back(static_cast<std::size_t>(f), omega);
      }
      sums[0].add(overlaps, p.m[a], p.v[a], specific_energy(a), right - left);
    }
  } else {
    static_assert(D == 2, "the remap supports 1D and 2D");
    std::vector<double> closing;
    if (box.edge[0] == Edge::open || box.edge[1] == Edge::open) {
      closing.resize(n_old);
      for (std::size_t a = 0; a < n_old; ++a) closing[a] = params.closing_radius_in_h * p.h[a];
    }
    struct Visitor {
      std::vector<detail::Sums<2>>* sums;
      const ParticleSet<D, E>* p;
      const Lattice* lattice;
      const Box<2>* box;
      decltype(flat)* flat_index;
      const std::array<std::array<std::int64_t, 2>, 2>* range;
      std::vector<std::vector<std::pair<std::size_t, double>>> overlaps;

      std::array<std::int64_t, 2> clamp_to_walls(std::array<std::int64_t, 2> idx) const {
        for (int k = 0; k < 2; ++k)
          if (box->edge[k] == Edge::reflecting)
            idx[static_cast<std::size_t>(k)] =
                std::clamp(idx[static_cast<std::size_t>(k)], (*range)[0][static_cast<std::size_t>(k)],
                           (*range)[1][static_cast<std::size_t>(k)]);
        return idx;
      }
      void restart() {
        for (auto& s : *sums) s.resize(s.m.size());
      }
      void operator()(int thread, std::size_t a, const geometry::ConvexPolygon& cell) {
        auto& ov = overlaps[static_cast<std::size_t>(thread)];
        ov.clear();
        const Vec<2> xo = p->x[a];
        const geometry::Bounds cb = geometry::bounds(cell);
        const double cell_area = geometry::area(cell);
        const auto r = lattice->cells_touching(*box, Vec<2>(cb.lo + xo), Vec<2>(cb.hi + xo));
        for (std::int64_t j = r.lo[1]; j <= r.hi[1]; ++j)
          for (std::int64_t i = r.lo[0]; i <= r.hi[0]; ++i) {
            const std::array<std::int64_t, 2> idx{i, j};
            const geometry::ConvexPolygon nc = lattice->cell(*box, idx, xo);
            double omega;
            if constexpr (Lattice::rectangular_cells)
              omega = geometry::clipped_area_rect(cell, cb, cell_area, nc[0].x(), nc[0].y(), nc[2].x(), nc[2].y());
            else
              omega = geometry::area(geometry::clip_convex(cell, nc));
            if (omega <= 0.0) continue;
            std::int64_t f = (*flat_index)(idx);
            if (f < 0) f = (*flat_index)(clamp_to_walls(idx));  // round-off sliver beyond a wall
            if (f < 0)
              throw NumericalError("regularization: an old cell reaches beyond the lattice grid (particle " +
                                   std::to_string(a) + ")");
            ov.emplace_back(static_cast<std::size_t>(f), omega);
          }
        const double e_o = [&] {
          if constexpr (E)
            return p->u[a];
          else
            return 0.0;
        }();
        (*sums)[static_cast<std::size_t>(thread)].add(ov, p->m[a], p->v[a], e_o, cell_area);
      }
    };
    const std::array<std::array<std::int64_t, 2>, 2> grid{{{range.lo[0], range.lo[1]}, {range.hi[0], range.hi[1]}}};
    Visitor visitor{&sums,
                    &p,
                    &lattice,
                    &box,
                    &flat,
                    &grid,
                    std::vector<std::vector<std::pair<std::size_t, double>>>(static_cast<std::size_t>(n_threads))};
    builder.build(p.x, box, closing, visitor);
  }

  // Reduce the per-thread sums (fixed order: the result does not depend on scheduling).
  for (std::size_t t = 1; t < sums.size(); ++t) sums[0].merge(sums[t]);
  auto& S = sums[0];

  // Hand the share of nearly empty cells to their fullest neighbour.
  RemapStats stats;
  stats.n_before = n_old;
  stats.max_volume_mismatch = S.max_mismatch;
  const double cell_volume = lattice.cell_volume();
  std::vector<std::uint8_t> keep(n_cells, 0);
  const double min_mass = params.min_mass_ratio * *std::max_element(S.m.begin(), S.m.end());
  for (std::size_t c = 0; c < n_cells; ++c)
    keep[c] = S.fill[c] > params.min_fill * cell_volume && S.m[c] > 0.0 && S.m[c] >= min_mass;
  auto unflat = [&](std::size_t f) {
    std::array<std::int64_t, D> idx;
    for (int k = 0; k < D; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      idx[kk] = range.lo[kk] + static_cast<std::int64_t>(f % static_cast<std::size_t>(count[kk]));
      f /= static_cast<std::size_t>(count[kk]);
    }
    return idx;
  };
  // Each pass hands every cell that gets no particle to its fullest kept neighbour or, lacking one, to
  // its heaviest neighbour that outweighs it; shares so flow towards kept cells along rising mass.
  // Cells with no such neighbour at all keep their particle rather than lose their share.
  auto best_neighbour = [&](std::size_t c) {
    const auto idx = unflat(c);
    std::int64_t kept_best = -1, heavy_best = -1;
    double best_fill = 0.0, best_mass = S.m[c];
    std::array<std::int64_t, D> off{};
    for (int k = 0; k < D; ++k) off[static_cast<std::size_t>(k)] = -1;
    for (;;) {
      std::array<std::int64_t, D> nb;
      for (int k = 0; k < D; ++k)
        nb[static_cast<std::size_t>(k)] = idx[static_cast<std::size_t>(k)] + off[static_cast<std::size_t>(k)];
      const std::int64_t f = flat(nb);
      if (f >= 0 && static_cast<std::size_t>(f) != c) {
        const auto g = static_cast<std::size_t>(f);
        if (keep[g] && S.fill[g] > best_fill) {
          kept_best = f;
          best_fill = S.fill[g];
        }
        if (!keep[g] && S.m[g] > best_mass) {
          heavy_best = f;
          best_mass = S.m[g];
        }
      }
      int k = 0;
      for (; k < D; ++k) {
        if (++off[static_cast<std::size_t>(k)] <= 1) break;
        off[static_cast<std::size_t>(k)] = -1;
      }
      if (k == D) break;
    }
    return kept_best >= 0 ? kept_best : heavy_best;
  };
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
      S.m[c] = 0.0;
      S.mv[c] = Vec<D>::Zero();
      S.E[c] = 0.0;
      ++stats.dropped_cells;
      moved = true;
    }
  }
  for (std::size_t c = 0; c < n_cells; ++c)
    if (!keep[c] && S.m[c] > 0.0) keep[c] = 1;  // no neighbour to take its share

  // New particles in lattice order; u takes up the kinetic energy the averaging removed.
  double ke_before = 0.0, ke_after = 0.0;
  for (std::size_t a = 0; a < n_old; ++a) ke_before += 0.5 * p.m[a] * p.v[a].squaredNorm();
  ParticleSet<D, E> fresh;
  std::size_t n_new = 0;
  for (std::size_t c = 0; c < n_cells; ++c) n_new += keep[c] && S.m[c] > 0.0;
  fresh.reserve(n_new);
  const double h_new = params.h_over_dx * lattice.spacing;
  for (std::size_t c = 0; c < n_cells; ++c) {
    if (!keep[c] || !(S.m[c] > 0.0)) continue;
    const double m_n = S.m[c];
    const Vec<D> v_n = S.mv[c] / m_n;  // eq. (8)
    const double ke = 0.5 * m_n * v_n.squaredNorm();
    ke_after += ke;
    const double e_n = std::max(0.0, (S.E[c] - ke) / m_n);  // eq. (9) plus the converted kinetic energy
    auto idx = unflat(c);
    fresh.add(m_n, lattice.site(box, idx), v_n, h_new, e_n);
  }
  stats.n_after = fresh.n_real;
  stats.kinetic_converted = ke_before - ke_after;
  p = std::move(fresh);
  return stats;
}

}  // namespace rsph::regularize
