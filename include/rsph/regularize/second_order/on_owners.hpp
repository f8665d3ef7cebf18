#pragma once
// The second-order remap on many ranks with every old cell built once, by the rank that owns its particle
// (owner_sums.hpp). What one process reads beyond a cell's own pieces comes from the other ranks:
// - the fits read each neighbour cell's volume and centroid, then its mass centroid: from the neighbour's owner,
//   one exchange each (RankPart::refresh);
// - the limiter reads each new cell's bounds, the union over every old cell with a piece in it, and the thermal
//   floor each new cell's complete sums and least u: completed at the cell's keeper and sent back to every rank
//   that touched it (complete_at_keepers, two exchanges each), so that every rank takes the same cells to first
//   order;
// - the hand-on then reads the kept cells and their neighbours, as in the first order.
#include "rsph/core/particle_set.hpp"
#include "rsph/regularize/cell_grid.hpp"
#include "rsph/regularize/owner_sums.hpp"
#include "rsph/regularize/remap_params.hpp"
#include "rsph/regularize/second_order/workspace.hpp"
#include "rsph/regularize/sums.hpp"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph::regularize::second_order {

/// The second-order remap in one process (or on ranks that gathered the cells near their own): every cell the fits,
/// the limiter and the thermal floor read is here, nothing to share.
struct InOneProcess {
  std::size_t own(std::size_t n_local) const { return n_local; }
  void share_geometry(const auto&) const {}
  void share_mass_centroids(const auto&) const {}
  void find_touched(const auto&, const auto&, std::size_t, std::size_t, const std::vector<std::size_t>*) const {}
  void complete_bounds(const auto&) const {}
  void complete_sums(const auto&, const std::vector<double>*) const {}
  bool any(std::size_t n) const { return n > 0; }
};

/// One rank's part of a second-order remap by owners: its own particles are the first `own` of the local set,
/// the others' follow. `cells`: the new cells as the ranks name them (detail::GridCells, detail::SitesOnRanks).
template <int D, class Cells>
class ByOwners {
 public:
  ByOwners(const RankPart& part, const Cells& cells) : part_(&part), cells_(cells) {}

  std::size_t own(std::size_t n_local) const { return std::min(n_local, part_->own); }

  /// The other ranks' cells' volumes and centroids (relative to their particles), from their owners.
  void share_geometry(CellStore<D>& s) const {
    share_from_owners(
        s.volume.size(), D + 1,
        [&](std::size_t a, double* v) {
          v[0] = s.volume[a];
          for (int k = 0; k < D; ++k) v[1 + k] = s.centroid[a][k];
        },
        [&](std::size_t a, const double* v) {
          s.volume[a] = v[0];
          for (int k = 0; k < D; ++k) s.centroid[a][k] = v[1 + k];
        });
  }

  /// The other ranks' cells' mass centroids, from their owners' density fits.
  void share_mass_centroids(std::vector<Reconstruction<D>>& recon) const {
    share_from_owners(
        recon.size(), D,
        [&](std::size_t a, double* v) {
          for (int k = 0; k < D; ++k) v[k] = recon[a].x_m[k];
        },
        [&](std::size_t a, const double* v) {
          for (int k = 0; k < D; ++k) recon[a].x_m[k] = v[k];
        });
  }

  /// The new cells this rank's own old cells (the first n_own of `p`) have pieces in (sum entries of `n_cells`;
  /// `cells`: each entry's cell of the local grid where the sums are compact, null where dense), and their
  /// keepers. Raises HaloTooNarrow on every rank where a rank's cells are not complete (reach beyond what it
  /// gathered) or the keeper of a cell is undecided.
  template <bool E>
  void find_touched(const ParticleSet<D, E>& p, const Workspace<D>& w2, std::size_t n_own, std::size_t n_cells,
                    const std::vector<std::size_t>* cells) {
    const bool complete = detail::cells_complete(p, std::span<const double>(w2.cells.reach).first(n_own), *part_);
    std::vector<std::uint8_t> touched(n_cells, 0);
    for (std::size_t a = 0; a < n_own; ++a) {
      const auto& listed = w2.threads[w2.piece_thread[a]].pieces;
      for (std::size_t k = w2.piece_first[a], end = k + w2.piece_count[a]; k < end; ++k) touched[listed.flat[k]] = 1;
    }
    entry_.clear();
    flat_.clear();
    for (std::size_t c = 0; c < n_cells; ++c) {
      if (!touched[c]) continue;
      const std::int64_t g = cells_.whole_flat(cells ? (*cells)[c] : c);
      require(g >= 0, "regularization: a new cell lies outside the grid of the whole set");
      entry_.push_back(static_cast<std::uint32_t>(c));
      flat_.push_back(static_cast<std::size_t>(g));
    }
    owner_ = detail::keepers_of(std::span<const std::size_t>(flat_), cells_, *part_, complete);
  }

