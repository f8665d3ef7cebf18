#pragma once
// Domain decomposition of the SPH step over the ranks of a communicator. Each rank owns the real particles
// of its part of the domain (Zoltan's partition, weighted by each particle's neighbour count); the particles
// of other ranks that its own ones can reach come to it as ghosts (halos), with the periodic and mirror
// images of make_ghosts made afterwards of real particles and halos alike; the fields a pass changes are
// refreshed on the halos after it; time steps, schedules and checks agree through reductions.
//
// Which rank owns a particle never changes a result beyond round-off: a rank's halo holds every particle
// within `width` of its own ones, whatever the cut, so the partition and the migration only move work.
// On one rank every call is the serial code's: the same ghosts in the same order, so the same bits.
#include "rsph/boundary/ghosts.hpp"
#include "rsph/core/diagnostics.hpp"
#include "rsph/core/exact_sum.hpp"
#include "rsph/core/keepers.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/mpi/comm.hpp"
#include "rsph/mpi/partition.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <span>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace rsph::mpi {

/// Where a rank's local set holds every particle of the run after add_remap_halo: the bounds of its own
/// particles widened by the width gathered, on each axis; unbounded where that passes the bounds of every rank's
/// particles or, on a periodic axis, spans the box. An old cell or a nearest-particle search inside it is
/// decided here alike on every rank.
template <int D>
struct Gathered {
  static constexpr double inf = std::numeric_limits<double>::infinity();
  Vec<D> lo = Vec<D>::Constant(-inf), hi = Vec<D>::Constant(inf);
  Vec<D> period = Vec<D>::Zero();  ///< the box's length on a periodic axis bounded here, else 0

  /// Whether the ball of radius r about c lies inside (on a periodic axis, one image of it).
  bool encloses(const Vec<D>& c, double r) const {
    for (int k = 0; k < D; ++k) {
      bool in = c[k] - r >= lo[k] && c[k] + r <= hi[k];
      for (double s : {-1.0, 1.0})
        in = in || (period[k] > 0.0 && c[k] + s * period[k] - r >= lo[k] && c[k] + s * period[k] + r <= hi[k]);
      if (!in) return false;
    }
    return true;
  }
};

/// Which rank keeps a point after a remap: the one whose old particle is nearest to it (periodic images included,
/// ties to the lower identity). Made on every rank from its local set before the remap (its own particles first,
/// then the other ranks' out to the remap's reach, `rank` naming each one's), it answers alike on every rank for a
/// point within `reach` of an old particle: each new site is one rank's, the one whose gas was there.
template <int D>
class SiteOwners {
 public:
  SiteOwners(const std::vector<Vec<D>>& x, const std::vector<std::uint64_t>& id, const Box<D>& box, double reach,
             std::vector<int> rank, Gathered<D> gathered = {})
      : id_(id), rank_(std::move(rank)), reach_(reach), gathered_(std::move(gathered)), pts_(x), of_(x.size()) {
    for (std::size_t i = 0; i < of_.size(); ++i) of_[i] = static_cast<std::uint32_t>(i);
    for (int k = 0; k < D; ++k) {  // images of the points near periodic faces
      if (!box.periodic(k)) continue;
      const double L = box.hi[k] - box.lo[k];
      const std::size_t n = pts_.size();
      for (std::size_t i = 0; i < n; ++i)
        for (double shift : {-L, L}) {
          Vec<D> y = pts_[i];
          y[k] += shift;
          if (y[k] >= box.lo[k] - reach && y[k] <= box.hi[k] + reach) {
            pts_.push_back(y);
            of_.push_back(of_[i]);
          }
        }
    }
    cells_.build(pts_, first_radius());
  }

  /// Per point of `sites`: the rank that keeps it, or -1 where a particle nearer than the nearest found here
  /// could lie outside the gathered set (`gathered`), so that only a wider halo tells.
  std::vector<int> owners(std::span<const double> sites) const {
    std::vector<int> out(sites.size() / D);
    rsph::run_parallel(out.size(), [&](int, std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        const Eigen::Map<const Vec<D>> site(sites.data() + D * i);
        double distance = 0.0;
        const std::size_t a = nearest(site, &distance);
        out[i] = gathered_.encloses(site, distance) ? rank_.at(a) : -1;
      }
    });
    return out;
  }

 private:
  /// The local index of the old particle nearest to `site`.
  std::size_t nearest(const Vec<D>& site, double* distance = nullptr) const {
    const std::size_t none = id_.size();
    for (double r = first_radius();; r *= 2.0) {
      double best = std::numeric_limits<double>::infinity();
      std::size_t who = none;
      cells_.for_each_within(site, r, [&](std::uint32_t j) {
        const double d2 = (pts_[j] - site).squaredNorm();
        const std::size_t o = of_[j];
        if (d2 < best || (d2 == best && who < none && id_[o] < id_[who])) best = d2, who = o;
      });
      if (who < none && best <= r * r) {
        if (distance) *distance = std::sqrt(best);
        return who;
      }
      require(r < 1e6 * reach_, "regularization: a new site has no old particle near it");
    }
  }

  /// The first search radius, and the cell list's: most sites have an old particle within a quarter of the
  /// reach (half an h), and a radius twice as large is tried where none is.
  double first_radius() const { return 0.25 * reach_; }

  std::vector<std::uint64_t> id_;
  std::vector<int> rank_;  ///< the rank that owns each particle of the local set
  double reach_;
  Gathered<D> gathered_;
  std::vector<Vec<D>> pts_;
  std::vector<std::uint32_t> of_;  ///< the particle each point (or image) is
  neighbors::CellList<D> cells_;
};

