#pragma once
// The programs on many ranks. Built with MPI (RSPH_WITH_MPI, where CMake finds MPI and Zoltan), a program starts
// and ends MPI itself (the library never does) and runs its scene's simulation with a domain decomposition
// (mpi/decomposition.hpp) on every rank count, one rank being the serial run bit for bit. Every rank computes
// the same figures (reductions); rank 0 writes the run's folder, into whose snapshots every rank writes its own
// particles, while the other ranks write their copies of the small files to a private temporary folder,
// removed at the end (prepare_output), and print nothing. Built without MPI, nothing here does anything.
#include "rsph/analysis/interpolate.hpp"
#include "rsph/core/errors.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>
#ifdef RSPH_WITH_MPI
#include "rsph/mpi/decomposition.hpp"
#endif

namespace rsph::examples {

/// MPI for the program's lifetime (started here only if nobody has).
class MpiSession {
 public:
  MpiSession(int& argc, char**& argv) {
#ifdef RSPH_WITH_MPI
    int started = 0;
    MPI_Initialized(&started);
    if (!started) {
      MPI_Init(&argc, &argv);
      owned_ = true;
    }
#else
    (void)argc;
    (void)argv;
#endif
  }
  ~MpiSession() {
#ifdef RSPH_WITH_MPI
    if (owned_) MPI_Finalize();
#endif
  }
  /// After an error on this rank: ends every rank with `code`, which may otherwise wait for this one in a
  /// collective call forever.
  void abort_all(int code) const {
#ifdef RSPH_WITH_MPI
    int n = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    if (n > 1) MPI_Abort(MPI_COMM_WORLD, code);
#else
    (void)code;
#endif
  }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

 private:
  bool owned_ = false;
};

/// Whether mpiexec started this process as one of several (its environment says so), for a program built
/// without MPI, which then runs alone.
inline bool started_as_one_of_many() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* v = std::getenv(name); v && std::atoi(v) > 1) return true;
  return false;
}

/// This process's rank and the rank count (0 and 1 without MPI).
inline int this_rank() {
#ifdef RSPH_WITH_MPI
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
#else
  return 0;
#endif
}
inline int rank_count() {
#ifdef RSPH_WITH_MPI
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
#else
  return 1;
#endif
}
inline bool on_root() { return this_rank() == 0; }

/// The communicator of a decomposed run's ranks (a build without MPI has none).
#ifdef RSPH_WITH_MPI
using RankComm = mpi::Comm;
#else
struct RankComm {};
#endif

/// The communicator of `sim`'s ranks where it runs on more than one, otherwise null: for the code that does the
/// same for every simulation type (checkpoints, snapshots), so that it is compiled once.
template <class Sim>
const RankComm* comm_of_ranks([[maybe_unused]] const Sim& sim) {
#ifdef RSPH_WITH_MPI
  if constexpr (Sim::distributed)
    if (rank_count() > 1) return &sim.domain().comm();
#endif
  return nullptr;
}

/// f(domain) with the decomposition of the ranks, or f() without MPI: a scene's make_ function takes the
/// decomposition as its last term.
template <int D, class F>
decltype(auto) with_ranks(F&& f) {
#ifdef RSPH_WITH_MPI
  return f(mpi::Decomposition<D>(MPI_COMM_WORLD));
#else
  return f();
#endif
}

/// Sums `values` over the ranks when `sim` is decomposed (a measure made of sums over particles).
template <class Sim, class Span>
void sum_over_ranks(const Sim& sim, Span&& values) {
  if constexpr (Sim::distributed) sim.domain().sum_in_place(std::span<double>(values));
}

/// Element-wise least (`least`) or largest values over the ranks when `sim` is decomposed (one reduction).
template <class Sim>
void extreme_over_ranks(const Sim& sim, std::vector<double>& values, bool least) {
  if constexpr (Sim::distributed) sim.domain().extreme_in_place(std::span<double>(values), least);
}

/// Sigma(points) = sum_b m_b W(|x - x_b|, h_b) over the whole gas (analysis::interpolate_density, an open box),
/// from each rank's own particles `own`: a sum over particles, so each rank adds its own share at every point and
/// the shares are summed over the ranks, and no rank needs another's particles. `own` must outlive the function.
template <class Kernel, class Sim, class P>
auto density_over_ranks(const Sim& sim, const P& own) {
  return [&sim, &own](const std::vector<Vec<2>>& points) {
    auto sigma = analysis::interpolate_density<Kernel>(own, points);
    sum_over_ranks(sim, sigma);
    return sigma;
  };
}

/// A count summed over the ranks when `sim` is decomposed.
template <class Sim>
std::uint64_t count_over_ranks(const Sim& sim, std::uint64_t n) {
  if constexpr (Sim::distributed)
    return sim.domain().sum(n);
  else
    return n;
}

/// The particles of every rank on rank 0 and none on the others, or the set itself in one process: for a measure
/// that needs the whole field at once, made on rank 0 (measured_on_root).
template <class Sim>
decltype(auto) particles_on_root(const Sim& sim) {
  if constexpr (Sim::distributed)
    return sim.domain().gather_on_root(sim.particles());
  else
    return (sim.particles());
}

/// f(whole), an array of figures, made on rank 0 from particles_on_root's set `whole` and sent to every rank (the
/// others hold no particles there and do not call f).
template <class Sim, class P, class F>
auto measured_on_root(const Sim& sim, const P& whole, F&& f) {
  static_assert(std::tuple_size_v<decltype(f(whole))> > 0, "a measure on rank 0 returns an std::array of doubles");
  if constexpr (Sim::distributed) {
    decltype(f(whole)) figures{};
    if (sim.domain().comm().rank() == 0) figures = f(whole);
    sim.domain().broadcast(std::span<double>(figures));
    return figures;
  } else {
    return f(whole);
  }
}

}  // namespace rsph::examples
