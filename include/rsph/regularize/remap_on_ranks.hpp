#pragma once
// The remap on many ranks, for a simulation whose scene names a domain decomposition (mpi/decomposition.hpp):
// what each rank gathers, builds and keeps so that the new particles over all ranks are those of one process.
// Every regularizer that runs on ranks remaps by owners: each old cell is built once, by its particle's rank.
// A function of the decomposition, the particle set and the regularizer, not of the kernel: the simulations of
// one scene with different kernels share its code.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/concept.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <span>
#include <string>
#include <vector>

namespace rsph::regularize {

namespace detail {

/// One rank's part of the remap, after add_remap_halo: the cells of its own n_own particles built and remapped,
/// the new cells' parts completed at the ranks that keep them, and the new particles of the sites this rank keeps
/// emitted. `reach`: the kernel's support times h_max.
template <class Domain, class Particles, int D, class Reg>
void remap_part(Domain& d, Particles& p, const Box<D>& box, Reg& reg, StepInfo info, std::size_t n_own, double reach) {
  std::vector<std::uint32_t> cells(n_own);
  std::iota(cells.begin(), cells.end(), 0u);
  auto owners = d.site_owners(p, box, reach);
  auto& part = info.part;
  part.cells = cells;
  part.max_over_ranks = [&d](double v) { return d.max(v); };
  part.sum_over_ranks = [&d](std::span<double> v) { d.sum_in_place(v); };
  part.own = n_own;
  part.exchange = [&d](const std::vector<std::vector<double>>& out, std::vector<int>* counts) {
    return d.exchange(out, counts);
  };
  part.rank = d.comm().rank();
  part.ranks = d.ranks();
  part.owner_of = [&owners](std::span<const double> sites) { return owners.owners(sites); };
  part.encloses = [&d](std::span<const double> x, double r) {
    return d.gathered().encloses(Eigen::Map<const Vec<D>>(x.data()), r);
  };
  part.refresh = [&d](std::vector<double>& v, std::size_t width) { d.refresh_rows(v, width); };
  reg.remap(p, box, info);
}

/// The mass and kinetic energy of the real particles over all ranks, in one reduction: plain sums, whose last
/// bits depend on the rank count (the mass is checked to 1e-12, the kinetic energy removed compared to 1e-10);
/// the exact totals took 5-6 % of a rank's time twice a remap.
template <class Domain, class Particles>
std::array<double, 2> mass_and_kinetic(const Domain& d, const Particles& p) {
  std::array<double, 2> s{};
  for (std::size_t a = 0; a < p.n_real; ++a) {
    s[0] += p.m[a];
    s[1] += 0.5 * p.m[a] * p.v[a].squaredNorm();
  }
  d.sum_in_place(std::span<double>(s));
  return s;
}

}  // namespace detail

/// The remap on many ranks: each rank builds the cells of its own particles only and completes the new cells' sums
/// with the other ranks' parts (the remap by owners: every old cell built once, by its owner), keeps the new
/// particles whose site its own gas held, and checks that the mass over all ranks is what it was. It gathers the
/// others' particles out to a short reach, and half as far again, on every rank, where some rank's cells or the
/// keepers it asks of reach beyond (Decomposition::gather_farther). `support`: the kernel's, in units of h.
/// Returns the kinetic energy the remap removed over all ranks.
template <class Domain, class Particles, int D, class Reg>
double remap_on_ranks(Domain& d, Particles& p, const Box<D>& box, Reg& reg, const StepInfo& info, double support) {
  static_assert(remaps_on_ranks<Reg>(), "this regularizer does not run on many ranks");
  const auto before = detail::mass_and_kinetic(d, p);
  double h_max = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) h_max = std::max(h_max, p.h[a]);
  h_max = d.max(h_max);
  for (;;) {
    const std::size_t n_own = d.add_remap_halo(p, box, d.owner_reach_in_h() * h_max);
    try {
      detail::remap_part(d, p, box, reg, info, n_own, support * h_max);
      break;
    } catch (const HaloTooNarrow&) {  // raised on every rank at once, before any particle changed
      d.gather_farther(p, n_own);
    }
  }
  d.renumber(p);  // the remap emitted only the sites this rank keeps
  const auto after = detail::mass_and_kinetic(d, p);
  if (!(std::abs(after[0] - before[0]) <= 1e-12 * before[0]))
    throw NumericalError("the remap on " + std::to_string(d.ranks()) + " ranks changed the mass by " +
                         std::to_string(after[0] / before[0] - 1.0) + ": its reach is too short");
  return before[1] - after[1];
}

}  // namespace rsph::regularize