/// When the partition is recomputed, and how a set built alike on every rank is first shared out.
struct DecompositionParams {
  PartitionParams partition;
  /// Recompute the partition when the largest rank's work passes this multiple of the mean, or every
  /// `repartition_every` steps (particles drift away from their rank's part, its halo grows).
  double rebalance_above = 1.1;
  int repartition_every = 20;
  /// The remap (each old cell built by its owner alone, regularize/remap_on_ranks.hpp) gathers the
  /// particles within this many largest h at first, and half as far again until every rank's own cells and the
  /// keepers of the new cells it asks about are decided within what it gathered (Gathered); later remaps start
  /// from the reach the last one needed.
  double owner_reach_in_h = 4.0;
  /// A rank describes its particles to the others for their halos by 2^halo_piece_levels boxes, its particles
  /// split that many times at the middle of their longest axis: a curved part (a piece of a disk's annulus) is
  /// held by boxes that hug it, where one box round it holds much of the others' gas. 0: one box a rank.
  int halo_piece_levels = 3;
  /// Up to this many ranks every rank receives every rank's boxes at each halo build (one all-gather, 4 D numbers
  /// a box); beyond, it receives every rank's one box round its boxes, and the boxes themselves only from the
  /// ranks whose box meets its own (Comm::trade): P boxes and a message to and from each such rank, where P
  /// 2^halo_piece_levels boxes grow past what the messages cost (3.1 MB a step at 4096 ranks in 3D,
  /// docs/performance.md).
  int boxes_to_all_up_to = 1024;
  void validate() const {
    partition.validate();
    require(rebalance_above >= 1.0, "the decomposition's rebalance threshold must be at least 1");
    require(repartition_every >= 1, "the decomposition must repartition at least every step count >= 1");
    require(owner_reach_in_h > 0.0, "the decomposition's first reach of the remap by owners must be positive");
    require(halo_piece_levels >= 0 && halo_piece_levels <= 10,
            "the decomposition's halo pieces must be split 0 to 10 times");
    require(boxes_to_all_up_to >= 1, "the decomposition's boxes_to_all_up_to must be at least 1");
  }
};

/// What the halo exchanges and migrations sent, for the scale measurements (docs/performance.md).
struct ExchangeCounts {
  std::uint64_t halo_points = 0;        ///< halos received at the last ghost build
  std::uint64_t remap_halo_points = 0;  ///< other ranks' particles remapped with this rank's at the last remap
  std::uint64_t remap_widenings = 0;    ///< remaps by owners that gathered again, wider, since the start
  std::uint64_t bytes_sent = 0;         ///< since the start: halos, their refreshes, migrations
  std::uint64_t migrated = 0;           ///< particles sent to another rank since the start
  std::uint64_t partitions = 0;         ///< partitions computed
  /// other ranks whose boxes this rank's particles were tested against at the last halo build (of the ghosts or
  /// of a remap): every other rank up to DecompositionParams::boxes_to_all_up_to ranks, beyond those whose box
  /// round their particles and reaches meets this rank's
  std::uint64_t halo_partners = 0;
};

namespace detail {
template <class T>
struct Parts {
  using Scalar = T;
  static constexpr int n = 1;
};
template <int R, int C, int O, int MR, int MC>
struct Parts<Eigen::Matrix<double, R, C, O, MR, MC>> {  // vectors and matrices, by their coefficients
  using Scalar = double;
  static constexpr int n = R * C;
};

/// A field's entry in a message: its bytes in whole 8-byte words (a byte takes one word, a Vec<3> three).
template <class T>
constexpr std::size_t words = (sizeof(typename Parts<T>::Scalar) * Parts<T>::n + 7) / 8;
/// Where an entry's bytes start (T const or not).
template <class T>
auto* bytes_of(T& v) {
  if constexpr (std::is_arithmetic_v<std::remove_const_t<T>>)
    return &v;
  else
    return v.data();
}
/// Writes v at w (its padding bytes left as they are); returns the words written.
template <class T>
std::size_t store(const T& v, std::uint64_t* w) {
  std::memcpy(w, bytes_of(v), sizeof(typename Parts<T>::Scalar) * Parts<T>::n);
  return words<T>;
}
/// Reads v from r; returns the words read.
template <class T>
std::size_t load(T& v, const std::uint64_t* r) {
  std::memcpy(bytes_of(v), r, sizeof(typename Parts<T>::Scalar) * Parts<T>::n);
  return words<T>;
}
/// f(std::get<i>(a), std::get<i>(b)) for every i of two tuples of one size.
template <class A, class B, class F>
void each_pair(A&& a, B&& b, F&& f) {
  constexpr std::size_t n = std::tuple_size_v<std::remove_cvref_t<A>>;
  static_assert(n == std::tuple_size_v<std::remove_cvref_t<B>>, "each_pair: two tuples of one size");
  [&]<std::size_t... I>(std::index_sequence<I...>) { (f(std::get<I>(a), std::get<I>(b)), ...); }
  (std::make_index_sequence<n>{});
}
}  // namespace detail

