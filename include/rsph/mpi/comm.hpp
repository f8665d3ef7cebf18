#pragma once
// Thin RAII wrappers over MPI's C API: a communicator the library is handed (it never initialises MPI),
// typed reductions, and the one exchange pattern the decomposition uses, a sparse all-to-all of typed spans.
// Needs an MPI-3 implementation; link rsph::mpi.
#include "rsph/core/errors.hpp"
#include "rsph/core/exact_sum.hpp"

#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace rsph::mpi {

/// The MPI datatype of T; a type without one fails here with this sentence.
template <class T>
MPI_Datatype datatype() {
  if constexpr (std::is_same_v<T, double>)
    return MPI_DOUBLE;
  else if constexpr (std::is_same_v<T, float>)
    return MPI_FLOAT;
  else if constexpr (std::is_same_v<T, int>)
    return MPI_INT;
  else if constexpr (std::is_same_v<T, std::int64_t>)
    return MPI_INT64_T;
  else if constexpr (std::is_same_v<T, std::uint64_t>)
    return MPI_UINT64_T;
  else if constexpr (std::is_same_v<T, std::uint32_t>)
    return MPI_UINT32_T;
  else if constexpr (std::is_same_v<T, std::uint8_t>)
    return MPI_UINT8_T;
  else if constexpr (std::is_same_v<T, char>)
    return MPI_CHAR;
  else
    static_assert(sizeof(T) == 0, "this type has no MPI datatype: send its scalar components instead");
}

