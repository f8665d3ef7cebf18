#pragma once
// The start of the disk scenes (the viscous ring, the planet disk): the sites of their lattice in an annulus,
// each with the area its cell stands for, and the kernel's sum over that lattice (the density bias).
#include "rsph/rsph.hpp"

#include <type_traits>

namespace rsph::examples {

/// f(x, cell area) for every site of `lat` at r_lo <= |x| <= r_hi; a rings lattice's sites unturned.
template <class Lattice, class F>
void for_each_site_in_annulus(const Lattice& lat, const Box<2>& box, double r_lo, double r_hi, F&& f) {
  auto inside = [&](const Vec<2>& x) { return x.norm() >= r_lo && x.norm() <= r_hi; };
  if constexpr (PerSiteLattice<Lattice>) {
    const auto sites = lat.sites(lat.ring_at(r_lo), lat.ring_at(r_hi));
    for (std::size_t c = 0; c < sites.n_cells; ++c)
      if (const Vec<2> x = sites.site(c); inside(x)) f(x, sites.nominal_area(c));
  } else {
    const auto range = lat.cells_touching(box, Vec<2>(-r_hi, -r_hi), Vec<2>(r_hi, r_hi));
    for (std::int64_t j = range.lo[1]; j <= range.hi[1]; ++j)
      for (std::int64_t i = range.lo[0]; i <= range.hi[0]; ++i)
        if (const Vec<2> x = lat.site(box, {i, j}); inside(x)) f(x, lat.cell_volume());
  }
}

/// The cell area times the kernel's sum over the lattice at h/Delta: square, hexagonal, or rings sliding past
/// each other. Masses rho A / this give SPH density rho.
template <class Kernel, class Lattice>
double lattice_bias(double h_over_dx) {
  if constexpr (std::is_same_v<Lattice, lattice::Hexagonal>)
    return kernel::hexagonal_lattice_sum<Kernel>(h_over_dx);
  else if constexpr (std::is_same_v<Lattice, lattice::Rings>)
    return kernel::sheared_rows_lattice_sum<Kernel>(h_over_dx);
  else
    return kernel::lattice_sum<Kernel, 2>(h_over_dx);
}

}  // namespace rsph::examples