/// Can any point of [lo1, hi1], or of one of its periodic images, lie within [lo2, hi2]? No where either is
/// empty, or their intervals miss on an axis, on a periodic one for every image: the shifts s L with
/// lo1 + s L <= hi2 and lo2 <= hi1 + s L hold no integer s (a slack of 1e-9 L keeps a touching image).
template <int D>
bool may_meet(const Vec<D>& lo1, const Vec<D>& hi1, const Vec<D>& lo2, const Vec<D>& hi2, const Box<D>& box) {
  for (int k = 0; k < D; ++k) {
    if (hi1[k] < lo1[k] || hi2[k] < lo2[k]) return false;
    if (!box.periodic(k)) {
      if (hi1[k] < lo2[k] || hi2[k] < lo1[k]) return false;
      continue;
    }
    const double L = box.hi[k] - box.lo[k], slack = 1e-9;
    if (std::floor((hi2[k] - lo1[k]) / L + slack) < std::ceil((lo2[k] - hi1[k]) / L - slack)) return false;
  }
  return true;
}

/// Whether two halo boxes (4 D numbers each: lo, hi of the particles, lo, hi of their reaches) may trade: the
/// particles of either reach the other's, or lie in its reach. Symmetric.
template <int D>
bool boxes_meet(const double* m, const double* o, const Box<D>& box) {
  using Map = Eigen::Map<const Vec<D>>;
  return may_meet<D>(Map(m), Map(m + D), Map(o + 2 * D), Map(o + 3 * D), box) ||
         may_meet<D>(Map(m + 2 * D), Map(m + 3 * D), Map(o), Map(o + D), box);
}

namespace detail {
/// A set of particles split into pieces: 4 D numbers a piece (lo, hi of its particles, lo, hi of their reaches
/// x -+ reach(a); a piece with none: lo = inf, hi = -inf), and the piece of each particle.
struct Pieces {
  std::vector<double> bounds;
  std::vector<std::uint32_t> piece;
};

/// One box round the boxes `bounds` (4 D numbers each: lo, hi of the particles, lo, hi of their reaches).
template <int D>
std::vector<double> hull_of(const std::vector<double>& bounds) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<double> hull(4 * D);
  for (int k = 0; k < D; ++k) hull[k] = hull[2 * D + k] = inf, hull[D + k] = hull[3 * D + k] = -inf;
  for (std::size_t b = 0; b < bounds.size(); b += 4 * D)
    for (std::size_t k = 0; k < 4 * D; ++k)
      hull[k] = (k / D) % 2 == 0 ? std::min(hull[k], bounds[b + k]) : std::max(hull[k], bounds[b + k]);
  return hull;
}

/// The particles x[0, n) split `levels` times at the middle of their bounds' longest axis, into 2^levels pieces
/// (some empty where a piece's particles all sit at one point, or fewer particles than pieces are left), the
/// same count on every rank. One pass over the particles a level.
template <int D, class Reach>
Pieces split_into_pieces(const std::vector<Vec<D>>& x, std::size_t n, Reach&& reach, int levels) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  constexpr std::size_t width = 4 * D;
  Pieces out{std::vector<double>((std::size_t{1} << levels) * width), std::vector<std::uint32_t>(n)};
  for (std::size_t i = 0; i < out.bounds.size(); i += width)
    for (int k = 0; k < D; ++k)
      out.bounds[i + k] = out.bounds[i + 2 * D + k] = inf, out.bounds[i + D + k] = out.bounds[i + 3 * D + k] = -inf;
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  // the particles order[first, last) at depth `level`: piece `at`, or the pieces after it that its halves take
  const auto split = [&](auto&& self, std::size_t first, std::size_t last, int level, std::size_t at) -> void {
    double* b = &out.bounds[at * width];
    for (std::size_t i = first; i < last; ++i) {
      const auto a = order[i];
      const double r = reach(a);
      out.piece[a] = static_cast<std::uint32_t>(at);
      for (int k = 0; k < D; ++k) {
        b[k] = std::min(b[k], x[a][k]), b[D + k] = std::max(b[D + k], x[a][k]);
        b[2 * D + k] = std::min(b[2 * D + k], x[a][k] - r), b[3 * D + k] = std::max(b[3 * D + k], x[a][k] + r);
      }
    }
    int axis = 0;
    for (int k = 1; k < D; ++k)
      if (b[D + k] - b[k] > b[D + axis] - b[axis]) axis = k;
    if (level == levels || last - first < 2 || !(b[D + axis] > b[axis])) return;
    const double cut = 0.5 * (b[axis] + b[D + axis]);
    const auto mid = std::partition(order.begin() + static_cast<std::ptrdiff_t>(first),
                                    order.begin() + static_cast<std::ptrdiff_t>(last),
                                    [&](std::uint32_t a) { return x[a][axis] < cut; }) -
                     order.begin();
    for (int k = 0; k < D; ++k)  // the two halves take this piece's place
      b[k] = b[2 * D + k] = inf, b[D + k] = b[3 * D + k] = -inf;
    self(self, first, static_cast<std::size_t>(mid), level + 1, at);
    self(self, static_cast<std::size_t>(mid), last, level + 1, at + (std::size_t{1} << (levels - level - 1)));
  };
  split(split, 0, n, 0, 0);
  return out;
}
}  // namespace detail

/// Does a point at x, or one of its periodic images, lie within the box [lo, hi]?
template <int D>
bool reaches(const Vec<D>& x, const Vec<D>& lo, const Vec<D>& hi, const Box<D>& box, double width) {
  for (int k = 0; k < D; ++k) {
    if (!box.periodic(k)) {
      if (x[k] < lo[k] || x[k] > hi[k]) return false;
      continue;
    }
    const double L = box.hi[k] - box.lo[k];
    const int reach = static_cast<int>(std::ceil(width / L)) + 1;
    bool any = false;
    for (int s = -reach; s <= reach && !any; ++s) any = x[k] + s * L >= lo[k] && x[k] + s * L <= hi[k];
    if (!any) return false;
  }
  return true;
}

