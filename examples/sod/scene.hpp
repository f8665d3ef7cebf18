#pragma once
// Sod's shock tube (Sod 1978): (rho, v, P) = (1, 0, 1) left of x = 0.5 and (0.125, 0, 0.1) right,
// gamma = 1.4, in 1D or in 2D as a strip periodic in y; reflecting walls at x = 0 and x = 1.
#include "common/blocks.hpp"
#include "common/levels.hpp"
#include "common/run_helpers.hpp"
#include "rsph/rsph.hpp"

#include <cmath>
#include <string>

namespace rsph::scenes {

struct SodParams {
  int n_left = 400;        ///< particles across the left half along x
  int ny_left = 8;         ///< 2D: particles across the strip on the left (even)
  double h_over_dx = 1.2;  ///< eta of h = eta (m / rho)^(1/D)
  double alpha = 1.0, beta = 2.0;
  double gamma = 1.4;
  double t_end = 0.2;
  double courant = 0.3;
  analysis::GasState left{1.0, 0.0, 1.0}, right{0.125, 0.0, 0.1};

  void validate() const {
    require(n_left >= 8, "Sod: n_left must be at least 8 (got " + std::to_string(n_left) + ")");
    require(ny_left >= 2 && ny_left % 2 == 0, "Sod: ny_left must be an even number >= 2");
    require(h_over_dx > 0.0, "Sod: h/dx must be positive (got " + std::to_string(h_over_dx) + ")");
    require(t_end > 0.0, "Sod: t_end must be positive");
    require(left.rho > 0 && right.rho > 0 && left.P > 0 && right.P > 0,
            "Sod: densities and pressures must be positive");
  }
};

/// Extra: a domain decomposition for many ranks (examples::with_ranks), or nothing.
template <int D, class Kernel, class... Extra>
using SodSimulation =
    Simulation<D, Kernel, eos::IdealGas, regularize::None, physics::ArtificialViscosity, physics::GradH<D>, Extra...>;

/// The walls at x = 0 and 1; in 2D and 3D the cross-section periodic, `width` wide.
template <int D>
Box<D> sod_box(double width) {
  Box<D> box;
  box.lo.setZero();
  box.hi.setConstant(width);
  box.hi[0] = 1.0;
  box.edge[0] = Edge::reflecting;
  for (int k = 1; k < D; ++k) box.edge[static_cast<std::size_t>(k)] = Edge::periodic;
  return box;
}

/// A block of nx x ny^(D-1) lattice particles of spacing dx from x0 on, masses state.rho dx^D / bias.
template <int D>
void add_sod_block(ParticleSet<D, true>& p, const analysis::GasState& state, const eos::IdealGas& gas, double x0,
                   int nx, int ny, double dx, double h_over_dx, double bias) {
  Vec<D> lo = Vec<D>::Zero(), v = Vec<D>::Zero();
  lo[0] = x0;
  v[0] = state.v;
  examples::for_each_block_site<D>({nx, ny, ny}, lo, Vec<D>::Constant(dx), [&](const Vec<D>& x, auto) {
    p.add(state.rho * std::pow(dx, D) / bias, x, v, h_over_dx * dx, gas.internal_energy(state.rho, state.P));
  });
}

/// Equal-mass particles in 1D (spacing ratio 8 across the membrane); in 2D and 3D a lattice of spacing dx on
/// the left and 2 dx on the right so both tile the periodic cross-section (masses differ by the density ratio
/// over 2^D: in 3D they are equal).
template <int D, class Kernel, class... Extra>
SodSimulation<D, Kernel, Extra...> make_sod(const SodParams& s, Extra... extra) {
  s.validate();
  const eos::IdealGas gas{s.gamma};
  gas.validate();
  ParticleSet<D, true> p;
  const double dx_left = 0.5 / s.n_left;
  const double ratio = D == 1 ? s.left.rho / s.right.rho : 2.0;
  const int n_right = std::max(1, static_cast<int>(std::lround(s.n_left / ratio)));
  const double dx_right = 0.5 / n_right;
  const int ny_left = D == 1 ? 1 : s.ny_left, ny_right = D == 1 ? 1 : s.ny_left / 2;
  // Masses so that the SPH density of each lattice block equals its nominal density.
  const double bias = kernel::lattice_sum<Kernel, D>(s.h_over_dx);
  add_sod_block(p, s.left, gas, 0.0, s.n_left, ny_left, dx_left, s.h_over_dx, bias);
  add_sod_block(p, s.right, gas, 0.5, n_right, ny_right, dx_right, s.h_over_dx, bias);
  TimeStepParams ts;
  ts.courant = s.courant;
  return SodSimulation<D, Kernel, Extra...>(std::move(p), sod_box<D>(ny_left * dx_left), gas, regularize::None{}, ts,
                                            physics::ArtificialViscosity{s.alpha, s.beta},
                                            physics::GradH<D>{s.h_over_dx}, std::move(extra)...);
}

/// RSPH on a lattice of levels 0..levels (levels = 0: uniform) with the density-jump criterion: the
/// finest spacing is the SPH run's left spacing 0.5 / n_left, so a uniform run and a refined one
/// share the finest resolution.
struct RsphSodParams {
  examples::DensityJumpLevels refinement{.levels = 2};  ///< the level-0 spacing is 2^levels times the finest
  std::uint64_t cycle = 10;                             ///< regularize every `cycle` steps
  int max_bin = 0;              ///< individual time steps down to 2^-max_bin of the longest (0: global)
  std::string remap = "first";  ///< the remap's order, first (eqs. 6-9) or second
  void validate() const {
    examples::check_remap(remap);
    refinement.validate("Sod RSPH", 8);
    require(cycle >= 1, "Sod RSPH: --cycle must be at least 1");
  }
};

template <int D, class Order = regularize::FirstOrder>
using RsphSodRegularizer =
    regularize::LatticeRegularizer<lattice::MultiLevel<D, refine::DensityJump>, schedule::EveryNSteps,
                                   geometry::LocalVoronoi, region::Unbounded, Order>;
template <int D, class Kernel, class Order, class... Extra>
using RsphSodSimulation =
    Simulation<D, Kernel, eos::IdealGas, RsphSodRegularizer<D, Order>, physics::ArtificialViscosity, Extra...>;

/// The tube on the finest lattice everywhere, then one remap onto the multi-level lattice, which puts
/// the membrane on the finest level and the uniform states on level 0.
/// `extra` terms join the artificial viscosity (physics::ConsistentGradient for exact level faces).
template <int D, class Kernel, class Order = regularize::FirstOrder, class... Extra>
requires(D == 1 || D == 2) RsphSodSimulation<D, Kernel, Order, Extra...> make_rsph_sod(const SodParams& s,
                                                                                       const RsphSodParams& r,
                                                                                       Extra... extra) {
  s.validate();
  r.validate();
  const eos::IdealGas gas{s.gamma};
  gas.validate();
  const double dx = 0.5 / s.n_left;
  const std::int64_t fine_per_block = r.refinement.fine_cells_per_block();
  const double block = dx * static_cast<double>(fine_per_block);
  require(std::abs(1.0 / block - std::round(1.0 / block)) < 1e-9,
          "Sod RSPH: the tube length must be a whole number of blocks (2 n_left = " + std::to_string(2 * s.n_left) +
              " must be a multiple of 2^levels * block_cells = " + std::to_string(fine_per_block) + ")");
  Box<D> box;
  box.lo.setZero();
  box.hi.setOnes();
  box.edge[0] = Edge::reflecting;
  int ny = 1;
  if constexpr (D == 2) {
    // the strip: ny_left finest rows, rounded up to whole blocks
    ny = static_cast<int>(((s.ny_left + fine_per_block - 1) / fine_per_block) * fine_per_block);
    box.hi[1] = ny * dx;
    box.edge[1] = Edge::periodic;
  }
  ParticleSet<D, true> p;
  const int nx = 2 * s.n_left;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      Vec<D> x;
      x[0] = (i + 0.5) * dx;
      if constexpr (D == 2) x[1] = (j + 0.5) * dx;
      const auto& state = x[0] < 0.5 ? s.left : s.right;
      Vec<D> v = Vec<D>::Zero();
      v[0] = state.v;
      p.add(state.rho * std::pow(dx, D), x, v, s.h_over_dx * dx, gas.internal_energy(state.rho, state.P));
    }
  const regularize::RemapParams remap{s.h_over_dx};
  auto ml = examples::start_on_levels(p, box, dx, r.refinement, remap);
  TimeStepParams ts;
  ts.courant = s.courant;
  ts.max_bin = r.max_bin;
  return RsphSodSimulation<D, Kernel, Order, Extra...>(
      std::move(p), box, gas,
      RsphSodRegularizer<D, Order>(std::move(ml), schedule::EveryNSteps{r.cycle}, {.remap = remap}), ts,
      physics::ArtificialViscosity{s.alpha, s.beta}, extra...);
}

