#pragma once
// Resolution criteria of a multi-level lattice: at every regularization each block is given a level
// from the remapped fields on its level-0 cells. One concept, RefinementCriterion, and the criteria
// scenes pick from: a geometric region, a density jump, a target mass per particle, and the finest of
// several.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/regularize/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

namespace rsph::refine {

/// What criteria see: the blocks of the lattice and, on its level-0 cells (spacing Delta_0), the mass
/// and the covered volume the remap put there. Blocks are numbered x fastest; each spans
/// `cells_per_block` level-0 cells per axis. On many ranks a rank sees a window of the blocks, whose first
/// lies `first_block` blocks past the whole set's first, at `origin`.
template <int D>
struct BlockField {
  Vec<D> origin;                              ///< lower corner of the whole set's first block
  std::array<std::int64_t, D> first_block{};  ///< this field's first block, counted from the whole set's first
  double spacing = 0.0;                       ///< Delta_0
  std::int64_t cells_per_block = 1;           ///< level-0 cells per block and axis
  std::array<std::int64_t, D> blocks{};       ///< blocks per axis
  std::array<std::int64_t, D> periods{};      ///< blocks per periodic axis (0: not periodic)
  std::vector<double> mass, volume;           ///< per level-0 cell, x fastest

  std::size_t n_blocks() const {
    std::size_t n = 1;
    for (auto b : blocks) n *= static_cast<std::size_t>(b);
    return n;
  }
  double block_size() const { return spacing * static_cast<double>(cells_per_block); }
  std::array<std::int64_t, D> block_index(std::size_t b) const {
    std::array<std::int64_t, D> idx;
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      idx[k] = static_cast<std::int64_t>(b % static_cast<std::size_t>(blocks[k]));
      b /= static_cast<std::size_t>(blocks[k]);
    }
    return idx;
  }
  Vec<D> block_lo(std::size_t b) const {
    const auto idx = block_index(b);
    Vec<D> lo;
    for (int k = 0; k < D; ++k)
      lo[k] =
          origin[k] + static_cast<double>(idx[static_cast<std::size_t>(k)] + first_block[static_cast<std::size_t>(k)]) *
                          block_size();
    return lo;
  }
  Vec<D> block_hi(std::size_t b) const { return block_lo(b) + Vec<D>::Constant(block_size()); }

  /// Flat index of level-0 cell idx (wrapping periodic axes), -1 outside.
  std::int64_t cell(std::array<std::int64_t, D> idx) const {
    std::int64_t f = 0;
    for (int k = D - 1; k >= 0; --k) {
      const auto kk = static_cast<std::size_t>(k);
      const std::int64_t n = blocks[kk] * cells_per_block;
      std::int64_t i = idx[kk];
      if (periods[kk] > 0) i = ((i % n) + n) % n;
      if (i < 0 || i >= n) return -1;
      f = f * n + i;
    }
    return f;
  }
  double density(std::int64_t c) const {
    const auto cc = static_cast<std::size_t>(c);
    return volume[cc] > 0.0 ? mass[cc] / volume[cc] : 0.0;
  }

  /// Mean density of block b: its mass over its covered volume (0 when empty).
  double block_density(std::size_t b) const {
    double m = 0.0, V = 0.0;
    for_each_cell(b, 0, [&](std::int64_t c) {
      m += mass[static_cast<std::size_t>(c)];
      V += volume[static_cast<std::size_t>(c)];
    });
    return V > 0.0 ? m / V : 0.0;
  }

  /// Largest |rho_i - rho_j| / min(rho_i, rho_j) between face-adjacent level-0 cells of block b and its
  /// one-cell halo, over cells covered at least half (partly covered edge cells would fake jumps).
  double max_relative_jump(std::size_t b) const {
    double jump = 0.0;
    const double cell_volume = std::pow(spacing, D);
    for_each_cell(b, 1, [&](std::int64_t c) {
      if (volume[static_cast<std::size_t>(c)] < 0.5 * cell_volume) return;
      const double rc = density(c);
      auto idx = cell_index(c);
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
        auto nb = idx;
        ++nb[k];
        const std::int64_t n = cell(nb);
        if (n < 0 || volume[static_cast<std::size_t>(n)] < 0.5 * cell_volume) continue;
        const double rn = density(n);
        const double lo = std::min(rc, rn);
        if (lo > 0.0) jump = std::max(jump, std::abs(rc - rn) / lo);
      }
    });
    return jump;
  }

  /// Calls f(c) for the level-0 cells of block b grown by `halo` cells per side (those inside the grid).
  template <class F>
  void for_each_cell(std::size_t b, std::int64_t halo, F&& f) const {
    const auto bi = block_index(b);
    std::array<std::int64_t, D> off;
    off.fill(-halo);
    const std::int64_t span = cells_per_block + halo;
    for (;;) {
      std::array<std::int64_t, D> idx;
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) idx[k] = bi[k] * cells_per_block + off[k];
      const std::int64_t c = cell(idx);
      if (c >= 0) f(c);
      std::size_t k = 0;
      for (; k < static_cast<std::size_t>(D); ++k) {
        if (++off[k] < span) break;
        off[k] = -halo;
      }
      if (k == static_cast<std::size_t>(D)) break;
    }
  }

 private:
  std::array<std::int64_t, D> cell_index(std::int64_t c) const {
    std::array<std::int64_t, D> idx;
    auto f = static_cast<std::size_t>(c);
    for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) {
      const auto n = static_cast<std::size_t>(blocks[k] * cells_per_block);
      idx[k] = static_cast<std::int64_t>(f % n);
      f /= n;
    }
    return idx;
  }
};