/// Throws when an MPI call failed (a duplicated communicator returns errors instead of aborting).
inline void check(int rc, const char* what) {
  if (rc == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int len = 0;
  MPI_Error_string(rc, text, &len);
  throw NumericalError(std::string("MPI: ") + what + " failed: " + std::string(text, static_cast<std::size_t>(len)));
}

/// A communicator: either borrowed (the caller's, left alone) or duplicated and freed on destruction, so that
/// the library's messages never mix with the application's. Move-only.
class Comm {
 public:
  /// Borrows `c`; the caller keeps it alive.
  explicit Comm(MPI_Comm c = MPI_COMM_WORLD) : c_(c) {}
  /// A private duplicate of `c`, freed with this object.
  static Comm duplicate(MPI_Comm c) {
    Comm d;
    check(MPI_Comm_dup(c, &d.c_), "MPI_Comm_dup");
    d.owned_ = true;
    check(MPI_Comm_set_errhandler(d.c_, MPI_ERRORS_RETURN), "MPI_Comm_set_errhandler");
    return d;
  }
  Comm(const Comm&) = delete;
  Comm& operator=(const Comm&) = delete;
  Comm(Comm&& o) noexcept
      : c_(o.c_),
        owned_(std::exchange(o.owned_, false)),
        seconds_(o.seconds_),
        exchanges_(o.exchanges_),
        messages_(o.messages_),
        collectives_(o.collectives_) {}
  Comm& operator=(Comm&& o) noexcept {
    if (this != &o) {
      release();
      c_ = o.c_;
      owned_ = std::exchange(o.owned_, false);
    }
    return *this;
  }
  ~Comm() { release(); }

  MPI_Comm get() const { return c_; }
  int rank() const {
    int r = 0;
    MPI_Comm_rank(c_, &r);
    return r;
  }
  int size() const {
    int s = 1;
    MPI_Comm_size(c_, &s);
    return s;
  }

  /// Wall seconds spent in this communicator's calls so far: the messages, and the waits for other ranks.
  double seconds() const { return seconds_; }
  /// The exchanges made so far, and the messages this rank sent in them (one to each rank it had data for).
  std::uint64_t exchanges() const { return exchanges_; }
  std::uint64_t messages() const { return messages_; }
  /// The reductions and all-gathers made so far (each a latency of about log2 P messages).
  std::uint64_t collectives() const { return collectives_; }

  template <class T>
  T all_reduce(T value, MPI_Op op) const {
    const Timer t(seconds_);
    T out{};
    ++collectives_;
    check(MPI_Allreduce(&value, &out, 1, datatype<T>(), op, c_), "MPI_Allreduce");
    return out;
  }
  double min(double v) const { return all_reduce(v, MPI_MIN); }
  double max(double v) const { return all_reduce(v, MPI_MAX); }
  std::uint64_t sum(std::uint64_t v) const { return all_reduce(v, MPI_SUM); }
  bool any(bool v) const { return all_reduce(int(v), MPI_LOR) != 0; }
  bool all(bool v) const { return all_reduce(int(v), MPI_LAND) != 0; }

  /// Element-wise reduction (MPI_SUM, MPI_MAX, ...) of a span in place, in one message.
  template <class T>
  void reduce_in_place(std::span<T> values, MPI_Op op) const {
    const Timer t(seconds_);
    ++collectives_;
    check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), datatype<T>(), op, c_),
          "MPI_Allreduce");
  }
  /// Element-wise sums of a span in place (integers: exact in any order).
  template <class T>
  void sum_in_place(std::span<T> values) const {
    reduce_in_place(values, MPI_SUM);
  }

  /// Adds the ranks' partial sums, which must share their exponent; every rank gets the same bits.
  void sum_in_place(ExactSum& s) const { sum_in_place(std::span<std::int64_t>(s.limbs())); }

  /// One value from every rank, in rank order.
  template <class T>
  std::vector<T> all_gather(std::span<const T> mine) const {
    const Timer t(seconds_);
    std::vector<T> out(mine.size() * static_cast<std::size_t>(size()));
    ++collectives_;
    check(MPI_Allgather(mine.data(), static_cast<int>(mine.size()), datatype<T>(), out.data(),
                        static_cast<int>(mine.size()), datatype<T>(), c_),
          "MPI_Allgather");
    return out;
  }

  /// All-to-all of variable counts: send[q] goes to rank q; returns what each rank sent here, concatenated in
  /// rank order, with `counts` (per source rank) when asked for. Sparse: only ranks with something to send send
  /// a message, so its cost grows with the ranks a rank trades with and log P, not with P. One reduction
  /// (MPI_Reduce_scatter_block) tells each rank how many will come; it also keeps exchanges apart, since no rank
  /// sends for the next one before every rank has entered it, and so has received all of this one.
  template <class T>
  std::vector<T> exchange(const std::vector<std::vector<T>>& send, std::vector<int>* counts = nullptr) const {
    const Timer t(seconds_);
    const int P = size(), me = rank();
    require(send.size() == static_cast<std::size_t>(P), "MPI exchange: one list per rank");
    std::vector<int> sends_to(static_cast<std::size_t>(P), 0);
    for (int q = 0; q < P; ++q) sends_to[std::size_t(q)] = q != me && !send[std::size_t(q)].empty();
    int incoming = 0;
    check(MPI_Reduce_scatter_block(sends_to.data(), &incoming, 1, MPI_INT, MPI_SUM, c_), "MPI_Reduce_scatter_block");
    constexpr int tag = 4242;  // this wrapper's only point-to-point messages
    std::vector<MPI_Request> sent;
    for (int q = 0; q < P; ++q) {
      const auto& out = send[std::size_t(q)];
      if (!sends_to[std::size_t(q)]) continue;
      require(out.size() <= std::size_t(std::numeric_limits<int>::max()), "MPI exchange: a message too long");
      sent.emplace_back();
      check(MPI_Isend(out.data(), static_cast<int>(out.size()), datatype<T>(), q, tag, c_, &sent.back()), "MPI_Isend");
    }
    std::vector<std::vector<T>> from(static_cast<std::size_t>(P));
    for (int i = 0; i < incoming; ++i) {
      MPI_Status status;
      check(MPI_Probe(MPI_ANY_SOURCE, tag, c_, &status), "MPI_Probe");
      int n = 0;
      check(MPI_Get_count(&status, datatype<T>(), &n), "MPI_Get_count");
      auto& in = from[static_cast<std::size_t>(status.MPI_SOURCE)];
      in.resize(static_cast<std::size_t>(n));
      check(MPI_Recv(in.data(), n, datatype<T>(), status.MPI_SOURCE, tag, c_, MPI_STATUS_IGNORE), "MPI_Recv");
    }
    check(MPI_Waitall(static_cast<int>(sent.size()), sent.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
    ++exchanges_;
    messages_ += sent.size();
    from[static_cast<std::size_t>(me)] = send[static_cast<std::size_t>(me)];
    std::vector<T> recv;
    if (counts) counts->assign(static_cast<std::size_t>(P), 0);
    for (int q = 0; q < P; ++q) {
      const auto& in = from[static_cast<std::size_t>(q)];
      recv.insert(recv.end(), in.begin(), in.end());
      if (counts) (*counts)[static_cast<std::size_t>(q)] = static_cast<int>(in.size());
    }
    return recv;
  }

  /// The same `mine` to each rank of `partners` (ascending), and theirs back, where every partner sends as many
  /// values and names this rank among its partners, so that no reduction need say what will come: one message
  /// each way a partner. Returns the partners' values in their order. Its own tag keeps it apart from `exchange`.
  template <class T>
  std::vector<T> trade(std::span<const int> partners, std::span<const T> mine) const {
    const Timer t(seconds_);
    constexpr int tag = 4243;
    const std::size_t n = mine.size();
    require(n <= std::size_t(std::numeric_limits<int>::max()), "MPI trade: a message too long");
    std::vector<T> in(partners.size() * n);
    std::vector<MPI_Request> requests(2 * partners.size());
    for (std::size_t i = 0; i < partners.size(); ++i) {
      check(MPI_Irecv(in.data() + i * n, static_cast<int>(n), datatype<T>(), partners[i], tag, c_, &requests[2 * i]),
            "MPI_Irecv");
      check(MPI_Isend(mine.data(), static_cast<int>(n), datatype<T>(), partners[i], tag, c_, &requests[2 * i + 1]),
            "MPI_Isend");
    }
    check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
    ++exchanges_;
    messages_ += partners.size();
    return in;
  }

  /// Rank `root`'s text, on every rank.
  std::string broadcast(std::string text, int root = 0) const {
    const Timer t(seconds_);
    auto n = static_cast<std::uint64_t>(text.size());
    check(MPI_Bcast(&n, 1, MPI_UINT64_T, root, c_), "MPI_Bcast");
    text.resize(static_cast<std::size_t>(n));
    check(MPI_Bcast(text.data(), static_cast<int>(n), MPI_CHAR, root, c_), "MPI_Bcast");
    return text;
  }

  /// Rank `root`'s values, on every rank.
  void broadcast(std::span<double> values, int root = 0) const {
    const Timer t(seconds_);
    ++collectives_;
    check(MPI_Bcast(values.data(), static_cast<int>(values.size()), MPI_DOUBLE, root, c_), "MPI_Bcast");
  }

  void barrier() const {
    const Timer t(seconds_);
    check(MPI_Barrier(c_), "MPI_Barrier");
  }

 private:
  /// Adds the wall time of its scope to a total.
  struct Timer {
    double& total;
    double start = MPI_Wtime();
    explicit Timer(double& t) : total(t) {}
    ~Timer() { total += MPI_Wtime() - start; }
    Timer(const Timer&) = delete;
    Timer& operator=(const Timer&) = delete;
  };
  void release() {
    if (owned_) MPI_Comm_free(&c_);
    owned_ = false;
  }
  MPI_Comm c_;
  bool owned_ = false;
  mutable double seconds_ = 0.0;
  mutable std::uint64_t exchanges_ = 0, messages_ = 0, collectives_ = 0;
};

}  // namespace rsph::mpi
