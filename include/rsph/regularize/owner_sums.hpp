#pragma once
// The remap's sums on many ranks when every old cell is built once, by the rank that owns its particle
// (mpi/decomposition.hpp): a rank's overlaps are then part of the sums of the new cells near its boundary, the
// rest lying on other ranks. Each new cell is kept by one rank (the owner of its site's nearest old particle);
// the others send it their parts, in one sparse all-to-all, and it adds them in rank order. The hand-on of
// nearly empty cells then reads the complete sums of the cells around a kept one, which their owners send in a
// second exchange (a request, then the answer). What is the same in every dimension and lattice is here; the
// new cells as the ranks name them (GridCells for a lattice fixed by the box, the sites themselves for a
// per-site lattice, SitesOnRanks) give their sites, indices and neighbours.
#include "rsph/core/errors.hpp"
#include "rsph/core/keepers.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/remap_params.hpp"
#include "rsph/regularize/sums.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
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

/// One new cell's sums as D + 3 numbers: m, m v, E and the covered volume.
template <int D>
void write_sums(const Conserved<D>& c, double* v) {
  v[0] = c.m;
  for (int k = 0; k < D; ++k) v[1 + k] = c.mv[k];
  v[1 + D] = c.E;
  v[2 + D] = c.volume;
}
template <int D>
Conserved<D> read_sums(const double* v) {
  Conserved<D> c;
  c.m = v[0];
  for (int k = 0; k < D; ++k) c.mv[k] = v[1 + k];
  c.E = v[1 + D];
  c.volume = v[2 + D];
  return c;
}

/// The numbers one new cell's sums travel as: its flat index, then its sums.
template <int D>
constexpr std::size_t owner_record = 4 + D;

template <int D>
void pack_sums(std::vector<double>& out, std::size_t flat, const Conserved<D>& c) {
  out.push_back(static_cast<double>(flat));  // exact: flat indices stay below 2^62, cells below 2^53 here
  out.resize(out.size() + D + 3);
  write_sums<D>(c, out.data() + out.size() - (D + 3));
}

template <int D>
Conserved<D> unpack_sums(const double* r) {
  return read_sums<D>(r + 1);
}

/// The new cells of a lattice fixed by the box as the ranks name them: by their flat index on the grid of the
/// whole set `whole`, which every rank lays out alike. `local`: the grid a rank sums on.
template <int D, class Lattice>
struct GridCells {
  const CellGrid<D>* whole;
  const CellGrid<D>* local;
  const Box<D>* box;
  const Lattice* lattice;
  std::size_t size() const { return whole->n_cells; }
  Vec<D> site(std::size_t f) const { return lattice->site(*box, whole->unflat(f)); }
  /// f(g) for the cells within `layers` of cell c, c left out.
  template <class F>
  void for_each_within(std::size_t c, int layers, F&& f) const {
    for_each_cell_within(*whole, c, layers, f);
  }
  /// The whole grid's cell of the local grid's cell `flat` (-1: outside).
  std::int64_t whole_flat(std::size_t flat) const { return whole->flat(local->unflat(flat)); }
  /// The local grid's cell of the whole grid's cell f, which must lie in it.
  std::size_t local_flat(std::size_t f) const {
    const std::int64_t l = local->flat(whole->unflat(f));
    require(l >= 0, "regularization: a new cell kept here lies beyond the grid this rank sums on");
    return static_cast<std::size_t>(l);
  }
};

/// The sites of the new cells `flats` (`cells`: GridCells, or a per-site lattice's), D coordinates after another,
/// for RankPart::owner_of.
template <class Cells>
std::vector<double> site_coordinates(std::span<const std::size_t> flats, const Cells& cells) {
  std::vector<double> xs;
  for (const std::size_t f : flats) {
    const auto s = cells.site(f);
    xs.insert(xs.end(), s.data(), s.data() + s.size());
  }
  return xs;
}

