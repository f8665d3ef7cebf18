#pragma once
// What a remap is told (its parameters), what it carries from old cells to new ones, and what it reports (its
// statistics), in every dimension.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
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
  /// The remap sums densely over the grid of lattice cells the particles span while it holds at most this many
  /// cells per old particle, sparsely (only the cells that receive something) beyond: a disk in a large box or a
  /// particle far out on an open axis costs memory in proportion to the particles, not to the box.
  double dense_cells_per_particle = 8.0;

  void validate() const {
    require(h_over_dx > 0.0, "regularization: h/Delta must be positive (got " + std::to_string(h_over_dx) + ")");
    require(min_fill >= 0.0 && min_fill < 1.0, "regularization: min_fill must lie in [0, 1)");
    require(closing_radius_in_h > 0.0, "regularization: the closing radius must be positive");
    require(min_mass_ratio >= 0.0 && min_mass_ratio < 1.0, "regularization: min_mass_ratio must lie in [0, 1)");
    require(dense_cells_per_particle >= 0.0, "regularization: dense_cells_per_particle must not be negative");
  }
};

/// A remap of one rank's part of a decomposed set (mpi/decomposition.hpp): the old particles whose cells it
/// builds (ascending; empty: every one), and the largest of a value over every rank (the heaviest new cell, which
/// min_mass_ratio scales, must be the whole set's). Empty in one process: the whole set, nothing to reduce.
/// A lattice that reads the whole set (a multi-level lattice's levels, the rings' phases) also takes
/// `sum_over_ranks` and `own`.
struct RankPart {
  std::span<const std::uint32_t> cells;
  std::function<double(double)> max_over_ranks;
  /// Element-wise sums over the ranks, in place (MPI's order; exact where one rank holds each value).
  std::function<void(std::span<double>)> sum_over_ranks;
  /// How many of the local set's first particles are this rank's own (the others are other ranks' out to the
  /// remap's reach): a sum over the whole set adds only these on each rank. Every one in one process.
  std::size_t own = std::numeric_limits<std::size_t>::max();
  /// The remap by owners (either order, every lattice that runs on ranks): each rank built the cells of its
  /// own particles only, and completes the sums of the new cells it keeps with the others' parts
  /// (owner_sums.hpp). `owner_of` names the rank that keeps each point (D coordinates after another), set for
  /// every remap on many ranks (regularize/remap_on_ranks.hpp). `exchange`, on many ranks, sends list q to rank q and
  /// returns what every rank sent here in rank order (with the count from each, when asked for).
  std::function<std::vector<int>(std::span<const double>)> owner_of;
  std::function<std::vector<double>(const std::vector<std::vector<double>>&, std::vector<int>*)> exchange;
  /// The remap by owners: whether the ball of a radius about a point (D coordinates) lies where the local set
  /// holds every particle of the run, so that an old cell reaching half as far is complete here. `owner_of` gives
  /// -1 for a point whose nearest particle it cannot tell for the same reason. Absent: everywhere.
  std::function<bool(std::span<const double>, double)> encloses;
  /// The second-order remap by owners: a per-particle value, `width` numbers per particle of the local set in its
  /// order, replaced on the other ranks' particles (after the first `own`) by what their owners hold (the old
  /// cells' geometry and fits that the neighbours' gradients read).
  std::function<void(std::vector<double>&, std::size_t)> refresh;
  int rank = 0, ranks = 1;

  double max(double v) const { return max_over_ranks ? max_over_ranks(v) : v; }
  double min(double v) const { return max_over_ranks ? -max_over_ranks(-v) : v; }
  /// Whether the remap is one rank's part of a decomposed set.
  bool on_ranks() const { return static_cast<bool>(max_over_ranks); }
  /// Whether every old cell was built by its owner alone, so that the new cells' sums must be completed.
  bool by_owners() const { return static_cast<bool>(owner_of); }
};

/// What a remap carries into one new cell: mass (eq. 6), momentum (eq. 8), total energy m (e + v^2/2) (eq. 9
/// plus the kinetic energy, so that total energy is conserved) and the volume of the old cells that cover it.
template <int D>
struct Conserved {
  double m = 0.0;
  Vec<D> mv = Vec<D>::Zero();
  double E = 0.0;
  double volume = 0.0;

