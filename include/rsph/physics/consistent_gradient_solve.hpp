#pragma once
// The solve behind physics::ConsistentGradient (consistent_gradient.hpp): psi on the band of particles
// around level faces (those with a neighbour of another h, grown by term.band_layers neighbour layers);
// pairs with a member outside keep grad W. Per axis k by conjugate gradients:
//   sum_{b in band} w_ab (psi_a - s_b psi_src(b)) = V_a E_a,
// where a ghost b stands for its source with s_b = -1 when it mirrors axis k (a mirrored psi flips its
// normal component). Outside the band a uniform lattice has E = 0; so the band's flux balances and a
// uniform state is exact. Warm-started from the last psi. Ghosts take their source's psi and membership.
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/conjugate_gradient.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/physics/consistent_gradient.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <span>
#include <vector>

namespace rsph::physics {

/// What the solve needs on many ranks (mpi/decomposition.hpp), where the band spans them: the halos' values of a
/// per-point field from their owners, sums over the ranks, and rows combined by name over them. Empty in one
/// process.
struct SolveOnRanks {
  std::function<void(std::vector<double>&)> refresh_halos;  ///< halo entries of a per-point field, from their owners
  std::function<void(std::span<double>)> sum;               ///< values summed over the ranks in place, in one reduction
  /// rows of a name and w values, each row's values made the sum (`add`) or the largest of every rank's rows of its
  /// name (Decomposition::combine_by_name)
  std::function<void(std::vector<double>& rows, std::size_t w, bool add)> combine;
  bool active() const { return static_cast<bool>(sum); }
  /// One value summed over the ranks.
  double sum_of(double v) const {
    sum(std::span<double>(&v, 1));
    return v;
  }
};

/// The state of the consistent-gradient solve a simulation keeps between force passes.
template <int D>
class ConsistentGradientWorkspace {
 public:
  std::vector<Vec<D>> psi;         ///< per point (real and ghosts)
  std::vector<std::uint8_t> band;  ///< per point: whether its pairs use the corrected gradient
  CgResult last;                   ///< the last solve, summed over axes
  std::uint64_t solves = 0, iterations = 0;

  /// Saves or restores what the next pass reads: psi of the n real particles (its warm start, or kept; none
  /// after a remap) and their band, per particle, and the counts.
  template <class Archive>
  void checkpoint(Archive& ar, std::size_t n) {
    const auto scope = ar.scope("consistent_gradient");
    std::uint64_t solved = psi.size() >= n;
    ar("solved", solved);
    psi.resize(n);
    band.resize(n);
    ar.rows("psi", psi);
    ar.rows("band", band);
    if (!solved) psi.clear();
    ar("solves", solves);
    ar("iterations", iterations);
    ar("last_iterations", last.iterations);
    ar("last_residual", last.relative_residual);
    ar("last_converged", last.converged);
  }

  /// New particles (after a remap): the next pass solves afresh.
  void reset() { psi.clear(); }

  /// psi and the band for the current neighbour lists: solved when fresh or term.every_step, else kept;
  /// then mirrored onto the ghosts. `ranks`: on many ranks, the band and the solve span them (a halo is a ghost
  /// that is its own source; its flags and psi come from its owner).
  template <class Kernel, class P>
  void update(const ConsistentGradient& term, const P& p, const Box<D>& box, const neighbors::NeighborList& nl,
              const SolveOnRanks& ranks = {}) {
    const std::size_t n = p.n_real;
    const bool fresh = psi.size() < n;
    if (fresh || term.every_step) {
      find_band(term, p, nl, ranks);
      std::vector<Vec<D>> psi_old;
      if (!fresh) psi_old.assign(psi.begin(), psi.begin() + static_cast<std::ptrdiff_t>(n));
      psi.assign(p.size_with_ghosts(), Vec<D>::Zero());
      last = CgResult{};
      last.converged = true;
      if (ranks.active() ? ranks.sum_of(static_cast<double>(members_.size())) > 0.0 : !members_.empty()) {
        pair_weights_and_rhs<Kernel>(p, box, nl);
        const auto anchored = ranks.active() ? pieces_on_ranks(p, nl, ranks) : connected_pieces(n, nl, p.ghost_source);
        const auto diagonal = assemble(n, nl, p.ghost_source);
        for (int axis = 0; axis < D; ++axis)
          solve_axis(term, axis, diagonal, anchored, fresh ? nullptr : &psi_old, ranks);
      }
      ++solves;
      iterations += static_cast<std::uint64_t>(last.iterations);
    }
    if (ranks.active()) {
      for (int axis = 0; axis < D; ++axis) {  // the halos' psi from their owners
        std::vector<double> c(p.size_with_ghosts());
        for (std::size_t a = 0; a < n; ++a) c[a] = psi[a][axis];
        ranks.refresh_halos(c);
        for (std::size_t g = n; g < c.size(); ++g)
          if (is_halo(p.ghost_source, n, g)) psi[g][axis] = c[g];
      }
    }
    mirror_onto_ghosts(p, box);
  }

