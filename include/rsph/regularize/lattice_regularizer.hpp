#pragma once
// The RSPH regularizer: a lattice, a schedule and a Voronoi cell builder; remaps with eqs. (6)-(9).
#include "rsph/core/particle_set.hpp"
#include "rsph/geometry/cell_builder.hpp"
#include "rsph/regularize/concept.hpp"
#include "rsph/regularize/lattice.hpp"
#include "rsph/regularize/multilevel.hpp"
#include "rsph/regularize/remap.hpp"
#include "rsph/regularize/remap_order.hpp"
#include "rsph/regularize/schedule.hpp"

#include <chrono>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace rsph::regularize {

/// One line of the regularization log.
struct Record {
  std::uint64_t step = 0;
  double time = 0.0;
  RemapStats stats;
  double seconds = 0.0;
};

/// Saves or restores a regularization log through a checkpoint archive, one column per figure.
template <class Archive>
void checkpoint_log(Archive& ar, std::vector<Record>& log) {
  const auto scope = ar.scope("log");
  std::size_t n = log.size();
  ar("count", n);
  log.resize(n);
  // one column per figure of RemapStats, beside the record's own step, time and seconds
  auto column = [&](const char* name, auto get) {
    using T = std::decay_t<decltype(get(log.front()))>;
    std::vector<T> c(n);
    for (std::size_t k = 0; k < n; ++k) c[k] = get(log[k]);
    ar(name, c);
    require(c.size() == n, std::string("checkpoint: the regularization log's column ") + name + " is short");
    for (std::size_t k = 0; k < n; ++k) get(log[k]) = c[k];
  };
  column(
      "step", [](Record & r) -> auto& { return r.step; });
  column(
      "time", [](Record & r) -> auto& { return r.time; });
  column(
      "seconds", [](Record & r) -> auto& { return r.seconds; });
  RemapStats::for_each_figure([&](const char* name, auto figure) {
    column(
        name, [figure](Record & r) -> auto& { return r.stats.*figure; });
  });
  std::vector<std::size_t> levels, per_level;  // the per-level counts, flattened
  for (const auto& r : log) {
    levels.push_back(r.stats.per_level.size());
    per_level.insert(per_level.end(), r.stats.per_level.begin(), r.stats.per_level.end());
  }
  ar("levels", levels);
  ar("per_level", per_level);
  if (ar.saving()) return;
  require(levels.size() == n, "checkpoint: the regularization log's level counts are short");
  std::size_t at = 0;
  for (std::size_t k = 0; k < n; ++k) {
    require(at + levels[k] <= per_level.size(), "checkpoint: the regularization log's level counts are short");
    log[k].stats.per_level.assign(per_level.begin() + static_cast<std::ptrdiff_t>(at),
                                  per_level.begin() + static_cast<std::ptrdiff_t>(at + levels[k]));
    at += levels[k];
  }
}

/// A lattice regularizer's options besides its lattice and schedule, named where they are given:
/// `{.remap = {1.4}, .region = region::Annulus{0.4, 2.5}, .order = regularize::SecondOrder{}}`.
template <class Builder, class Region, class Order>
struct RegularizerOptions {
  RemapParams remap{};
  Builder builder{};
  Region region{};
  Order order{};
};

template <class Lattice, class Schedule, class Builder = typename geometry::DefaultCellBuilder<Lattice::dim>::type,
          class Region = region::Unbounded, class Order = FirstOrder>
class LatticeRegularizer {
  static_assert(check_lattice<Lattice>());
  static_assert(geometry::check_cell_builder<Builder, Lattice::dim>());
  static_assert(check_closing_region<Region, Lattice::dim>());
  static_assert(check_remap_order<Order>());

 public:
  /// The driver hands the schedule n_a of eq. (A1) from its density pass (StepInfo::number_density).
  static constexpr bool wants_number_density = requires { requires Schedule::wants_number_density; };
  /// One regular lattice fixed by the box runs on many ranks, and a lattice that says it does (the multi-level
  /// lattice, whose levels every rank chooses alike from the level-0 field the ranks complete together; the rings,
  /// whose phases are summed over the ranks). Either order builds each old cell once, on the rank that owns its
  /// particle, and sends the overlaps to the ranks that keep the new cells (owner_sums.hpp; the second order also
  /// the neighbours' geometry, the limiter's bounds and the thermal floor's cells; level_owners.hpp on levels).
  static constexpr bool remaps_on_ranks =
      (RegularLattice<Lattice, Lattice::dim> && !PerSiteLattice<Lattice>) || requires {
    requires Lattice::remaps_on_ranks;
  };

  using Options = RegularizerOptions<Builder, Region, Order>;

  explicit LatticeRegularizer(Lattice lattice, Schedule schedule, Options options = {})
      : lattice_(std::move(lattice)),
        schedule_(std::move(schedule)),
        params_(options.remap),
        builder_(std::move(options.builder)),
        region_(std::move(options.region)),
        order_(std::move(options.order)) {}

  void validate() const {
    params_.validate();
    if constexpr (requires { order_.validate(); }) order_.validate();
    if constexpr (requires { region_.validate(); }) region_.validate();
    require(lattice_.spacing > 0.0, "regularization: the lattice spacing Delta must be positive");
    if constexpr (requires { schedule_.validate(); }) schedule_.validate();
  }

  template <class P, class B>
  bool due(const P& p, const B& box, const StepInfo& s) {
    static_assert(check_schedule<Schedule, P, B>());
    return schedule_.due(p, box, s);
  }

  /// Time left before a time-based schedule fires (absent for step-based ones).
  double time_until_due(const StepInfo& s) const requires requires(const Schedule& sc) { sc.time_until_due(s); }
  { return schedule_.time_until_due(s); }

  template <int D, bool E>
  double remap(ParticleSet<D, E>& p, const Box<D>& box, const StepInfo& s) {
    const auto t0 = std::chrono::steady_clock::now();
    Record r;
    r.step = s.step;
    r.time = s.time;
    r.stats = over_ranks(
        order_.remap(p, box, lattice_, builder_, params_, region_, workspace_, order_workspace_, s.part), s.part);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    log_.push_back(r);
    return r.stats.kinetic_converted;
  }

  const std::vector<Record>& log() const { return log_; }

  /// Saves or restores what later regularizations read or report: the log, and a multi-level lattice's
  /// levels (its hysteresis). Schedules decide from the step's counters and fields alone.
  template <class Archive>
  void checkpoint(Archive& ar) {
    const auto scope = ar.scope("regularizer");
    checkpoint_log(ar, log_);
    if constexpr (requires { lattice_.checkpoint(ar); }) lattice_.checkpoint(ar);
  }
  const Lattice& lattice() const { return lattice_; }
  Schedule& schedule() { return schedule_; }
  const RemapParams& params() const { return params_; }
  /// "first" or "second": the remap's order, for the records a run writes.
  static constexpr const char* remap_order() { return Order::name; }
  /// The figures the remap's order reports over the run's remaps: set(name, value) for each.
  template <class Set>
  void order_figures(Set&& set) const {
    Order::figures(log_, set);
  }

 private:
  Lattice lattice_;
  Schedule schedule_;
  RemapParams params_;
  Builder builder_;
  Region region_;
  Order order_;
  RemapWorkspace<Lattice::dim> workspace_;
  [[no_unique_address]] typename Order::template Workspace<Lattice::dim> order_workspace_;
  std::vector<Record> log_;
};

}  // namespace rsph::regularize