/// The decomposition as a term of a Simulation (core/domain.hpp): a scene that names it runs on the ranks of
/// its communicator; one that does not is unchanged.
template <int D>
class Decomposition {
 public:
  static constexpr bool decomposes_domain = true;
  static constexpr int dim = D;

  explicit Decomposition(MPI_Comm comm = MPI_COMM_WORLD, DecompositionParams params = {})
      : comm_(std::make_shared<Comm>(Comm::duplicate(comm))),
        params_(std::move(params)),
        owner_reach_in_h_(params_.owner_reach_in_h) {
    params_.validate();
    if (comm_->size() > 1) partitioner_ = std::make_shared<Partitioner<D>>(comm_->get(), params_.partition);
  }

  const Comm& comm() const { return *comm_; }
  int ranks() const { return comm_->size(); }
  const ExchangeCounts& counts() const { return counts_; }
  /// Wall seconds in MPI calls so far (messages, and waiting for the other ranks).
  double communication_seconds() const { return comm_->seconds(); }
  /// How far, in the largest h, the next remap by owners gathers first: the reach the last one needed.
  double owner_reach_in_h() const { return owner_reach_in_h_; }

  double min(double v) const { return ranks() == 1 ? v : comm_->min(v); }
  double max(double v) const { return ranks() == 1 ? v : comm_->max(v); }
  /// The least `lo` and the largest `hi` over the ranks, in one reduction (the least of lo and of -hi: exact).
  void min_max(double& lo, double& hi) const {
    std::array<double, 2> v{lo, -hi};
    extreme_in_place(v, true);
    lo = v[0];
    hi = -v[1];
  }
  bool any(bool v) const { return ranks() == 1 ? v : comm_->any(v); }
  bool all(bool v) const { return ranks() == 1 ? v : comm_->all(v); }
  std::uint64_t sum(std::uint64_t v) const { return ranks() == 1 ? v : comm_->sum(v); }

  /// Keeps this rank's share of a set that every rank built alike (the same particles, identities and
  /// order): a contiguous block of it; the first balance() then partitions it.
  template <bool E>
  void distribute(ParticleSet<D, E>& p) {
    const auto P = static_cast<std::size_t>(ranks()), r = static_cast<std::size_t>(comm_->rank());
    if (P == 1) return;
    const std::size_t n = p.n_real, begin = n * r / P, end = n * (r + 1) / P;
    p.erase_if([&](std::size_t a) { return a < begin || a >= end; });
  }

  /// Recomputes the partition when it is due and moves the particles (their fields and the per-particle
  /// arrays in `extra`, each of n_real entries) to their new ranks. work[a]: particle a's cost.
  template <bool E, class... Extra>
  void balance(ParticleSet<D, E>& p, std::span<const double> work, Extra&... extra) {
    if (ranks() == 1) return;
    ++steps_;
    if (!due_ && steps_ < params_.repartition_every) {
      double mine = 0.0;
      for (double w : work) mine += w;
      const double most = comm_->max(mine), mean = comm_->all_reduce(mine, MPI_SUM) / ranks();
      if (!(most > params_.rebalance_above * mean)) return;
    }
    p.clear_ghosts();
    std::vector<double> unit;
    if (work.size() != p.n_real) {  // no measured work yet (the first partition): every particle alike
      unit.assign(p.n_real, 1.0);
      work = unit;
    }
    const auto dest = partitioner_->destinations(std::span<const Vec<D>>(p.x.data(), p.n_real),
                                                 std::span<const std::uint64_t>(p.id), work, comm_->rank());
    ++counts_.partitions;
    migrate(p, dest, extra...);
    steps_ = 0;
    due_ = false;
  }

  /// The next balance() partitions afresh (the particles came from elsewhere: a checkpoint).
  void repartition() { due_ = true; }

  /// Sends every real particle a with dest[a] != this rank there, every field and identity with it, and the
  /// entries of the per-particle arrays `extra`; the staying ones keep their order, the arrivals follow in
  /// rank order.
  template <bool E, class... Extra>
  void migrate(ParticleSet<D, E>& p, const std::vector<int>& dest, Extra&... extra) {
    p.clear_ghosts();
    const int me = comm_->rank();
    Lists out(static_cast<std::size_t>(ranks()));
    std::vector<std::uint32_t> stay;
    for (std::size_t a = 0; a < p.n_real; ++a)
      (dest[a] == me ? stay : out[static_cast<std::size_t>(dest[a])]).push_back(static_cast<std::uint32_t>(a));
    counts_.migrated += p.n_real - stay.size();
    const auto fields = std::tuple_cat(std::tie(p.m, p.rho, p.h, p.P, p.cs, p.x, p.v, p.dv_dt), energy_fields(p),
                                       std::tie(p.frozen, p.id), std::tie(extra...));
    detail::each_pair(fields, send_tied(fields, out),
                      [&](auto& f, const auto& in) { f = concat(gather(f, stay), in); });
    p.n_real = p.x.size();
    p.next_id = comm_->all_reduce(p.next_id, MPI_MAX);
  }

