// The time to write one snapshot and one checkpoint of N particles (2D, with energy) from the ranks of
// MPI_COMM_WORLD, in turns and, where the HDF5 linked is parallel, together (mpi::FileTurns), in a folder of
// DIR's:
//   mpiexec -n R bench_files [N = 1000000] [repeats = 5] [DIR = the system's temporary folder]
// Prints one line per way: the median seconds of each over the repeats.
#include "rsph/io/checkpoint.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/mpi/file_turns.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace {

/// This rank's share of N particles on a line, every field set.
rsph::ParticleSet<2, true> share(std::size_t N, const rsph::mpi::Comm& c) {
  const auto P = static_cast<std::size_t>(c.size()), r = static_cast<std::size_t>(c.rank());
  const std::size_t first = N * r / P, n = N * (r + 1) / P - first;
  rsph::ParticleSet<2, true> p;
  p.n_real = n;
  p.resize_all(n);
  for (std::size_t a = 0; a < n; ++a) {
    const double s = double(first + a) / double(N);
    p.x[a] = rsph::Vec<2>(s, 1.0 - s);
    p.v[a] = rsph::Vec<2>(-s, s);
    p.m[a] = p.rho[a] = p.h[a] = p.P[a] = p.u[a] = 1.0 + s;
    p.id[a] = first + a;
  }
  return p;
}

/// The median of `repeats` timings of write(), each between barriers.
template <class Write>
double median_seconds(const rsph::mpi::Comm& c, int repeats, Write&& write) {
  std::vector<double> t;
  for (int k = 0; k < repeats; ++k) {
    c.barrier();
    const double start = MPI_Wtime();
    write();
    c.barrier();
    t.push_back(MPI_Wtime() - start);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

void measure(std::size_t N, int repeats, const std::filesystem::path& parent) {
  const rsph::mpi::Comm c(MPI_COMM_WORLD);
  const auto dir = parent / "rsph_bench_files";  // the snapshot's XDMF series goes beside it
  if (c.rank() == 0) std::filesystem::create_directories(dir);
  c.barrier();
  auto p = share(N, c);  // not const: an archive names the fields it saves by reference
  std::vector<bool> ways{false};
  if (rsph::mpi::parallel_hdf5) ways.push_back(true);
  for (const bool together : ways) {
    const auto snapshot = median_seconds(c, repeats, [&] {
      rsph::io::write_snapshot(dir / "bench_files_snap.h5", p, 0.0, 0, {}, rsph::mpi::FileTurns(c, together));
    });
    const auto checkpoint = median_seconds(c, repeats, [&] {
      auto ar = rsph::io::Archive::for_saving();
      ar.rows("x", p.x), ar.rows("v", p.v), ar.rows("m", p.m), ar.rows("rho", p.rho), ar.rows("h", p.h);
      ar.rows("u", p.u), ar.rows("id", p.id);
      ar.write(dir / "bench_files_checkpoint.h5", rsph::mpi::FileTurns(c, together));
    });
    if (c.rank() == 0)
      std::printf("%zu particles, %d ranks, %-9s: snapshot %.4f s, checkpoint %.4f s\n", N, c.size(),
                  together ? "together" : "in turns", snapshot, checkpoint);
  }
  c.barrier();
  if (c.rank() == 0) std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rc = 0;
  try {
    const std::size_t N = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000000;
    const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
    const std::filesystem::path dir = argc > 3 ? argv[3] : std::filesystem::temp_directory_path();
    if (N == 0 || repeats <= 0) throw std::invalid_argument("usage: bench_files [N > 0] [repeats > 0] [DIR]");
    measure(N, repeats, dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_files: %s\n", e.what());
    rc = 1;
  }
  MPI_Finalize();
  return rc;
}
