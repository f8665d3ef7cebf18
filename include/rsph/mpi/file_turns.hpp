#pragma once
// The ranks of a communicator writing one file together, a checkpoint or a snapshot (io::WritingTurns): the
// offsets of their rows, the sums of their totals, and their turns at the file, one rank after another, so that
// the file stays in the serial layout with the serial HDF5 library and each rank holds only its own particles.
// Link rsph::mpi and rsph::io.
#include "rsph/io/writing_turns.hpp"
#include "rsph/mpi/comm.hpp"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph::mpi {

class FileTurns {
 public:
  explicit FileTurns(const Comm& comm) : comm_(comm) {}

  std::size_t part() const { return static_cast<std::size_t>(comm_.rank()); }

  /// Per field: the rows of the ranks before this one.
  std::vector<std::uint64_t> first_rows(std::vector<std::uint64_t> counts) const {
    std::vector<std::uint64_t> first(counts.size(), 0);
    if (!counts.empty())
      check(
          MPI_Exscan(counts.data(), first.data(), static_cast<int>(counts.size()), MPI_UINT64_T, MPI_SUM, comm_.get()),
          "MPI_Exscan");
    if (comm_.rank() == 0) std::fill(first.begin(), first.end(), 0);  // MPI leaves rank 0's undefined
    return first;
  }
  /// Per field: the rows of every rank.
  std::vector<std::uint64_t> total_rows(std::vector<std::uint64_t> counts) const {
    comm_.sum_in_place(std::span<std::uint64_t>(counts));
    return counts;
  }
  template <class T>
  std::vector<T> sum(std::vector<T> values) const {
    comm_.sum_in_place(std::span<T>(values));
    return values;
  }
  bool all(bool ok) const { return comm_.all(ok); }

  /// write() on every rank after the first, one after another.
  template <class Write>
  void in_turn(Write&& write) const {
    for (int r = 1; r < comm_.size(); ++r) {
      if (comm_.rank() == r) write();
      comm_.barrier();
    }
  }

 private:
  const Comm& comm_;
};

static_assert(io::WritingTurns<FileTurns>);

}  // namespace rsph::mpi
