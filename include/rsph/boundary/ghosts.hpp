#pragma once
// Periodic images and mirror ghosts, appended at the tail of the particle arrays.
#include "rsph/core/dimension.hpp"
#include "rsph/core/particle_set.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace rsph::boundary {

/// Rebuilds the ghosts of `p` for every periodic or reflecting axis of `box`: a particle within
/// `width` of a face gets a periodic image beyond the opposite face, or a mirror image (normal velocity
/// reversed) beyond its own face. Axes are processed in turn over real and earlier ghosts, so corners
/// are covered. Ghosts copy their source's fields; refresh_ghosts updates them after a density sum.
template <int D, bool E>
void make_ghosts(ParticleSet<D, E>& p, const Box<D>& box, double width);

/// The images of make_ghosts, of every point already there (real particles, and ghosts another source put
/// there before, such as particles of other ranks), appended after them.
template <int D, bool E>
void add_images(ParticleSet<D, E>& p, const Box<D>& box, double width) {
  for (int k = 0; k < D; ++k) {
    if (box.edge[k] == Edge::open) continue;
    const double lo = box.lo[k], hi = box.hi[k], L = hi - lo;
    const std::size_t n = p.size_with_ghosts();
    if (box.edge[k] == Edge::periodic) {
      // a layer wider than the box needs images from several periods
      const int reach = static_cast<int>(std::ceil(width / L));
      for (std::size_t i = 0; i < n; ++i)
        for (int shift = -reach; shift <= reach; ++shift) {
          if (shift == 0) continue;
          Vec<D> g = p.x[i];
          g[k] += shift * L;
          if (g[k] >= lo - width && g[k] <= hi + width) p.add_ghost(i, g, Vec<D>(p.v[i]));
        }
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Vec<D> xi = p.x[i];
      const Vec<D> vi = p.v[i];
      Vec<D> g = xi, w = vi;
      w[k] = -vi[k];
      if (xi[k] < lo + width) {
        g[k] = 2.0 * lo - xi[k];
        p.add_ghost(i, g, w);
      }
      if (xi[k] > hi - width) {
        g[k] = 2.0 * hi - xi[k];
        p.add_ghost(i, g, w);
      }
    }
  }
}

template <int D, bool E>
void make_ghosts(ParticleSet<D, E>& p, const Box<D>& box, double width) {
  p.clear_ghosts();
  add_images(p, box, width);
}

/// Copies the scalar fields a density sum changed from each ghost's real particle.
template <int D, bool E>
void refresh_ghosts(ParticleSet<D, E>& p) {
  const std::size_t n_real = p.n_real;
  for (std::size_t g = n_real; g < p.size_with_ghosts(); ++g) {
    const std::size_t s = p.ghost_source[g - n_real];
    p.rho[g] = p.rho[s];
    p.P[g] = p.P[s];
    p.cs[g] = p.cs[s];
    p.h[g] = p.h[s];
    if constexpr (E) p.u[g] = p.u[s];
  }
}

/// The axes that ghost g (an index past n_real) mirrors at a reflecting wall, as bits (bit k: axis k).
/// A mirrored vector field flips those components, a mirrored tensor S becomes M S M, M = diag(+-1).
template <int D, bool E>
std::uint8_t mirror_flips(const ParticleSet<D, E>& p, const Box<D>& box, std::size_t g) {
  const std::size_t src = p.ghost_source[g - p.n_real];
  std::uint8_t flips = 0;
  for (int k = 0; k < D; ++k)
    if (box.edge[k] == Edge::reflecting && p.x[g][k] != p.x[src][k]) flips |= std::uint8_t(1u << k);
  return flips;
}

/// M = diag(+-1) of a mirror: -1 on the axes of `flips` (mirror_flips), +1 on the others.
template <int D>
Vec<D> mirror_signs(std::uint8_t flips) {
  Vec<D> sign = Vec<D>::Ones();
  for (int k = 0; k < D; ++k)
    if (flips & (1u << k)) sign[k] = -1.0;
  return sign;
}

}  // namespace rsph::boundary