/// Step 0: this rank's parts, summed over its own grid (dense or sparse), as sparse sums over the new cells as the
/// ranks name them (`cells`), in lattice order; cells that received nothing left out.
template <int D, class Cells>
Sums<D> numbered_for_ranks(const Sums<D>& S, const Cells& cells) {
  Sums<D> parts;
  parts.reset(0, true);
  parts.max_mismatch = S.max_mismatch;
  std::vector<std::size_t> flats;
  for (std::size_t c = 0; c < S.size(); ++c) {
    if (S.cell[c].volume == 0.0 && S.cell[c].m == 0.0) continue;
    const std::int64_t g = cells.whole_flat(S.flat(c));
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
template <int D, class Cells>
void add_window(Sums<D>& kept, const Sums<D>& S, const std::vector<int>& owner, const Cells& cells,
                const RankPart& part, int layers) {
  const std::size_t n_kept = kept.size();
  SlotMap seen;  // the cells asked for, once each
  std::vector<std::size_t> known, unknown;
  std::vector<int> known_owner;
  for (std::size_t c = 0; c < n_kept; ++c) {
    bool inside = true;  // every neighbour kept here too: the cells that are not look `layers` deep for it
    cells.for_each_within(kept.flat(c), 1, [&](std::size_t g) { inside = inside && kept.find(g) >= 0; });
    if (inside) continue;
    cells.for_each_within(kept.flat(c), layers, [&](std::size_t g) {
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
  const auto asked_owner = part.owner_of(site_coordinates(std::span<const std::size_t>(unknown), cells));
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

/// The end of the remap by owners, once `kept` holds the complete sums of the cells this rank keeps: adds the
/// complete sums of the cells within `layers` of them that others keep (for the hand-on; asked of their keepers),
/// sorts them into lattice order and flags in `elsewhere` the cells added, which the hand-on reads and the emission
/// skips. `S` and `owner`: the cells this rank's gas touched and their keepers.
template <int D, class Cells>
void add_window_in_lattice_order(Sums<D>& kept, const Sums<D>& S, const std::vector<int>& owner, const Cells& cells,
                                 const RankPart& part, std::vector<std::uint8_t>& elsewhere, int layers = 2) {
  const std::size_t n_kept = kept.size();
  add_window(kept, S, owner, cells, part, layers);
  const std::vector<std::size_t> window(kept.flat_of.begin() + static_cast<std::ptrdiff_t>(n_kept), kept.flat_of.end());
  kept.sort_by_cell();  // lattice order, as one process sums them: the hand-on visits the cells in it
  elsewhere.assign(kept.size(), 0);
  for (const std::size_t f : window) elsewhere[static_cast<std::size_t>(kept.find(f))] = 1;
}

/// Which rank keeps each new cell of `flats` (of `cells`, as the ranks name them); raises HaloTooNarrow on every
/// rank where a rank's cells are not complete (`cells_complete`) or a keeper is undecided.
template <class Cells>
std::vector<int> keepers_of(std::span<const std::size_t> flats, const Cells& cells, const RankPart& part,
                            bool cells_complete) {
  require(part.owner_of && part.exchange, "regularization: the remap by owners needs owner_of and exchange");
  require(cells.size() < (std::size_t{1} << 53), "regularization: too many lattice cells to send their indices");
  auto owner = part.owner_of(site_coordinates(flats, cells));
  require_decided_everywhere(cells_complete && std::find(owner.begin(), owner.end(), -1) == owner.end(), part,
                             "an old cell, or the keeper of a new cell it meets,");
  return owner;
}

/// Completes the sums of a remap whose old cells were built by their owners only (part.by_owners()): returns the
/// sums of the cells this rank keeps, complete, and of the cells within `layers` of them that others keep (for the
/// hand-on), in lattice order; `elsewhere` flags the latter, which the hand-on reads and the emission skips.
/// `cells_complete`: whether this rank's old cells are (cells_complete). Raises HaloTooNarrow on every rank where
/// a rank's cells or the keepers it needs lie beyond what it gathered.
template <int D, class Cells>
Sums<D> complete_on_owners(const Sums<D>& S, const Cells& cells, const RankPart& part, bool cells_complete,
                           std::vector<std::uint8_t>& elsewhere, int layers = 2) {
  const auto owner = keepers_of(std::span<const std::size_t>(S.flat_of), cells, part, cells_complete);
  Sums<D> kept = gather_kept_parts(S, owner, part);
  add_window_in_lattice_order(kept, S, owner, cells, part, elsewhere, layers);
  return kept;
}

using rsph::KeptElsewhereTouched;

/// complete_at_keepers (core/keepers.hpp) over the ranks of a remap: cell i, flat index flat[i] on the grid of the
/// whole set, is kept by owner[i].
template <class Combine>
KeptElsewhereTouched complete_at_keepers(std::span<const std::size_t> flat, std::span<const int> owner,
                                         std::vector<double>& values, std::size_t w, const RankPart& part,
                                         Combine&& combine) {
  return rsph::complete_at_keepers(flat, owner, values, w, part.rank, part.ranks, part.exchange,
                                   std::forward<Combine>(combine));
}

}  // namespace rsph::regularize::detail
