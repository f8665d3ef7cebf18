#pragma once
// The remap's sums on many ranks when every old cell is built once, by the rank that owns its particle
// (mpi/decomposition.hpp): a rank's overlaps are then part of the sums of the new cells near its boundary, the
// rest lying on other ranks. Each new cell is kept by one rank (the owner of its site's nearest old particle);
// the others send it their parts, in one sparse all-to-all, and it adds them in rank order. The hand-on of
// nearly empty cells then reads the complete sums of the cells around a kept one, which their owners send in a
// second exchange (a request, then the answer). What is the same in every dimension is here; the lattice
// gives the sites, the grid their indices.
#include "rsph/core/errors.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/remap_params.hpp"
#include "rsph/regularize/sums.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace rsph::regularize::detail {

/// Raises HaloTooNarrow on every rank where any rank could not decide its share (`decided` false): a check
/// every rank makes at the same point, before anything is sent on what an undecided rank computed.
inline void require_decided_everywhere(bool decided, const RankPart& part, const char* what) {
  if (part.max(decided ? 0.0 : 1.0) > 0.0)
    throw HaloTooNarrow(std::string("regularization: ") + what + " reaches beyond the particles a rank gathered");
}

/// Whether every old cell this rank built (reach >= 0: its farthest point from its particle) is complete: no
/// particle the local set lacks could cut it, since the local set holds every particle within twice that reach.
template <int D, bool E>
bool cells_complete(const ParticleSet<D, E>& p, std::span<const double> reach, const RankPart& part) {
  if (!part.encloses) return true;
  for (std::size_t a = 0; a < reach.size(); ++a)
    if (reach[a] >= 0.0 && !part.encloses(std::span<const double>(p.x[a].data(), D), 2.0 * reach[a])) return false;
  return true;
}

/// The numbers one new cell's sums travel as: its flat index, m, m v, E and the covered volume.
template <int D>
constexpr std::size_t owner_record = 4 + D;

template <int D>
void pack_sums(std::vector<double>& out, std::size_t flat, const Conserved<D>& c) {
  out.push_back(static_cast<double>(flat));  // exact: flat indices stay below 2^62, cells below 2^53 here
  out.push_back(c.m);
  for (int k = 0; k < D; ++k) out.push_back(c.mv[k]);
  out.push_back(c.E);
  out.push_back(c.volume);
}

template <int D>
Conserved<D> unpack_sums(const double* r) {
  Conserved<D> c;
  c.m = r[1];
  for (int k = 0; k < D; ++k) c.mv[k] = r[2 + k];
  c.E = r[2 + D];
  c.volume = r[3 + D];
  return c;
}

/// The sites of the grid cells `flats`, D coordinates after another, for RankPart::owner_of.
template <int D, class Lattice>
std::vector<double> site_coordinates(std::span<const std::size_t> flats, const CellGrid<D>& grid, const Box<D>& box,
                                     const Lattice& lattice) {
  std::vector<double> xs;
  xs.reserve(flats.size() * D);
  for (const std::size_t f : flats) {
    const Vec<D> s = lattice.site(box, grid.unflat(f));
    for (int k = 0; k < D; ++k) xs.push_back(s[k]);
  }
  return xs;
}

/// Step 0: this rank's parts, summed over its own grid `local` (dense or sparse), as sparse sums over the grid of
/// the whole set `whole`, which every rank lays out alike, in lattice order; cells that received nothing left out.
template <int D>
Sums<D> on_whole_grid(const Sums<D>& S, const CellGrid<D>& local, const CellGrid<D>& whole) {
  Sums<D> parts;
  parts.reset(0, true);
  parts.max_mismatch = S.max_mismatch;
  std::vector<std::size_t> flats;
  for (std::size_t c = 0; c < S.size(); ++c) {
    if (S.cell[c].volume == 0.0 && S.cell[c].m == 0.0) continue;
    const std::int64_t g = whole.flat(local.unflat(S.flat(c)));
    require(g >= 0, "regularization: a new cell lies outside the grid of the whole set");
    flats.push_back(static_cast<std::size_t>(g));
    parts.cell.push_back(S.cell[c]);
  }
  parts.index_by(std::move(flats));
  if (!std::is_sorted(parts.flat_of.begin(), parts.flat_of.end())) parts.sort_by_cell();
  return parts;
}

/// Step 1: every entry's part sent to the rank that keeps its cell; what this rank keeps, its own part first and
/// then the others' in rank order, returned as sparse sums. `owner` is each entry's keeper.
template <int D>
Sums<D> gather_kept_parts(const Sums<D>& S, const std::vector<int>& owner, const RankPart& part) {
  std::vector<std::vector<double>> out(static_cast<std::size_t>(part.ranks));
  Sums<D> kept;
  kept.reset(0, true);
  kept.max_mismatch = S.max_mismatch;
  for (std::size_t c = 0; c < S.size(); ++c) {
    if (owner[c] == part.rank)
      kept.at(S.flat(c)) += S.cell[c];
    else
      pack_sums<D>(out[static_cast<std::size_t>(owner[c])], S.flat(c), S.cell[c]);
  }
  const auto in = part.exchange(out, nullptr);
  for (std::size_t r = 0; r < in.size(); r += owner_record<D>)
    kept.at(static_cast<std::size_t>(in[r])) += unpack_sums<D>(&in[r]);
  return kept;
}

