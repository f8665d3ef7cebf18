#pragma once
// The velocity-gradient passes: a viscous stress term's S / rho^2 of each particle (physics/shear_viscosity.hpp),
// ghosts mirrored, whose part of eq. (3) the force pass then sums; a viscosity switch's factor of each particle.
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/physics/shear_viscosity.hpp"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace rsph::physics::loops {

/// nabla_a W of a pair as the force sum uses it: at h_ab, or the mean of both h in grad-h SPH.
template <class S>
[[gnu::always_inline]] inline Vec<S::dim> pair_grad_W(const Vec<S::dim>& r_ab, double r, double h_a, double inv_h_a,
                                                      double h_b) {
  using Kernel = typename S::Kernel;
  constexpr int D = S::dim;
  if constexpr (S::grad_h)
    return 0.5 * (kernel::grad_W_inv_h<Kernel, D>(r_ab, r, inv_h_a) + kernel::grad_W<Kernel, D>(r_ab, r, h_b));
  else
    return kernel::grad_W_inv_h<Kernel, D>(r_ab, r, kernel::inv_h_ab(h_a, inv_h_a, h_b));
}

/// G_a = sum_b (m_b / rho_b) (v_b - v_a) (x) nabla_a W_ab of point a over its neighbour list (row a).
template <class S, class P>
Mat<S::dim> velocity_gradient(const P& p, const neighbors::NeighborList& nl, std::size_t a) {
  constexpr int D = S::dim;
  Mat<D> G = Mat<D>::Zero();
  const double h_a = p.h[a], inv_h_a = 1.0 / h_a;
  for (auto k = nl.offset[a]; k < nl.offset[a + 1]; ++k) {
    const std::uint32_t b = nl.index[k];
    const Vec<D> r_ab = p.x[a] - p.x[b];
    const double r = r_ab.norm();
    if (r <= 0.0) continue;
    if constexpr (S::grad_h)
      if (r >= S::Kernel::support * std::max(h_a, p.h[b])) continue;
    G += physics::velocity_gradient_term<D>(p.m[b], p.rho[b], p.v[a] - p.v[b],
                                            pair_grad_W<S>(r_ab, r, h_a, inv_h_a, p.h[b]));
  }
  return G;
}

/// S / rho^2 of every real particle from `term`'s stress of the velocity gradient, over current neighbour lists
/// and densities, sized for the ghosts too, which stress_images then fills.
template <class S, class P, class Term>
void stress_over_rho2(const P& p, const neighbors::NeighborList& nl, const Term& term,
                      std::vector<Mat<S::dim>>& S_over_rho2) {
  const std::size_t n = p.n_real;
  S_over_rho2.resize(p.size_with_ghosts());
#pragma omp parallel for schedule(dynamic, kRowChunk) if (n >= kParallelMin)
  for (std::size_t a = 0; a < n; ++a) {
    const double rho = p.rho[a];
    S_over_rho2[a] = term.stress(velocity_gradient<S>(p, nl, a), rho) / (rho * rho);
  }
}

/// A viscosity switch's factor of every real particle from its velocity gradient (physics/viscosity_switch.hpp),
/// sized for the ghosts too, which scalar_images then fills.
template <class S, class P, class Term>
void switch_factors(const P& p, const neighbors::NeighborList& nl, const Term& term, std::vector<double>& factor) {
  const std::size_t n = p.n_real;
  factor.resize(p.size_with_ghosts());
#pragma omp parallel for schedule(dynamic, kRowChunk) if (n >= kParallelMin)
  for (std::size_t a = 0; a < n; ++a)
    factor[a] = term.template switch_factor<S::dim>(velocity_gradient<S>(p, nl, a), p.cs[a], p.h[a]);
}

/// The ghosts' values of a per-point scalar that mirrors do not change: their sources' (on many ranks after the
/// halos' came from their owners). `field` is resized to the points with ghosts.
template <class P>
void scalar_images(const P& p, std::vector<double>& field) {
  const std::size_t n = p.n_real;
  field.resize(p.size_with_ghosts());
  for (std::size_t g = n; g < p.size_with_ghosts(); ++g) field[g] = field[p.ghost_source[g - n]];
}

/// The ghosts' S / rho^2 from their sources' (on many ranks after the halos' came from their owners, the
/// sources of images made of them): a mirror ghost sees the stress reflected, S' = M S M.
template <class P, int D>
void stress_images(const P& p, const Box<D>& box, std::vector<Mat<D>>& S_over_rho2) {
  const std::size_t n = p.n_real;
  for (std::size_t g = n; g < p.size_with_ghosts(); ++g) {
    const Vec<D> sign = boundary::mirror_signs<D>(boundary::mirror_flips(p, box, g));
    S_over_rho2[g] = sign.asDiagonal() * S_over_rho2[p.ghost_source[g - n]] * sign.asDiagonal();
  }
}

}  // namespace rsph::physics::loops
