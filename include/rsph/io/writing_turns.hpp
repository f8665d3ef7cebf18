#pragma once
// Processes that write one file together (the ranks of a decomposed run, mpi::FileTurns): where each one's rows
// begin, the sums of their totals, whether all succeeded, and how they reach the file: in turns, one after
// another, each opening it alone (serial HDF5), or together, every one opening it at once and writing its rows in
// one collective call (parallel HDF5 through MPI-IO). OneWriter is the single process of a serial run.
#include <hdf5.h>

#include <algorithm>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace rsph::io {

/// How a process opens a file to read: alone (the default), or together with the other ranks of a
/// communicator, opened at once through MPI-IO (parallel HDF5: mpi::FileTurns::reading()) and each field's rows
/// read in one collective call, which MPI-IO may gather into few large reads. Together, every rank must read the
/// same fields in the same order.
struct Reading {
  hid_t file_access = H5P_DEFAULT;
  hid_t transfer = H5P_DEFAULT;
};

template <class T>
concept WritingTurns = requires(const T& t, std::vector<std::uint64_t> counts, std::vector<double> reals,
                                std::vector<std::int64_t> integers, void (*write_part)()) {
  { t.part() } -> std::convertible_to<std::size_t>;
  { t.first_rows(counts) } -> std::same_as<std::vector<std::uint64_t>>;  ///< sum of the counts of earlier parts
  { t.total_rows(counts) } -> std::same_as<std::vector<std::uint64_t>>;
  { t.sum(reals) } -> std::same_as<std::vector<double>>;
  { t.sum(integers) } -> std::same_as<std::vector<std::int64_t>>;
  { t.all(true) } -> std::same_as<bool>;
  t.in_turn(write_part);                       ///< each part after the first, one after another
  { t.together() } -> std::same_as<bool>;      ///< every part creates the file and writes at once instead
  { t.file_access() } -> std::same_as<hid_t>;  ///< HDF5's file access list for creating the file
  { t.transfer() } -> std::same_as<hid_t>;     ///< and its transfer list for writing data
};

/// One process writing alone: its rows are all the rows, and it has no turns to wait for.
struct OneWriter {
  std::size_t part() const { return 0; }
  std::vector<std::uint64_t> first_rows(std::vector<std::uint64_t> counts) const {
    return std::vector<std::uint64_t>(counts.size(), 0);
  }
  std::vector<std::uint64_t> total_rows(std::vector<std::uint64_t> counts) const { return counts; }
  template <class T>
  std::vector<T> sum(std::vector<T> values) const {
    return values;
  }
  bool all(bool ok) const { return ok; }
  template <class Write>
  void in_turn(Write&&) const {}
  bool together() const { return false; }
  hid_t file_access() const { return H5P_DEFAULT; }
  hid_t transfer() const { return H5P_DEFAULT; }
};

static_assert(WritingTurns<OneWriter>);

/// Writes `n` rows of `cols` numbers each (0: a one-dimensional dataset) of type `type` from `values` into rows
/// `first` .. `first` + n of dataset `set`, with transfer list `transfer`. A part without rows writes an empty
/// selection, so that a collective transfer sees every part; an empty dataset is left alone by all.
inline bool write_slab(hid_t set, hid_t type, hsize_t first, hsize_t n, hsize_t cols, const void* values,
                       hid_t transfer) {
  const int rank = cols == 0 ? 1 : 2;
  const hsize_t start[2] = {first, 0}, count[2] = {n, cols};
  const hid_t whole = H5Dget_space(set);
  if (whole >= 0 && H5Sget_simple_extent_npoints(whole) == 0) return H5Sclose(whole) >= 0 && n == 0;
  const hid_t memory = H5Screate_simple(rank, count, nullptr);
  bool ok = whole >= 0 && memory >= 0;
  if (n > 0)
    ok = ok && H5Sselect_hyperslab(whole, H5S_SELECT_SET, start, nullptr, count, nullptr) >= 0;
  else
    ok = ok && H5Sselect_none(whole) >= 0 && H5Sselect_none(memory) >= 0;
  ok = ok && H5Dwrite(set, type, memory, whole, transfer, values) >= 0;
  if (memory >= 0) H5Sclose(memory);
  if (whole >= 0) H5Sclose(whole);
  return ok;
}

/// One file written by every part of `turns` at the temporary path `tmp`: part 0 creates it (create(), with its
/// own rows), the others add theirs in turn (add()), or, `together`, every part calls create() at once; then part 0
/// puts it in place (commit()). Each returns false where it failed. Every part calls it; if one failed, all throw
/// `failure` (and part 0 removes `tmp`), and no part goes on before the file is in place.
template <WritingTurns Turns, class Create, class Add, class Commit>
void write_in_turns(const Turns& turns, const std::filesystem::path& tmp, Create&& create, Add&& add, Commit&& commit,
                    const std::string& failure) {
  bool ok = true;
  if (turns.together()) {
    ok = create();
  } else {
    ok = turns.part() != 0 || create();
    if (turns.all(ok)) turns.in_turn([&] { ok = add(); });
  }
  ok = turns.all(ok);
  if (ok && turns.part() == 0) ok = commit();
  if (!turns.all(ok)) {
    std::error_code ignored;
    if (turns.part() == 0) std::filesystem::remove(tmp, ignored);
    throw std::runtime_error(failure);
  }
}

}  // namespace rsph::io