/// No level known yet (the first regularization): criteria apply no hysteresis.
inline constexpr int no_previous_level = -1;

/// A resolution criterion: the level block b wants, given the level it had (or no_previous_level).
/// Levels above the lattice's finest are capped by the lattice, which reports it.
template <class C, int D>
concept RefinementCriterion = requires(const C& c, const BlockField<D>& field, std::size_t b, int previous) {
  { c.level(field, b, previous) } -> std::convertible_to<int>;
};

template <class C, int D>
constexpr bool check_criterion() {
  static_assert(RefinementCriterion<C, D>,
                "a refinement criterion needs `int level(const refine::BlockField<D>&, std::size_t block, int "
                "previous_level) const`: the level a block should have");
  return true;
}

/// Level `inside_level` wherever the region meets the block, 0 elsewhere; `meets(lo, hi)` tests a block's box.
template <int D, class Meets>
struct Region {
  Meets meets;
  int inside_level = 1;
  int level(const BlockField<D>& f, std::size_t b, int) const {
    return meets(f.block_lo(b), f.block_hi(b)) ? inside_level : 0;
  }
};
template <int D, class Meets>
Region<D, Meets> region(Meets meets, int level) {
  return {std::move(meets), level};
}

/// Refines to `front_level` where the density jumps between neighbouring level-0 cells by more than
/// refine_above (relative), returns to 0 below coarsen_below and keeps the old level in between, so
/// blocks at the edge of a front do not flicker.
struct DensityJump {
  double refine_above = 0.5;
  double coarsen_below = 0.25;
  int front_level = 1;
  void validate() const {
    require(refine_above > 0.0 && coarsen_below >= 0.0 && coarsen_below <= refine_above,
            "density-jump criterion: need 0 <= coarsen_below <= refine_above and refine_above > 0");
  }
  template <int D>
  int level(const BlockField<D>& f, std::size_t b, int previous) const {
    const double jump = f.max_relative_jump(b);
    if (jump > refine_above) return front_level;
    if (jump < coarsen_below || previous == no_previous_level) return 0;
    return std::min(previous, front_level);
  }
};

/// Resolution following the mass, as plain SPH does: the coarsest level whose particle mass
/// rho Delta_l^D stays at or below `mass`. With `hysteresis` eta a block keeps its level while the
/// particle mass there lies within (mass 2^-D(1+eta), mass 2^(D eta)].
struct TargetMass {
  double mass = 1.0;
  double hysteresis = 0.25;
  void validate() const {
    require(mass > 0.0, "target-mass criterion: the mass per particle must be positive");
    require(hysteresis >= 0.0 && hysteresis < 0.5, "target-mass criterion: hysteresis must lie in [0, 0.5)");
  }
  template <int D>
  int level(const BlockField<D>& f, std::size_t b, int previous) const {
    const double rho = f.block_density(b);
    if (!(rho > 0.0)) return 0;
    // continuous level s: rho (Delta_0 / 2^s)^D = mass
    const double s = std::log2(rho * std::pow(f.spacing, D) / mass) / D;
    if (previous != no_previous_level && s > previous - 1 - hysteresis && s <= previous + hysteresis) return previous;
    return std::max(0, static_cast<int>(std::ceil(s - 1e-12)));
  }
};

/// The finest level any of the criteria asks for.
template <class... Criteria>
struct Finest {
  std::tuple<Criteria...> criteria;
  template <int D>
  int level(const BlockField<D>& f, std::size_t b, int previous) const {
    return std::apply(
        [&](const auto&... c) {
          return std::max({0, static_cast<int>(c.level(f, b, previous))...});
        },
        criteria);
  }
};
template <class... Criteria>
Finest<Criteria...> finest(Criteria... c) {
  return {std::tuple<Criteria...>{std::move(c)...}};
}

}  // namespace rsph::refine
