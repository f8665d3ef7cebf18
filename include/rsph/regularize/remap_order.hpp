#pragma once
// The remap's order, one policy axis of the lattice regularizer: the paper's piecewise-constant hand-out
// (eqs. 6-9) or the limited linear reconstruction of second_order/remap_second.hpp. Both conserve mass,
// momentum and total energy exactly; the second moves less across cells that the flow does not mix. Each
// order owns its remap, the scratch it keeps between remaps, and the figures it reports.
#include "rsph/regularize/second_order/remap_second_levels.hpp"

#include <concepts>
#include <cstddef>

namespace rsph::regularize {

/// Eqs. (6)-(9): every old cell hands out its mean, in proportion to overlap volume.
struct FirstOrder {
  static constexpr const char* name = "first";
  /// Averaging velocities only turns kinetic energy into heat, never the reverse.
  static constexpr bool heats_only = true;
  /// Nothing kept beyond the remap's common workspace.
  template <int D>
  struct Workspace {};

  template <class Lattice, class Builder, int D, bool E, class Region>
  RemapStats remap(ParticleSet<D, E>& p, const Box<D>& box, Lattice& lattice, Builder& builder,
                   const RemapParams& params, const Region& region, RemapWorkspace<D>& ws, Workspace<D>&,
                   const RankPart& part = {}) const {
    return remap_onto_lattice(p, box, lattice, builder, params, region, &ws, part);
  }
  /// Figures of a run's remaps beyond the common ones: none.
  template <class Log, class Set>
  static void figures(const Log&, Set&&) {}
};

/// Every old cell hands out its linear reconstruction, limited to the range of its neighbourhood.
struct SecondOrder {
  static constexpr const char* name = "second";
  /// The pieces carry velocity differences the old means do not: heat may turn into kinetic energy too.
  static constexpr bool heats_only = false;
  template <int D>
  using Workspace = second_order::Workspace<D>;
  SecondOrderParams params;

  void validate() const { params.validate(); }
  template <class Lattice, class Builder, int D, bool E, class Region>
  RemapStats remap(ParticleSet<D, E>& p, const Box<D>& box, Lattice& lattice, Builder& builder,
                   const RemapParams& remap_params, const Region& region, RemapWorkspace<D>& ws, Workspace<D>& w2,
                   const RankPart& part = {}) const {
    return remap_second_order(p, box, lattice, builder, remap_params, params, region, &ws, &w2, part);
  }
  /// How often the limiter cut a gradient, how many old cells the thermal floor sent back to first order, and
  /// in how many remaps: set(name, value) for each.
  template <class Log, class Set>
  static void figures(const Log& log, Set&& set) {
    std::size_t refilled = 0;
    for (const auto& r : log) refilled += r.stats.passes > 1;
    set("remap_limited_cells", total(log, &RemapStats::limited_cells));
    set("remap_first_order_cells", total(log, &RemapStats::first_order_cells));
    set("remaps_refilled_at_first_order", refilled);
  }
};

template <class R>
concept RemapOrder = requires {
  { R::name } -> std::convertible_to<const char*>;
  { R::heats_only } -> std::convertible_to<bool>;
  typename R::template Workspace<2>;
};

template <class R>
constexpr bool check_remap_order() {
  static_assert(RemapOrder<R>,
                "a remap order needs `static constexpr const char* name`, `static constexpr bool heats_only`, "
                "`template <int D> Workspace` (what it keeps between remaps) and `RemapStats remap(p, box, lattice, "
                "builder, params, region, workspace, order_workspace)`, as regularize::FirstOrder and "
                "regularize::SecondOrder have");
  return true;
}

}  // namespace rsph::regularize
