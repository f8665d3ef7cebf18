#pragma once
// Shared by the benchmarks: argument 2 of every benchmark is the thread count (0: all cores).
#include <benchmark/benchmark.h>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace rsph::bench {

/// Sets the OpenMP thread count from state.range(2) and returns it (1 without OpenMP).
inline int use_threads(const benchmark::State& state) {
  int t = static_cast<int>(state.range(2));
#ifdef _OPENMP
  if (t == 0) t = omp_get_num_procs();
  omp_set_num_threads(t);
#else
  t = 1;
#endif
  return t;
}

}  // namespace rsph::bench
