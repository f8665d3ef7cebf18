#pragma once
// The one parallel pattern the library uses outside the pair loops: contiguous chunks, one per thread, so
// that every result is put together in a fixed order (it depends on the thread count, never on scheduling).
#include <cstddef>
#include <exception>
#include <numeric>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace rsph {

/// Rows a thread takes at a time in the passes whose rows are independent gathers (density, forces, stress, h):
/// handed out as threads come free, so a thread whose core another process shares takes fewer, and the results
/// stay the same bits, each row summed alone whichever thread sums it.
inline constexpr std::size_t kRowChunk = 64;

/// A pass over fewer items runs on one thread: waking a sleeping thread costs more than such a pass saves, and
/// the programs' threads sleep when they wait (docs/performance.md, "Threads on a shared core").
inline constexpr std::size_t kParallelMin = 4096;

/// Number of threads a parallel pass uses (1 without OpenMP).
inline int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// Runs body(thread, begin, end) over contiguous chunks of [0, n), one per thread of the team, thread t
/// taking the t-th; thread < max_threads(). The chunks follow the team actually started (a call from inside
/// a parallel region gets a team of one), so no part of [0, n) is ever left out. An exception thrown in a
/// chunk is carried out of the parallel region and rethrown (the first one wins).
template <class Body>
void run_parallel(std::size_t n, Body&& body) {
  std::exception_ptr error;
#pragma omp parallel num_threads(n >= kParallelMin ? max_threads() : 1)
  {
    int t = 0, team = 1;
#ifdef _OPENMP
    t = omp_get_thread_num();
    team = omp_get_num_threads();
#endif
    const std::size_t begin = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(team);
    const std::size_t end = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(team);
    try {
      body(t, begin, end);
    } catch (...) {
#pragma omp critical(rsph_parallel_error)
      if (!error) error = std::current_exception();
    }
  }
  if (error) std::rethrow_exception(error);
}

/// A parallel pass whose chunks each write a number of items known only per chunk, packed in chunk order
/// (the order a serial pass would write them in): count(begin, end) says how many the chunk writes, then
/// make_room(total) sizes the output and write(thread, begin, end, first) writes the chunk's items from
/// index `first` on. Returns the total.
template <class Count, class MakeRoom, class Write>
std::size_t run_parallel_packed(std::size_t n, Count&& count, MakeRoom&& make_room, Write&& write) {
  std::vector<std::size_t> first(static_cast<std::size_t>(max_threads()) + 1, 0);
  run_parallel(n, [&](int t, std::size_t begin, std::size_t end) {
    first[static_cast<std::size_t>(t) + 1] = count(begin, end);
  });
  std::partial_sum(first.begin(), first.end(), first.begin());
  make_room(first.back());
  run_parallel(
      n, [&](int t, std::size_t begin, std::size_t end) { write(t, begin, end, first[static_cast<std::size_t>(t)]); });
  return first.back();
}

}  // namespace rsph
