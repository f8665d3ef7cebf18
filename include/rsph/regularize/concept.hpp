#pragma once
// The regularization policy axis: the one thing that tells RSPH from SPH.
#include "rsph/core/dimension.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/regularize/remap_params.hpp"

#include <concepts>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace rsph {

/// What a schedule may look at when deciding whether to regularize.
struct StepInfo {
  std::uint64_t step = 0;              ///< steps taken so far
  double time = 0.0;                   ///< simulated time
  std::uint64_t steps_since_last = 0;  ///< steps since the last regularization (or the start)
  double time_since_last = 0.0;
  const neighbors::NeighborList* neighbors = nullptr;  ///< current neighbour lists of the real particles
  /// n_a = sum_{b != a} W_ab (eq. A1 of the paper) per real particle from the density pass, when the
  /// regularizer asks for it (`static constexpr bool wants_number_density`) and h is fixed; empty otherwise.
  std::span<const double> number_density;
  /// W_ab of each entry of `neighbors` as the density pass summed it, given with number_density (empty
  /// when that pass covered only some particles); so a schedule's pair sums need no distances of their own.
  std::span<const double> pair_kernel;
  /// On many ranks (mpi/decomposition.hpp): fills a per-point field's halo entries from the ranks that own them,
  /// given the field on the real particles and sized for every point; empty in one process.
  std::function<void(std::vector<double>&)> refresh_halos;
  /// On many ranks: the old particles (ascending) whose cells the remap builds, this rank's own and the other
  /// ranks' near them (the cells farther out, open where the halo ends, would only feed sites another rank
  /// keeps), and the reduction over ranks the hand-on of light cells needs. Empty in one process.
  regularize::RankPart part;
};

/// A regularizer decides when (`due`) and remaps the particles onto a new set (`remap`) conserving
/// mass, momentum and total energy. `remap` is handed the step it acts after and returns the kinetic
/// energy it removed.
template <class R, int D, bool E>
concept Regularizer = requires(R& r, ParticleSet<D, E>& p, const Box<D>& box, const StepInfo& s) {
  { r.due(p, box, s) } -> std::same_as<bool>;
  { r.remap(p, box, s) } -> std::convertible_to<double>;
};

template <class R, int D, bool E>
constexpr bool check_regularizer() {
  static_assert(
      requires(R & r, ParticleSet<D, E> & p, const Box<D>& box, const StepInfo& s) {
        { r.due(p, box, s) } -> std::same_as<bool>;
      },
      "a regularizer needs `bool due(const ParticleSet<D, E>&, const Box<D>&, const StepInfo&)`: when to remap");
  static_assert(
      requires(R & r, ParticleSet<D, E> & p, const Box<D>& box, const StepInfo& s) {
        { r.remap(p, box, s) } -> std::convertible_to<double>;
      },
      "a regularizer needs `double remap(ParticleSet<D, E>&, const Box<D>&, const StepInfo&)`: the remap after "
      "that step, returning the kinetic energy removed");
  return true;
}

/// When a lattice regularizer remaps: `due` after each step (or block of steps); a schedule may also
/// offer `double time_until_due(const StepInfo&) const`, and the step before is shortened to land on it.
template <class S, class P, class B>
concept Schedule = requires(S& s, const P& p, const B& box, const StepInfo& info) {
  { s.due(p, box, info) } -> std::same_as<bool>;
};

template <class S, class P, class B>
constexpr bool check_schedule() {
  static_assert(Schedule<S, P, B>,
                "a regularization schedule needs `bool due(const ParticleSet<D, E>&, const Box<D>&, const StepInfo&)`: "
                "whether to remap after this step");
  return true;
}

namespace regularize {

/// Whether regularizer R runs on many ranks (mpi/decomposition.hpp): one whose new lattice every rank can lay out
/// alike (from the box, or from figures reduced over the ranks) and whose remap builds each old cell once, on its
/// particle's rank, completing the new cells' sums with the other ranks' parts (`remaps_on_ranks`;
/// regularize/remap_on_ranks.hpp).
template <class R>
constexpr bool remaps_on_ranks() {
  if constexpr (requires { R::remaps_on_ranks; })
    return R::remaps_on_ranks;
  else
    return false;
}

/// Plain SPH: never regularize.
struct None {
  static constexpr bool remaps_on_ranks = true;
  template <class P, class B>
  bool due(const P&, const B&, const StepInfo&) const {
    return false;
  }
  template <class P, class B>
  double remap(P&, const B&, const StepInfo&) {
    return 0.0;
  }
};

}  // namespace regularize
}  // namespace rsph