 private:
  using Anchors = std::vector<std::array<bool, D>>;
  using Diagonal = std::array<std::vector<double>, D>;

  static std::size_t source_of(std::uint32_t b, std::size_t n, const std::vector<std::uint32_t>& ghost_source) {
    return b < n ? b : ghost_source[b - n];
  }
  /// Whether ghost g is a halo of another rank's particle (its own source), not an image.
  static bool is_halo(const std::vector<std::uint32_t>& ghost_source, std::size_t n, std::size_t g) {
    return ghost_source[g - n] == g;
  }
  /// On many ranks: the halos' band flags from their owners.
  static void refresh_flags(std::vector<std::uint8_t>& flags, std::size_t n, const SolveOnRanks& ranks) {
    if (!ranks.active()) return;
    std::vector<double> f(flags.begin(), flags.end());
    ranks.refresh_halos(f);
    for (std::size_t g = n; g < f.size(); ++g) flags[g] = f[g] != 0.0;
  }

  /// The particles with a neighbour of another h, grown by term.band_layers neighbour layers, and each
  /// member's index in the band.
  /// On many ranks the halos' flags follow each layer, and the band's halo members are numbered after this
  /// rank's own (band_index_), as the columns they are in the matrix.
  template <class P>
  void find_band(const ConsistentGradient& term, const P& p, const neighbors::NeighborList& nl,
                 const SolveOnRanks& ranks) {
    const std::size_t n = p.n_real, n_all = p.size_with_ghosts();
    band.assign(n_all, 0);
    for (std::size_t a = 0; a < n; ++a)
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k)
        if (std::abs(p.h[nl.index[k]] - p.h[a]) > 1e-12 * p.h[a]) {
          band[a] = 1;
          break;
        }
    refresh_flags(band, n, ranks);
    for (int layer = 0; layer < term.band_layers; ++layer) {
      grow_.assign(band.begin(), band.begin() + static_cast<std::ptrdiff_t>(n));
      for (std::size_t a = 0; a < n; ++a) {
        if (band[a]) continue;
        for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k)
          if (band[source_of(nl.index[k], n, p.ghost_source)]) {
            grow_[a] = 1;
            break;
          }
      }
      std::copy(grow_.begin(), grow_.end(), band.begin());
      refresh_flags(band, n, ranks);
    }
    band_index_.assign(ranks.active() ? n_all : n, -1);
    members_.clear();
    for (std::size_t a = 0; a < n; ++a)
      if (band[a]) {
        band_index_[a] = static_cast<std::int32_t>(members_.size());
        members_.push_back(static_cast<std::uint32_t>(a));
      }
    halo_members_.clear();
    if (ranks.active())
      for (std::size_t g = n; g < n_all; ++g)
        if (band[g] && is_halo(p.ghost_source, n, g)) {
          band_index_[g] = static_cast<std::int32_t>(members_.size() + halo_members_.size());
          halo_members_.push_back(static_cast<std::uint32_t>(g));
        }
  }

  /// Volumes, each ghost's mirrored axes, the pair weights w_ab = V_a V_b W_ab within the band, and the
  /// right-hand sides V_a E_a per axis.
  template <class Kernel, class P>
  void pair_weights_and_rhs(const P& p, const Box<D>& box, const neighbors::NeighborList& nl) {
    const std::size_t n = p.n_real, n_all = p.size_with_ghosts(), m = members_.size();
    V_.resize(n_all);
    for (std::size_t a = 0; a < n_all; ++a) V_[a] = p.m[a] / p.rho[a];
    ghost_flips_.resize(n_all - n);
    for (std::size_t g = n; g < n_all; ++g) ghost_flips_[g - n] = boundary::mirror_flips(p, box, g);
    pair_w_.resize(nl.index.size());
    for (auto& r : rhs_) r.resize(m);
#pragma omp parallel for schedule(static) if (m >= kParallelMin)
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint32_t a = members_[i];
      Vec<D> E = Vec<D>::Zero();
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
        const std::uint32_t b = nl.index[k];
        const Vec<D> r_ab = p.x[a] - p.x[b];
        const double r = r_ab.norm();
        const double h_ab = 0.5 * (p.h[a] + p.h[b]);
        const bool inside = r > 0.0 && band[source_of(b, n, p.ghost_source)];
        pair_w_[k] = inside ? laplacian_weight(V_[a], V_[b], kernel::W<Kernel, D>(r, h_ab)) : 0.0;
        if (r > 0.0) E += zeroth_order_error_term<D>(V_[b], kernel::grad_W<Kernel, D>(r_ab, r, h_ab));
      }
      for (int k = 0; k < D; ++k) rhs_[static_cast<std::size_t>(k)][i] = V_[a] * E[k];
    }
  }

  /// Connected pieces of the band, and per axis whether a mirror pair anchors a piece (otherwise psi is
  /// fixed only up to a constant there, and the right-hand side is kept in the range).
  Anchors connected_pieces(std::size_t n, const neighbors::NeighborList& nl, const std::vector<std::uint32_t>& gs) {
    const std::size_t m = members_.size();
    piece_.assign(m, -1);
    Anchors anchored;
    std::vector<std::size_t> stack;
    for (std::size_t start = 0; start < m; ++start) {
      if (piece_[start] >= 0) continue;
      const auto id = static_cast<std::int32_t>(anchored.size());
      anchored.push_back({});
      piece_[start] = id;
      stack.assign(1, start);
      while (!stack.empty()) {
        const std::uint32_t a = members_[stack.back()];
        stack.pop_back();
        for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
          if (pair_w_[k] == 0.0) continue;
          const std::uint32_t b = nl.index[k];
          if (b >= n)
            for (int ax = 0; ax < D; ++ax)
              if (ghost_flips_[b - n] & (1u << ax)) anchored.back()[static_cast<std::size_t>(ax)] = true;
          const auto j = static_cast<std::size_t>(band_index_[source_of(b, n, gs)]);
          if (piece_[j] < 0) {
            piece_[j] = id;
            stack.push_back(j);
          }
        }
      }
    }
    return anchored;
  }

  /// connected_pieces over the ranks: each piece is named by the least identity among its members, found by
  /// passing names across pairs and, between rounds, across the halos, until no rank changes one; whether a
  /// mirror pair anchors it is combined over the ranks that hold a part of it.
  template <class P>
  Anchors pieces_on_ranks(const P& p, const neighbors::NeighborList& nl, const SolveOnRanks& ranks) {
    const std::size_t n = p.n_real, m = members_.size();
    std::vector<double> name(p.size_with_ghosts(), std::numeric_limits<double>::infinity());
    for (std::size_t a = 0; a < n; ++a)
      if (band[a]) name[a] = static_cast<double>(p.id[a]);
    for (bool changed = true; changed;) {
      changed = false;
      for (bool again = true; again;) {
        again = false;
        for (std::size_t i = 0; i < m; ++i) {
          const std::uint32_t a = members_[i];
          for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
            if (pair_w_[k] == 0.0) continue;
            const std::size_t b = source_of(nl.index[k], n, p.ghost_source);
            const double least = std::min(name[a], name[b]);
            if (name[a] != least || (b < n && name[b] != least)) {
              name[a] = least;
              if (b < n) name[b] = least;
              again = changed = true;
            }
          }
        }
      }
      ranks.refresh_halos(name);
      changed = ranks.sum_of(changed ? 1.0 : 0.0) > 0.0;
    }
    // each piece's local number, and its anchors over all ranks: (name, anchored per axis) from every rank
    std::map<double, std::int32_t> local;
    piece_.assign(m, -1);
    for (std::size_t i = 0; i < m; ++i)
      piece_[i] = local.emplace(name[members_[i]], static_cast<std::int32_t>(local.size())).first->second;
    std::vector<std::array<bool, D>> mine(local.size());
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint32_t a = members_[i];
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
        const std::uint32_t b = nl.index[k];
        if (pair_w_[k] == 0.0 || b < n) continue;
        for (int ax = 0; ax < D; ++ax)
          if (ghost_flips_[b - n] & (1u << ax))
            mine[static_cast<std::size_t>(piece_[i])][static_cast<std::size_t>(ax)] = true;
      }
    }
    std::vector<double> rows;
    for (const auto& [nm, c] : local) {
      rows.push_back(nm);
      for (int ax = 0; ax < D; ++ax) rows.push_back(mine[static_cast<std::size_t>(c)][static_cast<std::size_t>(ax)]);
    }
    ranks.combine(rows, D, false);  // anchored along an axis on any rank
    Anchors anchored(local.size());
    for (std::size_t r = 0; r < rows.size(); r += D + 1) {
      const auto c = static_cast<std::size_t>(local.at(rows[r]));
      for (int ax = 0; ax < D; ++ax) anchored[c][static_cast<std::size_t>(ax)] = rows[r + 1 + ax] != 0.0;
    }
    piece_names_.assign(local.size(), 0.0);
    for (const auto& [nm, c] : local) piece_names_[static_cast<std::size_t>(c)] = nm;
    return anchored;
  }

  /// The band's matrix (CSR): row i holds, for each pair with a band member b that is not i's own mirror
  /// image, b's band index and per axis its weight times the sign of b's mirroring; the rest of each row
  /// lands on the diagonal, which is returned. Iterating on it instead of the neighbour list skips the pairs
  /// leaving the band and the ghost look-ups in every product.
  Diagonal assemble(std::size_t n, const neighbors::NeighborList& nl, const std::vector<std::uint32_t>& gs) {
    const std::size_t m = members_.size();
    row_.assign(m + 1, 0);
    col_.clear();
    for (auto& c : coef_) c.clear();
    Diagonal diagonal;
    for (auto& d : diagonal) d.assign(m, 0.0);
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint32_t a = members_[i];
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
        const double w = pair_w_[k];
        if (w == 0.0) continue;
        const std::uint32_t b = nl.index[k];
        const std::uint8_t flips = b >= n ? ghost_flips_[b - n] : std::uint8_t(0);
        if (source_of(b, n, gs) == a) {  // a's mirror image: w (psi_a - s psi_a)
          for (int axis = 0; axis < D; ++axis)
            diagonal[static_cast<std::size_t>(axis)][i] += (flips & (1u << axis)) ? 2.0 * w : 0.0;
          continue;
        }
        col_.push_back(static_cast<std::uint32_t>(band_index_[source_of(b, n, gs)]));
        for (int axis = 0; axis < D; ++axis) {
          diagonal[static_cast<std::size_t>(axis)][i] += w;
          coef_[static_cast<std::size_t>(axis)].push_back((flips & (1u << axis)) ? -w : w);
        }
      }
      row_[i + 1] = col_.size();
    }
    return diagonal;
  }

  /// One axis: the right-hand side kept in the range of unanchored pieces, then conjugate gradients from
  /// the last psi (or zero).
  /// On many ranks the product reads the halo members' values from their owners, and the pieces' means and the
  /// solver's dot products are summed over the ranks.
  void solve_axis(const ConsistentGradient& term, int axis, const Diagonal& diagonal, const Anchors& anchored,
                  const std::vector<Vec<D>>* psi_old, const SolveOnRanks& ranks) {
    const std::size_t m = members_.size();
    const auto ax = static_cast<std::size_t>(axis);
    const auto& diag = diagonal[ax];
    const auto& coef = coef_[ax];
    std::vector<double> with_halos, field;
    auto apply = [&](const std::vector<double>& own, std::vector<double>& out) {
      const std::vector<double>* in = &own;
      if (ranks.active()) {  // the halo members' entries after this rank's own
        field.assign(band_index_.size(), 0.0);
        for (std::size_t i = 0; i < m; ++i) field[members_[i]] = own[i];
        ranks.refresh_halos(field);
        with_halos.assign(own.begin(), own.end());
        for (const auto g : halo_members_) with_halos.push_back(field[g]);
        in = &with_halos;
      }
      out.resize(m);
#pragma omp parallel for schedule(static) if (m >= kParallelMin)
      for (std::size_t i = 0; i < m; ++i) {
        double off = 0.0;
        for (std::size_t e = row_[i]; e < row_[i + 1]; ++e) off += coef[e] * (*in)[col_[e]];
        out[i] = diag[i] * (*in)[i] - off;
      }
    };
    auto& rhs = rhs_[ax];
    std::vector<double> mean(anchored.size(), 0.0), count(anchored.size(), 0.0);
    for (std::size_t i = 0; i < m; ++i) {
      mean[static_cast<std::size_t>(piece_[i])] += rhs[i];
      count[static_cast<std::size_t>(piece_[i])] += 1.0;
    }
    if (ranks.active()) sum_pieces_over_ranks(mean, count, ranks);
    for (std::size_t i = 0; i < m; ++i) {
      const auto c = static_cast<std::size_t>(piece_[i]);
      if (!anchored[c][ax]) rhs[i] -= mean[c] / count[c];
    }
    std::vector<double> component(m);
    for (std::size_t i = 0; i < m; ++i) component[i] = psi_old ? (*psi_old)[members_[i]][axis] : 0.0;
    const CgResult res =
        ranks.active() ? conjugate_gradient(apply, diag, rhs, component, term.tolerance, term.max_iterations, ranks.sum)
                       : conjugate_gradient(apply, diag, rhs, component, term.tolerance, term.max_iterations);
    last.iterations += res.iterations;
    last.relative_residual = std::max(last.relative_residual, res.relative_residual);
    last.converged = last.converged && res.converged;
    for (std::size_t i = 0; i < m; ++i) psi[members_[i]][axis] = component[i];
  }

  /// Each piece's sum and count over every rank (pieces named by piece_names_).
  void sum_pieces_over_ranks(std::vector<double>& sum, std::vector<double>& count, const SolveOnRanks& ranks) const {
    std::vector<double> rows;
    for (std::size_t c = 0; c < sum.size(); ++c) rows.insert(rows.end(), {piece_names_[c], sum[c], count[c]});
    ranks.combine(rows, 2, true);
    for (std::size_t c = 0; c < sum.size(); ++c)
      std::tie(sum[c], count[c]) = std::pair(rows[3 * c + 1], rows[3 * c + 2]);
  }

  /// Ghosts take their source's psi (its mirrored components flipped) and band membership.
  template <class P>
  void mirror_onto_ghosts(const P& p, const Box<D>& box) {
    const std::size_t n = p.n_real, n_all = p.size_with_ghosts();
    psi.resize(n_all);
    band.resize(n_all);
    for (std::size_t g = n; g < n_all; ++g) {
      const std::size_t src = p.ghost_source[g - n];
      psi[g] = boundary::mirror_signs<D>(boundary::mirror_flips(p, box, g)).cwiseProduct(psi[src]);
      band[g] = band[src];
    }
  }

  std::vector<double> V_, pair_w_;
  std::array<std::vector<double>, D> rhs_;
  std::vector<std::uint8_t> ghost_flips_, grow_;
  std::vector<std::int32_t> band_index_, piece_;
  std::vector<std::size_t> row_;
  std::vector<std::uint32_t> col_;
  std::array<std::vector<double>, D> coef_;
  std::vector<std::uint32_t> members_;
  std::vector<std::uint32_t> halo_members_;  ///< on many ranks: the band's halos, numbered after members_
  std::vector<double> piece_names_;          ///< on many ranks: each piece's name (its least identity)
};

}  // namespace rsph::physics
