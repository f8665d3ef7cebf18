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
#include <vector>

namespace rsph::physics {

/// The state of the consistent-gradient solve a simulation keeps between force passes.
template <int D>
class ConsistentGradientWorkspace {
 public:
  std::vector<Vec<D>> psi;         ///< per point (real and ghosts)
  std::vector<std::uint8_t> band;  ///< per point: whether its pairs use the corrected gradient
  CgResult last;                   ///< the last solve, summed over axes
  std::uint64_t solves = 0, iterations = 0;

  /// Saves or restores what the next pass reads: psi (its warm start, or kept) and the band, and the counts.
  template <class Archive>
  void checkpoint(Archive& ar) {
    const auto scope = ar.scope("consistent_gradient");
    ar("psi", psi);
    ar("band", band);
    ar("solves", solves);
    ar("iterations", iterations);
    ar("last_iterations", last.iterations);
    ar("last_residual", last.relative_residual);
    ar("last_converged", last.converged);
  }

  /// New particles (after a remap): the next pass solves afresh.
  void reset() { psi.clear(); }

  /// psi and the band for the current neighbour lists: solved when fresh or term.every_step, else kept;
  /// then mirrored onto the ghosts.
  template <class Kernel, class P>
  void update(const ConsistentGradient& term, const P& p, const Box<D>& box, const neighbors::NeighborList& nl) {
    const std::size_t n = p.n_real;
    const bool fresh = psi.size() < n;
    if (fresh || term.every_step) {
      find_band(term, p, nl);
      std::vector<Vec<D>> psi_old;
      if (!fresh) psi_old.assign(psi.begin(), psi.begin() + static_cast<std::ptrdiff_t>(n));
      psi.assign(p.size_with_ghosts(), Vec<D>::Zero());
      last = CgResult{};
      last.converged = true;
      if (!members_.empty()) {
        pair_weights_and_rhs<Kernel>(p, box, nl);
        const auto anchored = connected_pieces(n, nl, p.ghost_source);
        const auto diagonal = assemble(n, nl, p.ghost_source);
        for (int axis = 0; axis < D; ++axis) solve_axis(term, axis, diagonal, anchored, fresh ? nullptr : &psi_old);
      }
      ++solves;
      iterations += static_cast<std::uint64_t>(last.iterations);
    }
    mirror_onto_ghosts(p, box);
  }

 private:
  using Anchors = std::vector<std::array<bool, D>>;
  using Diagonal = std::array<std::vector<double>, D>;

  static std::size_t source_of(std::uint32_t b, std::size_t n, const std::vector<std::uint32_t>& ghost_source) {
    return b < n ? b : ghost_source[b - n];
  }

  /// The particles with a neighbour of another h, grown by term.band_layers neighbour layers, and each
  /// member's index in the band.
  template <class P>
  void find_band(const ConsistentGradient& term, const P& p, const neighbors::NeighborList& nl) {
    const std::size_t n = p.n_real;
    band.assign(p.size_with_ghosts(), 0);
    for (std::size_t a = 0; a < n; ++a)
      for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k)
        if (std::abs(p.h[nl.index[k]] - p.h[a]) > 1e-12 * p.h[a]) {
          band[a] = 1;
          break;
        }
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
    }
    band_index_.assign(n, -1);
    members_.clear();
    for (std::size_t a = 0; a < n; ++a)
      if (band[a]) {
        band_index_[a] = static_cast<std::int32_t>(members_.size());
        members_.push_back(static_cast<std::uint32_t>(a));
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
  void solve_axis(const ConsistentGradient& term, int axis, const Diagonal& diagonal, const Anchors& anchored,
                  const std::vector<Vec<D>>* psi_old) {
    const std::size_t m = members_.size();
    const auto ax = static_cast<std::size_t>(axis);
    const auto& diag = diagonal[ax];
    const auto& coef = coef_[ax];
    auto apply = [&](const std::vector<double>& in, std::vector<double>& out) {
      out.resize(m);
#pragma omp parallel for schedule(static) if (m >= kParallelMin)
      for (std::size_t i = 0; i < m; ++i) {
        double off = 0.0;
        for (std::size_t e = row_[i]; e < row_[i + 1]; ++e) off += coef[e] * in[col_[e]];
        out[i] = diag[i] * in[i] - off;
      }
    };
    auto& rhs = rhs_[ax];
    std::vector<double> mean(anchored.size(), 0.0), count(anchored.size(), 0.0);
    for (std::size_t i = 0; i < m; ++i) {
      mean[static_cast<std::size_t>(piece_[i])] += rhs[i];
      count[static_cast<std::size_t>(piece_[i])] += 1.0;
    }
    for (std::size_t i = 0; i < m; ++i) {
      const auto c = static_cast<std::size_t>(piece_[i]);
      if (!anchored[c][ax]) rhs[i] -= mean[c] / count[c];
    }
    std::vector<double> component(m);
    for (std::size_t i = 0; i < m; ++i) component[i] = psi_old ? (*psi_old)[members_[i]][axis] : 0.0;
    const CgResult res = conjugate_gradient(apply, diag, rhs, component, term.tolerance, term.max_iterations);
    last.iterations += res.iterations;
    last.relative_residual = std::max(last.relative_residual, res.relative_residual);
    last.converged = last.converged && res.converged;
    for (std::size_t i = 0; i < m; ++i) psi[members_[i]][axis] = component[i];
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
};

}  // namespace rsph::physics