  /// Each touched cell's bounds made the union over every rank's old cells with a piece in it.
  void complete_bounds(std::vector<FieldRanges<D>>& bounds) const {
    constexpr std::size_t w = 2 * (D + 2);  // lo and -hi of rho, e and each v: every one combined by min
    std::vector<double> v(entry_.size() * w);
    auto ranges = [](FieldRanges<D>& b, auto&& f) {
      f(b.rho, 0);
      f(b.e, 2);
      for (std::size_t k = 0; k < static_cast<std::size_t>(D); ++k) f(b.v[k], 4 + 2 * k);
    };
    for (std::size_t i = 0; i < entry_.size(); ++i)
      ranges(bounds[entry_[i]], [&](const Range& r, std::size_t at) {
        v[i * w + at] = r.lo;
        v[i * w + at + 1] = -r.hi;
      });
    (void)detail::complete_at_keepers(flat_, owner_, v, w, *part_, [](double* into, const double* from) {
      for (std::size_t k = 0; k < w; ++k) into[k] = std::min(into[k], from[k]);
    });
    for (std::size_t i = 0; i < entry_.size(); ++i)
      ranges(bounds[entry_[i]], [&](Range& r, std::size_t at) {
        r.lo = v[i * w + at];
        r.hi = -v[i * w + at + 1];
      });
  }

  /// Each touched cell's sums (and least u of its feeders, with `u_min`) made complete over the ranks; the cells
  /// kept here that only others touched are kept for kept_sums.
  void complete_sums(detail::Sums<D>& S, std::vector<double>* u_min) {
    width_ = D + 3 + (u_min ? 1 : 0);
    const std::size_t w = width_;
    std::vector<double> v(entry_.size() * w);
    for (std::size_t i = 0; i < entry_.size(); ++i) {
      detail::write_sums<D>(S.cell[entry_[i]], &v[i * w]);
      if (u_min) v[i * w + D + 3] = (*u_min)[entry_[i]];
    }
    extra_ = detail::complete_at_keepers(flat_, owner_, v, w, *part_, [w](double* into, const double* from) {
      for (std::size_t k = 0; k < D + 3; ++k) into[k] += from[k];
      if (w > D + 3) into[D + 3] = std::min(into[D + 3], from[D + 3]);
    });
    for (std::size_t i = 0; i < entry_.size(); ++i) {
      S.cell[entry_[i]] = detail::read_sums<D>(&v[i * w]);
      if (u_min) (*u_min)[entry_[i]] = v[i * w + D + 3];
    }
  }

  /// Whether any rank counted any (the thermal floor's cells: every rank takes the same passes).
  bool any(std::size_t n) const { return part_->max(static_cast<double>(n)) > 0.0; }

  /// After complete_sums, on sums dense over this rank's grid (`cells_` a detail::GridCells): the complete sums of the
  /// cells this rank keeps, the others' emptied, so that the ranks' sums add up to one process's (the multi-level
  /// remap adds them into its coarser cells and trades them).
  void keep_kept_only(detail::Sums<D>& S) const {
    for (std::size_t i = 0; i < entry_.size(); ++i)
      if (owner_[i] != part_->rank) S.cell[entry_[i]] = Conserved<D>{};
    for (std::size_t e = 0; e < extra_.name.size(); ++e)  // kept here, touched by the others' cells alone
      S.cell[cells_.local_flat(extra_.name[e])] = detail::read_sums<D>(&extra_.values[e * width_]);
  }

  /// After the last complete_sums: the complete sums of the cells this rank keeps and of those within two layers
  /// that others keep (`elsewhere`), on the grid of the whole set in lattice order, for the hand-on and emission.
  detail::Sums<D> kept_sums(const detail::Sums<D>& S, std::vector<std::uint8_t>& elsewhere) const {
    detail::Sums<D> kept, touched;
    kept.reset(0, true);
    touched.reset(0, true);
    kept.max_mismatch = S.max_mismatch;
    for (std::size_t i = 0; i < entry_.size(); ++i) {
      touched.at(flat_[i]);  // entry i, for the keepers of the cells near the kept ones
      if (owner_[i] == part_->rank) kept.at(flat_[i]) = S.cell[entry_[i]];
    }
    for (std::size_t e = 0; e < extra_.name.size(); ++e)
      kept.at(extra_.name[e]) = detail::read_sums<D>(&extra_.values[e * width_]);
    detail::add_window_in_lattice_order(kept, touched, owner_, cells_, *part_, elsewhere);
    return kept;
  }

 private:
  /// w numbers per particle of the n in the local set: put(a, row) writes this rank's own, take(a, row) reads
  /// what the owners of the others sent (one exchange, RankPart::refresh).
  template <class Put, class Take>
  void share_from_owners(std::size_t n, std::size_t w, Put&& put, Take&& take) const {
    const std::size_t n_own = own(n);
    std::vector<double> v(n * w, 0.0);
    for (std::size_t a = 0; a < n_own; ++a) put(a, &v[a * w]);
    part_->refresh(v, w);
    for (std::size_t a = n_own; a < n; ++a) take(a, &v[a * w]);
  }

  const RankPart* part_;
  Cells cells_;
  std::vector<std::uint32_t> entry_;  ///< the sum entries this rank's own cells touched
  std::vector<std::size_t> flat_;     ///< their cells on the whole grid
  std::vector<int> owner_;            ///< their keepers
  detail::KeptElsewhereTouched extra_;
  std::size_t width_ = D + 3;
};

}  // namespace rsph::regularize::second_order