  /// The ghosts of every point this rank needs: the real particles of other ranks within reach of its own, or
  /// whose reach its own are in (reach: `width` for the largest h, in proportion for the others; across periodic
  /// faces too), appended first, then the periodic and mirror images of boundary::add_images
  /// of real particles and halos. One rank: boundary::make_ghosts itself. h_max: every rank's largest h, when the
  /// caller has it (else one more reduction finds it).
  template <bool E>
  void make_ghosts(ParticleSet<D, E>& p, const Box<D>& box, double width, double h_max = -1.0) {
    p.clear_ghosts();
    if (ranks() > 1) {
      if (h_max < 0.0) {
        h_max = 0.0;
        for (std::size_t a = 0; a < p.n_real; ++a) h_max = std::max(h_max, p.h[a]);
        h_max = max(h_max);
      }
      (void)receive_halos(p, box, width, h_max);
    }
    counts_.halo_points = halo_count_;
    boundary::add_images(p, box, width);
  }

  /// After a pass has changed the fields f... on the real particles: their values on this rank's halos, all in
  /// one message from each rank.
  template <class... T>
  void refresh_halos(std::vector<T>&... f) const {
    if (ranks() == 1) return;
    detail::each_pair(std::tie(f...), send(halo_send_, nullptr, f...), [&](auto& field, const auto& in) {
      std::copy(in.begin(), in.end(), field.begin() + static_cast<std::ptrdiff_t>(halo_first_));
    });
  }

  /// Before a remap: the real particles of other ranks within `width` of this rank's own, appended after them
  /// as real particles (fields and identities), so that the remap of this local set builds exactly every old
  /// cell that meets a new cell this rank keeps. Returns how many are this rank's own (the first ones).
  template <bool E>
  std::size_t add_remap_halo(ParticleSet<D, E>& p, const Box<D>& box, double width) {
    const std::size_t n_own = p.n_real;
    if (ranks() == 1) return n_own;
    const auto bounds = receive_halos(p, box, width, 0.0);  // as ghosts first, then made real
    counts_.remap_halo_points = halo_count_;
    p.id.resize(n_own);
    p.id.insert(p.id.end(), halo_count_, 0);
    std::vector<int> from;
    const auto [ids] = send(halo_send_, &from, std::vector<std::uint64_t>(p.id.begin(), p.id.begin() + n_own));
    std::copy(ids.begin(), ids.end(), p.id.begin() + static_cast<std::ptrdiff_t>(n_own));
    remap_rank_.assign(n_own, comm_->rank());
    for (std::size_t q = 0; q < from.size(); ++q) remap_rank_.insert(remap_rank_.end(), std::size_t(from[q]), int(q));
    gathered_ = gathered_within(bounds, box, width);
    p.n_real = p.x.size();
    p.ghost_source.clear();
    return n_own;
  }

  /// After add_remap_halo: a per-particle value, `width` numbers per particle of the local set, replaced on the
  /// other ranks' particles by their owners' (one exchange).
  void refresh_rows(std::vector<double>& v, std::size_t width) const {
    if (ranks() == 1) return;
    std::vector<std::vector<double>> out(static_cast<std::size_t>(ranks()));
    for (std::size_t q = 0; q < out.size(); ++q)
      for (const std::uint32_t a : halo_send_[q])
        out[q].insert(out[q].end(), v.begin() + static_cast<std::ptrdiff_t>(a * width),
                      v.begin() + static_cast<std::ptrdiff_t>((a + 1) * width));
    const auto in = exchange(out);
    require(in.size() == halo_count_ * width && v.size() >= (halo_first_ + halo_count_) * width,
            "the remap's refresh: the other ranks sent a value for each of their particles here");
    std::copy(in.begin(), in.end(), v.begin() + static_cast<std::ptrdiff_t>(halo_first_ * width));
  }

  /// Undoes add_remap_halo before a remap by owners that the particles gathered could not decide (every rank at
  /// once): the local set is the first n_own again, and the remap gathers half as far again from now on.
  template <bool E>
  void gather_farther(ParticleSet<D, E>& p, std::size_t n_own) {
    p.resize_all(n_own);
    p.n_real = n_own;
    remap_rank_.clear();
    gathered_ = {};
    owner_reach_in_h_ *= 1.5;
    ++counts_.remap_widenings;
  }

  /// After add_remap_halo: where the local set holds every particle of the run.
  const Gathered<D>& gathered() const { return gathered_; }

  /// After add_remap_halo: which rank keeps each new site, from the local set (this rank's own the first n_own),
  /// for sites within `reach` of an old particle.
  template <bool E>
  SiteOwners<D> site_owners(const ParticleSet<D, E>& p, const Box<D>& box, double reach) const {
    std::vector<int> rank = remap_rank_;
    rank.resize(p.n_real, comm_->rank());  // one rank: no halo
    return SiteOwners<D>(p.x, p.id, box, reach, std::move(rank), gathered_);
  }

  /// New identities for the real particles, after every rank's earlier ones and rank by rank (after a remap, whose
  /// ranks emitted the new particles of the sites each keeps: on one rank as the serial run numbers them).
  template <bool E>
  void renumber(ParticleSet<D, E>& p) const {
    std::uint64_t first = 0, mine = p.n_real;
    if (ranks() > 1) check(MPI_Exscan(&mine, &first, 1, MPI_UINT64_T, MPI_SUM, comm_->get()), "MPI_Exscan");
    if (comm_->rank() == 0) first = 0;
    const std::uint64_t total = sum(mine);
    p.next_id += first;
    p.renumber();
    p.next_id += total - first - mine;
  }

  /// Sends list q to rank q; returns what every rank sent here, in rank order, with the count from each when asked
  /// for (the remap by owners' partial sums).
  std::vector<double> exchange(const std::vector<std::vector<double>>& out, std::vector<int>* counts = nullptr) const {
    for (const auto& list : out) counts_.bytes_sent += list.size() * sizeof(double);
    return comm_->exchange(out, counts);
  }