/// Step 2: the cells within `layers` of a kept one that other ranks keep, asked of their keepers, and their
/// complete sums added to `kept` (after its own entries, the first n_kept). `S` and `owner` (this rank's parts and
/// their keepers) name the keepers of the cells this rank's gas touched; the others are asked of part.owner_of.
template <int D, class Lattice>
void add_window(Sums<D>& kept, const Sums<D>& S, const std::vector<int>& owner, const CellGrid<D>& grid,
                const Box<D>& box, const Lattice& lattice, const RankPart& part, int layers) {
  const std::size_t n_kept = kept.size();
  SlotMap seen;  // the cells asked for, once each
  std::vector<std::size_t> known, unknown;
  std::vector<int> known_owner;
  for (std::size_t c = 0; c < n_kept; ++c) {
    bool inside = true;  // every neighbour kept here too: the cells that are not look `layers` deep for it
    for_each_cell_within(grid, kept.flat(c), 1, [&](std::size_t g) { inside = inside && kept.find(g) >= 0; });
    if (inside) continue;
    for_each_cell_within(grid, kept.flat(c), layers, [&](std::size_t g) {
      if (kept.find(g) >= 0 || seen.find(g) >= 0) return;
      seen.find_or_insert(g, 0);
      if (const std::int64_t e = S.find(g); e >= 0) {
        known.push_back(g);
        known_owner.push_back(owner[static_cast<std::size_t>(e)]);
      } else {
        unknown.push_back(g);
      }
    });
  }
  const auto asked_owner = part.owner_of(site_coordinates(std::span<const std::size_t>(unknown), grid, box, lattice));
  require_decided_everywhere(std::find(asked_owner.begin(), asked_owner.end(), -1) == asked_owner.end(), part,
                             "the keeper of a new cell near another rank's");
  std::vector<std::vector<double>> ask(static_cast<std::size_t>(part.ranks));
  for (std::size_t i = 0; i < known.size(); ++i)
    ask[static_cast<std::size_t>(known_owner[i])].push_back(static_cast<double>(known[i]));
  for (std::size_t i = 0; i < unknown.size(); ++i)
    if (asked_owner[i] != part.rank) ask[static_cast<std::size_t>(asked_owner[i])].push_back(double(unknown[i]));
  std::vector<int> counts;
  const auto asked = part.exchange(ask, &counts);
  std::vector<std::vector<double>> answer(static_cast<std::size_t>(part.ranks));
  std::size_t r = 0;
  for (std::size_t q = 0; q < counts.size(); ++q)
    for (int i = 0; i < counts[q]; ++i, ++r) {
      const auto f = static_cast<std::size_t>(asked[r]);
      if (const std::int64_t e = kept.find(f); e >= 0 && static_cast<std::size_t>(e) < n_kept)
        pack_sums<D>(answer[q], f, kept.cell[static_cast<std::size_t>(e)]);
    }
  const auto in = part.exchange(answer, nullptr);
  for (std::size_t k = 0; k < in.size(); k += owner_record<D>)
    kept.at(static_cast<std::size_t>(in[k])) = unpack_sums<D>(&in[k]);
}

/// Completes the sums of a remap whose old cells were built by their owners only (part.by_owners()): returns the
/// sums of the cells this rank keeps, complete, and of the cells within `layers` of them that others keep (for the
/// hand-on), in lattice order; `elsewhere` flags the latter, which the hand-on reads and the emission skips.
/// `cells_complete`: whether this rank's old cells are (cells_complete). Raises HaloTooNarrow on every rank where
/// a rank's cells or the keepers it needs lie beyond what it gathered.
template <int D, class Lattice>
Sums<D> complete_on_owners(const Sums<D>& S, const CellGrid<D>& grid, const Box<D>& box, const Lattice& lattice,
                           const RankPart& part, bool cells_complete, std::vector<std::uint8_t>& elsewhere,
                           int layers = 2) {
  require(part.owner_of && part.exchange, "regularization: the remap by owners needs owner_of and exchange");
  require(grid.n_cells < (std::size_t{1} << 53), "regularization: too many lattice cells to send their indices");
  const auto owner = part.owner_of(site_coordinates(std::span<const std::size_t>(S.flat_of), grid, box, lattice));
  require_decided_everywhere(cells_complete && std::find(owner.begin(), owner.end(), -1) == owner.end(), part,
                             "an old cell, or the keeper of a new cell it meets,");
  Sums<D> kept = gather_kept_parts(S, owner, part);
  const std::size_t n_kept = kept.size();
  add_window(kept, S, owner, grid, box, lattice, part, layers);
  const std::vector<std::size_t> window(kept.flat_of.begin() + static_cast<std::ptrdiff_t>(n_kept), kept.flat_of.end());
  kept.sort_by_cell();  // lattice order, as one process sums them: the hand-on visits the cells in it
  elsewhere.assign(kept.size(), 0);
  for (const std::size_t f : window) elsewhere[static_cast<std::size_t>(kept.find(f))] = 1;
  return kept;
}

}  // namespace rsph::regularize::detail