/// RSPH in 3D: the uniform cubic lattice of the finest spacing 0.5 / n_left (multi-level lattices are 2D so far),
/// regularized every `cycle` steps; masses rho Delta^3 over the lattice sum, so the SPH density of each state is
/// its own.
template <class Order = regularize::FirstOrder>
using RsphSod3Regularizer =
    regularize::LatticeRegularizer<lattice::Cubic, schedule::EveryNSteps,
                                   typename geometry::DefaultCellBuilder<3>::type, region::Unbounded, Order>;
template <class Kernel, class Order, class... Extra>
using RsphSod3Simulation =
    Simulation<3, Kernel, eos::IdealGas, RsphSod3Regularizer<Order>, physics::ArtificialViscosity, Extra...>;

template <class Kernel, class Order = regularize::FirstOrder, class... Extra>
RsphSod3Simulation<Kernel, Order, Extra...> make_rsph_sod3(const SodParams& s, const RsphSodParams& r, Extra... extra) {
  s.validate();
  r.validate();
  const eos::IdealGas gas{s.gamma};
  gas.validate();
  const double dx = 0.5 / s.n_left;
  ParticleSet<3, true> p;
  const double bias = kernel::lattice_sum<Kernel, 3>(s.h_over_dx);
  add_sod_block(p, s.left, gas, 0.0, s.n_left, s.ny_left, dx, s.h_over_dx, bias);
  add_sod_block(p, s.right, gas, 0.5, s.n_left, s.ny_left, dx, s.h_over_dx, bias);
  TimeStepParams ts;
  ts.courant = s.courant;
  ts.max_bin = r.max_bin;
  return RsphSod3Simulation<Kernel, Order, Extra...>(
      std::move(p), sod_box<3>(s.ny_left * dx), gas,
      RsphSod3Regularizer<Order>(lattice::Cubic{dx}, schedule::EveryNSteps{r.cycle},
                                 {.remap = regularize::RemapParams{s.h_over_dx}}),
      ts, physics::ArtificialViscosity{s.alpha, s.beta}, std::move(extra)...);
}

}  // namespace rsph::scenes