  /// A reduction keyed by name: `rows` holds rows of a name (a whole number below 2^53, each at most once on a
  /// rank) and w values. Each name's keeper, the rank name mod P, adds the rows every rank sent for it (`add`), or
  /// takes their largest values, its own first and then the others' in rank order (complete_at_keepers), and each
  /// rank finds the result in place of its row's values. Two exchanges with the ranks that share a name, where
  /// gathering every rank's rows on every rank took P messages each way.
  void combine_by_name(std::vector<double>& rows, std::size_t w, bool add) const {
    if (ranks() == 1) return;  // its own rows: already complete
    const auto P = static_cast<std::size_t>(ranks());
    std::vector<std::size_t> names;
    std::vector<int> keepers;
    std::vector<double> values;
    for (std::size_t r = 0; r < rows.size(); r += 1 + w) {
      names.push_back(static_cast<std::size_t>(rows[r]));
      keepers.push_back(static_cast<int>(names.back() % P));
      values.insert(values.end(), rows.begin() + std::ptrdiff_t(r + 1), rows.begin() + std::ptrdiff_t(r + 1 + w));
    }
    complete_at_keepers(
        std::span<const std::size_t>(names), std::span<const int>(keepers), values, w, comm_->rank(), ranks(),
        [this](const std::vector<std::vector<double>>& out, std::vector<int>* counts) { return exchange(out, counts); },
        [w, add](double* into, const double* part) {
          for (std::size_t k = 0; k < w; ++k) into[k] = add ? into[k] + part[k] : std::max(into[k], part[k]);
        });
    for (std::size_t i = 0; i < names.size(); ++i)
      std::copy_n(values.begin() + std::ptrdiff_t(i * w), w, rows.begin() + std::ptrdiff_t(i * (1 + w) + 1));
  }

  /// Element-wise least (`least`) or largest values over the ranks, in one reduction: exact in any order.
  void extreme_in_place(std::span<double> values, bool least) const {
    if (ranks() > 1) comm_->reduce_in_place(values, least ? MPI_MIN : MPI_MAX);
  }

  /// Element-wise sums over the ranks (MPI's order: the last bits may depend on the rank count).
  void sum_in_place(std::span<double> values) const {
    if (ranks() > 1) comm_->sum_in_place(values);
  }

  /// Every rank's real particles on rank 0, in rank order (fields and identities; rates left out), and none on
  /// the others: for a measure that needs the whole set at once (an interface traced through the field, a profile
  /// written particle by particle), made by rank 0 and its figures sent to the others (broadcast).
  template <bool E>
  ParticleSet<D, E> gather_on_root(const ParticleSet<D, E>& p) const {
    if (ranks() == 1) {
      auto all = p;
      all.clear_ghosts();
      return all;
    }
    Lists to(static_cast<std::size_t>(ranks()));
    for (std::size_t a = 0; a < p.n_real; ++a) to[0].push_back(static_cast<std::uint32_t>(a));
    ParticleSet<D, E> all;
    const auto fields = [](auto& q) {
      if constexpr (E)
        return std::tie(q.m, q.x, q.v, q.h, q.rho, q.P, q.cs, q.frozen, q.id, q.u);
      else
        return std::tie(q.m, q.x, q.v, q.h, q.rho, q.P, q.cs, q.frozen, q.id);
    };
    detail::each_pair(fields(all), send_tied(fields(p), to), [](auto& f, auto& in) { f = std::move(in); });
    all.n_real = all.x.size();
    all.dv_dt.assign(all.n_real, Vec<D>::Zero());
    if constexpr (E) all.du_dt.assign(all.n_real, 0.0);
    all.next_id = p.next_id;
    return all;
  }

  /// Rank 0's values on every rank (the figures of a measure made there).
  void broadcast(std::span<double> values) const {
    if (ranks() > 1) comm_->broadcast(values);
  }

  /// Mass, momentum, angular momentum and energies over every rank's real particles, the same bits at any
  /// rank count (ExactSum).
  template <bool E>
  Conservation<D> totals(const ParticleSet<D, E>& p) const;

 private:
  using Lists = std::vector<std::vector<std::uint32_t>>;

  /// Appends the halos; returns every rank's bounds it chose them by (4 D numbers a box: lo, hi of its
  /// particles, lo, hi of their reaches; 2^halo_piece_levels boxes a rank where h_max > 0, else one). h_max > 0:
  /// a particle reaches width h / h_max (h_max: every rank's largest h); else every particle reaches `width`.
  template <bool E>
  std::vector<double> receive_halos(ParticleSet<D, E>& p, const Box<D>& box, double width, double h_max);

  /// The other ranks whose boxes (`mine`: this rank's, 4 D numbers each) a rank tests its particles against, and
  /// their boxes, as many each as this rank's: every rank up to DecompositionParams::boxes_to_all_up_to ranks
  /// (one all-gather; `all` holds every rank's boxes); beyond, where a rank has more than one box, those whose box
  /// round their boxes meets this rank's (an all-gather of those, in `all`, and Comm::trade).
  struct OthersBoxes {
    std::vector<double> all;     ///< every rank's boxes, or every rank's one box round them
    std::vector<int> rank;       ///< the other ranks, ascending
    std::vector<double> traded;  ///< the traded ranks' boxes, after one another (empty where all holds them)
    /// rank[i]'s first box
    const double* boxes(std::size_t i, std::size_t per_rank) const {
      return traded.empty() ? &all[per_rank * static_cast<std::size_t>(rank[i])] : &traded[per_rank * i];
    }
  };
  OthersBoxes boxes_of_others(const std::vector<double>& mine, const Box<D>& box) const {
    constexpr std::size_t B = 4 * D;
    const std::size_t per_rank = mine.size();
    const int me = comm_->rank();
    OthersBoxes o;
    if (per_rank > B && ranks() > params_.boxes_to_all_up_to) {
      const auto hull = detail::hull_of<D>(mine);
      o.all = comm_->all_gather(std::span<const double>(hull));
      for (int q = 0; q < ranks(); ++q)
        if (q != me && boxes_meet<D>(hull.data(), &o.all[B * static_cast<std::size_t>(q)], box)) o.rank.push_back(q);
      o.traded = comm_->trade(std::span<const int>(o.rank), std::span<const double>(mine));
      return o;
    }
    o.all = comm_->all_gather(std::span<const double>(mine));
    for (int q = 0; q < ranks(); ++q)
      if (q != me) o.rank.push_back(q);
    return o;
  }

