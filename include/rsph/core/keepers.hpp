#pragma once
// Values of named items made complete over the ranks by each name's keeper (the remap's new cells, kept by the
// owner of their site; the consistent-gradient solve's pieces, by their name mod P): every rank that holds a name
// sends its part to the keeper, which combines them, its own first and then the others' in rank order, and answers
// each rank that sent one. Free of MPI: the sparse exchange is handed in (Comm::exchange, RankPart::exchange).
#include "rsph/core/errors.hpp"
#include "rsph/core/slot_map.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace rsph {

/// The names kept here that only other ranks held, after complete_at_keepers: the names and their complete values.
struct KeptElsewhereTouched {
  std::vector<std::size_t> name;
  std::vector<double> values;
};

/// Values of named items (item i: name[i], a whole number below 2^53, at most once on a rank; its keeper keeper[i];
/// its numbers values[i w, (i + 1) w)) made complete over the ranks: each name's keeper combines every rank's part
/// into its own, its own first and then the others' in rank order (`combine(into, part)`, w numbers each), and
/// sends the result back to every rank that sent a part, which takes it in place of its own. Every rank that holds
/// a name then holds the same numbers for it. Two exchanges (`exchange(out, counts)`: out[q] to rank q; what came,
/// in rank order, with how many numbers from each). Returns the names kept here that only others held, with their
/// complete values.
template <class Exchange, class Combine>
KeptElsewhereTouched complete_at_keepers(std::span<const std::size_t> name, std::span<const int> keeper,
                                         std::vector<double>& values, std::size_t w, int rank, int ranks,
                                         Exchange&& exchange, Combine&& combine) {
  const auto P = static_cast<std::size_t>(ranks);
  SlotMap mine;  // the names kept here that this rank holds: name -> i
  std::vector<std::vector<double>> out(P);
  std::vector<std::vector<std::uint32_t>> sent(P);  // per keeper: the names whose parts went there, in order
  for (std::size_t i = 0; i < name.size(); ++i) {
    const auto q = static_cast<std::size_t>(keeper[i]);
    if (keeper[i] == rank) {
      mine.find_or_insert(name[i], static_cast<std::uint32_t>(i));
      continue;
    }
    out[q].push_back(static_cast<double>(name[i]));
    out[q].insert(out[q].end(), values.begin() + static_cast<std::ptrdiff_t>(i * w),
                  values.begin() + static_cast<std::ptrdiff_t>((i + 1) * w));
    sent[q].push_back(static_cast<std::uint32_t>(i));
  }
  std::vector<int> counts;
  const auto in = exchange(out, &counts);
  KeptElsewhereTouched extra;
  SlotMap extra_slot;
  auto complete_of = [&](std::size_t f) -> double* {
    if (const std::int64_t i = mine.find(f); i >= 0) return values.data() + static_cast<std::size_t>(i) * w;
    return extra.values.data() + static_cast<std::size_t>(extra_slot.find(f)) * w;
  };
  for (std::size_t r = 0; r < in.size(); r += 1 + w) {
    const auto f = static_cast<std::size_t>(in[r]);
    if (mine.find(f) < 0 && extra_slot.find(f) < 0) {  // the first part of a name this rank does not hold
      extra_slot.find_or_insert(f, std::uint32_t(extra.name.size()));
      extra.name.push_back(f);
      extra.values.insert(extra.values.end(), in.begin() + static_cast<std::ptrdiff_t>(r + 1),
                          in.begin() + static_cast<std::ptrdiff_t>(r + 1 + w));
      continue;
    }
    combine(complete_of(f), &in[r + 1]);
  }
  std::vector<std::vector<double>> answer(P);
  std::size_t r = 0;
  for (std::size_t q = 0; q < counts.size(); ++q)
    for (std::size_t k = 0; k < static_cast<std::size_t>(counts[q]); k += 1 + w, r += 1 + w) {
      const double* c = complete_of(static_cast<std::size_t>(in[r]));
      answer[q].insert(answer[q].end(), c, c + w);
    }
  const auto back = exchange(answer, nullptr);
  std::size_t at = 0;  // the answers come in rank order, each keeper's in the order its names were sent
  for (std::size_t q = 0; q < P; ++q)
    for (const std::uint32_t i : sent[q]) {
      std::copy_n(back.begin() + static_cast<std::ptrdiff_t>(at), w, values.begin() + std::ptrdiff_t(i * w));
      at += w;
    }
  require(at == back.size(), "a keeper answered for other names than it was sent");
  return extra;
}

}  // namespace rsph
