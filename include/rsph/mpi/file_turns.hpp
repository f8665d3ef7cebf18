#pragma once
// The ranks of a communicator writing one file together, a checkpoint or a snapshot (io::WritingTurns): the
// offsets of their rows, the sums of their totals, and how they reach the file, so that it stays in the serial
// layout and each rank holds only its own particles.
// - Together (with parallel HDF5, the default where the HDF5 linked is parallel): every rank creates the file
//   through MPI-IO and writes its rows into each dataset in one collective call.
// - In turns (with the serial HDF5 library): rank 0 creates the file, the others add their rows one after
//   another.
// Link rsph::mpi and rsph::io.
#include "rsph/io/writing_turns.hpp"
#include "rsph/mpi/comm.hpp"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph::mpi {

/// Whether the HDF5 linked can write one file from many ranks at once (parallel HDF5).
inline constexpr bool parallel_hdf5 =
#ifdef H5_HAVE_PARALLEL
    true;
#else
    false;
#endif

class FileTurns {
 public:
  /// The ranks of `comm`, writing together where `together` (and the HDF5 linked is parallel), else in turns.
  explicit FileTurns(const Comm& comm, bool together = parallel_hdf5) : comm_(comm) {
    if (!together) return;
#ifdef H5_HAVE_PARALLEL
    access_ = H5Pcreate(H5P_FILE_ACCESS);
    transfer_ = H5Pcreate(H5P_DATASET_XFER);
    if (access_ < 0 || transfer_ < 0 || H5Pset_fapl_mpio(access_, comm.get(), MPI_INFO_NULL) < 0 ||
        H5Pset_dxpl_mpio(transfer_, H5FD_MPIO_COLLECTIVE) < 0)
      throw NumericalError("parallel HDF5: cannot set up MPI-IO for writing together");
#else
    throw InputError("writing one file together needs parallel HDF5, and the HDF5 linked is serial");
#endif
  }
  ~FileTurns() {
    if (access_ != H5P_DEFAULT) H5Pclose(access_);
    if (transfer_ != H5P_DEFAULT) H5Pclose(transfer_);
  }
  FileTurns(const FileTurns&) = delete;
  FileTurns& operator=(const FileTurns&) = delete;

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

  /// write() on every rank after the first, one after another (in turns).
  template <class Write>
  void in_turn(Write&& write) const {
    for (int r = 1; r < comm_.size(); ++r) {
      if (comm_.rank() == r) write();
      comm_.barrier();
    }
  }

  bool together() const { return access_ != H5P_DEFAULT; }
  /// How the ranks read a checkpoint: together where they write together, else each alone.
  io::Reading reading() const { return {access_, transfer_}; }
  hid_t file_access() const { return access_; }
  hid_t transfer() const { return transfer_; }

 private:
  const Comm& comm_;
  hid_t access_ = H5P_DEFAULT, transfer_ = H5P_DEFAULT;
};

static_assert(io::WritingTurns<FileTurns>);

}  // namespace rsph::mpi