  /// Where the local set holds every particle, after gathering the others' within `width` of this rank's own:
  /// the own particles' bounds widened by it, unbounded on an axis where they pass every rank's particles' bounds
  /// or a periodic box's length. `bounds`: every rank's, as receive_halos returns them.
  Gathered<D> gathered_within(const std::vector<double>& bounds, const Box<D>& box, double width) const {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const double* mine = &bounds[4 * D * static_cast<std::size_t>(comm_->rank())];
    Gathered<D> g;
    for (int k = 0; k < D; ++k) {
      double lo_all = inf, hi_all = -inf;
      for (std::size_t q = 0; q < bounds.size(); q += 4 * D)
        lo_all = std::min(lo_all, bounds[q + k]), hi_all = std::max(hi_all, bounds[q + D + k]);
      const double lo = mine[k] - width, hi = mine[D + k] + width;
      if (box.periodic(k)) {
        const double L = box.hi[k] - box.lo[k];
        if (!(hi - lo >= L)) g.lo[k] = lo, g.hi[k] = hi, g.period[k] = L;
      } else {
        if (lo > lo_all) g.lo[k] = lo;
        if (hi < hi_all) g.hi[k] = hi;
      }
    }
    return g;
  }

  template <class T>
  static std::vector<T> gather(const std::vector<T>& f, const std::vector<std::uint32_t>& which) {
    std::vector<T> g;
    g.reserve(which.size());
    for (auto a : which) g.push_back(f[a]);
    return g;
  }
  template <class T>
  static std::vector<T> concat(std::vector<T> a, const std::vector<T>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  }

  /// The fields f... of every particle a of lists[q], to rank q, in one message per rank (particle by particle,
  /// each entry in whole words: detail::words); what the other ranks sent here, in rank order, field by field
  /// (with how many particles each sent, when asked for).
  template <class... T>
  std::tuple<std::vector<T>...> send(const Lists& lists, std::vector<int>* from, const std::vector<T>&... f) const {
    constexpr std::size_t stride = (detail::words<T> + ...);
    std::vector<std::vector<std::uint64_t>> out(lists.size());
    for (std::size_t q = 0; q < lists.size(); ++q) {
      out[q].resize(lists[q].size() * stride);
      std::uint64_t* w = out[q].data();
      for (auto a : lists[q]) ((w += detail::store(f[a], w)), ...);
      counts_.bytes_sent += out[q].size() * sizeof(std::uint64_t);
    }
    const auto in = comm_->exchange(out, from);
    if (from)
      for (auto& n : *from) n /= static_cast<int>(stride);
    const std::size_t n = in.size() / stride;
    std::tuple<std::vector<T>...> got{std::vector<T>(n)...};
    const std::uint64_t* r = in.data();
    for (std::size_t i = 0; i < n; ++i)
      std::apply([&](auto&... field) { ((r += detail::load(field[i], r)), ...); }, got);
    return got;
  }
  /// send of a tuple of fields (std::tie).
  template <class Fields>
  auto send_tied(const Fields& fields, const Lists& lists) const {
    return std::apply([&](const auto&... f) { return send(lists, nullptr, f...); }, fields);
  }
  /// The fields of a set with internal energy that move with a particle beside the others (none without).
  template <bool E>
  static auto energy_fields(ParticleSet<D, E>& p) {
    if constexpr (E)
      return std::tie(p.u, p.du_dt);
    else
      return std::tuple<>();
  }

  std::shared_ptr<Comm> comm_;  // shared: a Simulation copies its terms
  DecompositionParams params_;
  double owner_reach_in_h_;  ///< where the next remap by owners starts gathering, in the largest h
  std::shared_ptr<Partitioner<D>> partitioner_;
  bool due_ = true;  ///< the first balance partitions
  int steps_ = 0;
  Lists halo_send_;  ///< per rank: the real particles whose halos it holds, in the order it holds them
  std::size_t halo_first_ = 0, halo_count_ = 0;
  std::vector<int> remap_rank_;  ///< after add_remap_halo: the rank that owns each particle of the local set
  Gathered<D> gathered_;         ///< after add_remap_halo: where the local set holds every particle
  mutable ExchangeCounts counts_;
};