  Conserved& operator+=(const Conserved& o) {
    m += o.m;
    mv += o.mv;
    E += o.E;
    volume += o.volume;
    return *this;
  }
};

/// What one regularization did.
struct RemapStats {
  std::size_t n_before = 0, n_after = 0;
  double kinetic_converted = 0.0;    ///< kinetic energy turned into heat (or dissipated, without u)
  double max_volume_mismatch = 0.0;  ///< max over old cells of |sum_n Omega_n^o - V_o| / V_o
  std::size_t dropped_cells = 0;     ///< nearly empty new cells whose share was handed on
  /// New particles per resolution level (one entry on a uniform lattice).
  std::vector<std::size_t> per_level;
  /// Multi-level lattices: blocks whose criterion asked for more than the finest level, and the level asked.
  std::size_t capped_blocks = 0;
  int requested_level = 0;
  /// Second-order remap: old cells handed out at first order because a new particle they feed would have
  /// fallen below the thermal floor, and the passes over the overlaps that took (1 when none fell).
  std::size_t first_order_cells = 0;
  int passes = 1;
  /// Second-order remap: old cells whose gradient the limiter cut (phi < 1 for rho, a velocity component or e).
  std::size_t limited_cells = 0;
  /// Multi-level lattices: the cells of the finest grid the remap summed on, over the ranks each rank's part (a
  /// diagnostic of memory, not logged).
  std::size_t summed_cells = 0;

  /// Calls f(name, &RemapStats::field) for every scalar figure, in one fixed order: what a log saves, restores
  /// and totals iterates (per_level, a list, is left to its owners).
  template <class F>
  static void for_each_figure(F&& f) {
    f("n_before", &RemapStats::n_before);
    f("n_after", &RemapStats::n_after);
    f("kinetic_converted", &RemapStats::kinetic_converted);
    f("max_volume_mismatch", &RemapStats::max_volume_mismatch);
    f("dropped_cells", &RemapStats::dropped_cells);
    f("capped_blocks", &RemapStats::capped_blocks);
    f("requested_level", &RemapStats::requested_level);
    f("first_order_cells", &RemapStats::first_order_cells);
    f("passes", &RemapStats::passes);
    f("limited_cells", &RemapStats::limited_cells);
  }
};

/// One remap's figures over every rank's part of it, on every rank: the counts (the blocks capped among them, each
/// counted by one rank) and the kinetic energy converted summed; the worst volume mismatch, the level asked and the
/// passes, their largest. In one process, `s` itself.
inline RemapStats over_ranks(RemapStats s, const RankPart& part) {
  if (!part.on_ranks()) return s;
  std::vector<double> sums{static_cast<double>(s.n_before),
                           static_cast<double>(s.n_after),
                           s.kinetic_converted,
                           static_cast<double>(s.dropped_cells),
                           static_cast<double>(s.first_order_cells),
                           static_cast<double>(s.limited_cells),
                           static_cast<double>(s.summed_cells),
                           static_cast<double>(s.capped_blocks)};
  for (const std::size_t n : s.per_level) sums.push_back(static_cast<double>(n));  // alike in length on every rank
  part.sum_over_ranks(sums);
  auto count = [&](std::size_t k) { return static_cast<std::size_t>(sums[k]); };  // exact below 2^53
  s.n_before = count(0);
  s.n_after = count(1);
  s.kinetic_converted = sums[2];
  s.dropped_cells = count(3);
  s.first_order_cells = count(4);
  s.limited_cells = count(5);
  s.summed_cells = count(6);
  s.capped_blocks = count(7);
  for (std::size_t l = 0; l < s.per_level.size(); ++l) s.per_level[l] = count(8 + l);
  s.max_volume_mismatch = part.max(s.max_volume_mismatch);
  s.requested_level = static_cast<int>(part.max(s.requested_level));
  s.passes = static_cast<int>(part.max(s.passes));
  return s;
}

/// The sum of one figure over a log of records holding RemapStats as `stats`.
template <class Log, class T>
T total(const Log& log, T RemapStats::*figure) {
  T sum{};
  for (const auto& r : log) sum += r.stats.*figure;
  return sum;
}

}  // namespace rsph::regularize
