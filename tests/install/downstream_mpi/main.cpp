// A downstream program on MPI: it starts MPI itself, hands the decomposition its communicator, and checks that
// the particles it shares out keep their total mass.
#include <rsph/mpi/decomposition.hpp>
#include <rsph/rsph.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rc = 0;
  {
    rsph::mpi::Decomposition<2> d(MPI_COMM_WORLD);
    rsph::ParticleSet<2, false> p;
    for (int i = 0; i < 100; ++i) p.add(1.0, rsph::Vec<2>(0.01 * i, 0.5), rsph::Vec<2>::Zero(), 0.02);
    d.distribute(p);
    d.balance(p, {});
    const double mass = d.totals(p).mass;
    std::printf("rank %d of %d: %zu particles, total mass %g\n", d.comm().rank(), d.ranks(), p.n_real, mass);
    rc = mass == 100.0 ? 0 : 1;
  }
  MPI_Finalize();
  return rc;
}