template <int D>
template <bool E>
std::vector<double> Decomposition<D>::receive_halos(ParticleSet<D, E>& p, const Box<D>& box, double width,
                                                    double h_max) {
  // A pair interacts within support max(h_a, h_b) (times the search margin), so particle a reaches
  // R_a = width h_a / h_max: each rank's boxes, of its particles and of their reaches, go to every rank that may
  // need them (boxes_of_others); a particle goes to a rank one of whose reaches holds it or one of whose boxes it
  // reaches. Without h_max, R = width, and a rank is one box (Gathered: the local set then holds every particle
  // within width of its bounds).
  const auto reach = [&](std::size_t a) { return h_max > 0.0 ? width * p.h[a] / h_max : width; };
  const int levels = h_max > 0.0 ? params_.halo_piece_levels : 0;
  const auto pieces = detail::split_into_pieces<D>(p.x, p.n_real, reach, levels);
  const auto& mine = pieces.bounds;
  const std::size_t per_rank = mine.size();
  constexpr std::size_t B = 4 * D;  // numbers a box
  using Map = Eigen::Map<const Vec<D>>;
  const auto others = boxes_of_others(mine, box);
  counts_.halo_partners = others.rank.size();
  const std::size_t K = per_rank / B;
  halo_send_.assign(static_cast<std::size_t>(ranks()), {});
  std::vector<const double*> near;  // of each of this rank's pieces, rank q's boxes near it
  std::vector<std::size_t> near_first(K + 1);
  for (std::size_t o = 0; o < others.rank.size(); ++o) {
    const int q = others.rank[o];
    const double* theirs = others.boxes(o, per_rank);
    // the boxes first, so that a rank looks at its particles only for the ranks and boxes near them: O(P K^2 + k
    // n), not O(P n)
    near.clear();
    for (std::size_t l = 0; l < K; ++l) {
      const double* m = &mine[l * B];
      near_first[l] = near.size();
      for (std::size_t i = 0; i < per_rank; i += B)
        if (boxes_meet<D>(m, theirs + i, box)) near.push_back(theirs + i);
    }
    near_first[K] = near.size();
    if (near.empty()) continue;
    for (std::size_t a = 0; a < p.n_real; ++a) {
      const Vec<D> r = Vec<D>::Constant(reach(a));
      const auto l = pieces.piece[a];
      for (std::size_t i = near_first[l]; i < near_first[l + 1]; ++i)
        if (reaches<D>(p.x[a], Map(near[i] + 2 * D), Map(near[i] + 3 * D), box, width) ||
            reaches<D>(p.x[a], Map(near[i]) - r, Map(near[i] + D) + r, box, width)) {
          halo_send_[static_cast<std::size_t>(q)].push_back(std::uint32_t(a));
          break;
        }
    }
  }
  const auto fields = [&] {
    if constexpr (E)
      return std::tie(p.x, p.v, p.m, p.h, p.rho, p.P, p.cs, p.frozen, p.u);
    else
      return std::tie(p.x, p.v, p.m, p.h, p.rho, p.P, p.cs, p.frozen);
  }();
  halo_first_ = p.n_real;
  detail::each_pair(fields, send_tied(fields, halo_send_), [&](auto& f, const auto& values) {
    f.resize(halo_first_);
    f.insert(f.end(), values.begin(), values.end());
  });
  halo_count_ = p.x.size() - halo_first_;
  p.dv_dt.resize(p.x.size(), Vec<D>::Zero());
  if constexpr (E) p.du_dt.resize(p.x.size(), 0.0);
  for (std::size_t g = 0; g < halo_count_; ++g) p.ghost_source.push_back(std::uint32_t(halo_first_ + g));
  return others.all;
}

template <int D>
template <bool E>
Conservation<D> Decomposition<D>::totals(const ParticleSet<D, E>& p) const {
  // one scale for all ranks: the largest magnitude of each sum's terms
  constexpr int n_sums = 4 + D;
  std::vector<std::vector<double>> terms(n_sums);
  for (std::size_t a = 0; a < p.n_real; ++a) {
    terms[0].push_back(p.m[a]);
    for (int k = 0; k < D; ++k) terms[1 + k].push_back(p.m[a] * p.v[a][k]);
    if constexpr (D >= 2) terms[1 + D].push_back(p.m[a] * (p.x[a][0] * p.v[a][1] - p.x[a][1] * p.v[a][0]));
    terms[2 + D].push_back(0.5 * p.m[a] * p.v[a].squaredNorm());
    if constexpr (E) terms[3 + D].push_back(p.m[a] * p.u[a]);
  }
  // two reductions for all the sums: their largest terms, then their limbs
  std::array<double, n_sums> largest{};
  for (int i = 0; i < n_sums; ++i)
    for (double t : terms[i]) largest[i] = std::max(largest[i], std::abs(t));
  if (ranks() > 1) comm_->reduce_in_place(std::span<double>(largest), MPI_MAX);
  constexpr std::size_t L = ExactSum::kLimbs;
  std::vector<ExactSum> partial;
  std::vector<std::int64_t> limbs;
  for (int i = 0; i < n_sums; ++i) {
    ExactSum& s = partial.emplace_back(ExactSum::exponent_for(largest[i]));
    for (double t : terms[i]) s.add(t);
    limbs.insert(limbs.end(), s.limbs().begin(), s.limbs().end());
  }
  if (ranks() > 1) comm_->sum_in_place(std::span<std::int64_t>(limbs));
  std::vector<double> sums(n_sums);
  for (int i = 0; i < n_sums; ++i) {
    std::copy_n(limbs.begin() + static_cast<std::ptrdiff_t>(L * i), L, partial[i].limbs().begin());
    sums[i] = partial[i].value();
  }
  Conservation<D> c;
  c.mass = sums[0];
  for (int k = 0; k < D; ++k) c.momentum[k] = sums[1 + k];
  c.angular_momentum = sums[1 + D];
  c.kinetic = sums[2 + D];
  c.thermal = sums[3 + D];
  return c;
}

}  // namespace rsph::mpi
