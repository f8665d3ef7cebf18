#pragma once
// Processes that write one file together (the ranks of a decomposed run, mpi::FileTurns): where each one's rows
// begin, the sums of their totals, whether all succeeded, and their turns at the file. OneWriter is the single
// process of a serial run.
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace rsph::io {

template <class T>
concept WritingTurns = requires(const T& t, std::vector<std::uint64_t> counts, std::vector<double> reals,
                                std::vector<std::int64_t> integers, void (*write_part)()) {
  { t.part() } -> std::convertible_to<std::size_t>;
  { t.first_rows(counts) } -> std::same_as<std::vector<std::uint64_t>>;  ///< sum of the counts of earlier parts
  { t.total_rows(counts) } -> std::same_as<std::vector<std::uint64_t>>;
  { t.sum(reals) } -> std::same_as<std::vector<double>>;
  { t.sum(integers) } -> std::same_as<std::vector<std::int64_t>>;
  { t.all(true) } -> std::same_as<bool>;
  t.in_turn(write_part);  ///< each part after the first, one after another
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
};

static_assert(WritingTurns<OneWriter>);

/// One file written by every part of `turns` at the temporary path `tmp`: part 0 creates it (create(), with its
/// own rows), the others add theirs in turn (add()), and part 0 puts it in place (commit()); each returns false
/// where it failed. Every part calls it; if one failed, all throw `failure` (and part 0 removes `tmp`), and no part
/// goes on before the file is in place.
template <WritingTurns Turns, class Create, class Add, class Commit>
void write_in_turns(const Turns& turns, const std::filesystem::path& tmp, Create&& create, Add&& add, Commit&& commit,
                    const std::string& failure) {
  bool ok = turns.part() != 0 || create();
  if (turns.all(ok)) turns.in_turn([&] { ok = add(); });
  ok = turns.all(ok);
  if (ok && turns.part() == 0) ok = commit();
  if (!turns.all(ok)) {
    std::error_code ignored;
    if (turns.part() == 0) std::filesystem::remove(tmp, ignored);
    throw std::runtime_error(failure);
  }
}

}  // namespace rsph::io
