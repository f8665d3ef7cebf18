#pragma once
// The physics-term policy axis: what a Term may add to a simulation. Each term is one of these kinds;
// the driver finds out which at compile time, so a term a scene does not name costs nothing.
#include "rsph/core/dimension.hpp"
#include "rsph/core/particle_set.hpp"
#include "rsph/physics/pair.hpp"

#include <array>
#include <concepts>
#include <cstddef>
#include <span>
#include <vector>

namespace rsph {

/// A dissipation or force term summed over neighbour pairs (artificial viscosity, conductivity, shear).
template <class T, int D>
concept PairTerm = requires(const T& t, const physics::Pair<D>& pair) {
  { t.pair(pair) } -> std::same_as<physics::PairRates<D>>;
};

/// A pair term scaled by a per-particle factor of the velocity gradient (Balsara's switch on the artificial
/// viscosity): the driver runs a gradient pass before the force sum and hands each pair both factors
/// (Pair::switch_a, switch_b); active() false skips the pass.
template <class T, int D>
concept ViscositySwitch = PairTerm<T, D> && requires(const T& t, const Mat<D>& grad_v, double cs, double h) {
  { t.switch_factor(grad_v, cs, h) } -> std::same_as<double>;
  { t.active() } -> std::same_as<bool>;
};

/// A stress built from each particle's velocity gradient (Navier-Stokes viscosity); the driver runs a
/// gradient pass before the force sum when a scene names one.
template <class T, int D>
concept StressTerm = requires(const T& t, const Mat<D>& grad_v, double rho, double h) {
  { t.stress(grad_v, rho) } -> std::same_as<Mat<D>>;
  { t.signal_speed(h) } -> std::same_as<double>;
};

/// An external acceleration g(x, t) per particle (point-mass gravity).
template <class T, int D>
concept BodyForce = requires(const T& t, const Vec<D>& x, double time) {
  { t.acceleration(x, time) } -> std::same_as<Vec<D>>;
};

/// A body force whose time dependence can be evaluated once per force pass: t.at(time) returns an object
/// with acceleration(x) (orbits, ramps), so the pass does not repeat it for every particle.
template <class T, int D>
concept BodyForceAtTime = BodyForce<T, D> && requires(const T& t, const Vec<D>& x, double time) {
  { t.at(time).acceleration(x) } -> std::same_as<Vec<D>>;
};

/// Adaptive smoothing lengths solved with the density (grad-h SPH); the driver switches to the grad-h
/// density and force sums when a scene names one.
template <class T>
concept SmoothingLengthSolver = requires(const T& t, double m, double rho, double h) {
  requires T::solves_smoothing_length;
  { t.rho_of_h(m, h) } -> std::same_as<double>;
  { t.h_of_rho(m, rho) } -> std::same_as<double>;
};

/// Prescribes x and v of frozen particles at time t (boundary zones moving on fixed orbits).
template <class T, int D>
concept PrescribedMotion = requires(const T& t, std::size_t i, Vec<D>& x, Vec<D>& v, double time) {
  t.prescribe(i, x, v, time);
};

/// A region whose gas moves on fixed orbits (the disk's boundary zones of §5.1): members are chosen by
/// position whenever the particle set is rebuilt and turned by advance(x, v, dt) instead of integrated.
template <class T, int D>
concept BoundaryZone = requires(const T& t, const Vec<D>& x, Vec<D>& x_mut, Vec<D>& v, double dt) {
  { t.contains(x) } -> std::same_as<bool>;
  t.advance(x_mut, v, dt);
};

/// A region where the velocity of the integrated gas relaxes toward a reference field (the wave-damping zones
/// at a disk's edges of de Val-Borro et al. 2006): damp(x, v, dt) relaxes v of a particle at x over a step dt;
/// active() says whether any region damps at all.
template <class T, int D>
concept VelocityDamping = requires(const T& t, const Vec<D>& x, Vec<D>& v, double dt) {
  t.damp(x, v, dt);
  { t.active() } -> std::same_as<bool>;
};

/// Pair gradients corrected so that a uniform state is an exact equilibrium where h varies (level faces of
/// a multi-level lattice), with the density from the continuity equation (physics/consistent_gradient.hpp).
template <class T>
concept GradientCorrection = requires(const T& t) {
  requires T::corrects_gradient;
  { t.tolerance } -> std::convertible_to<double>;
  { t.max_iterations } -> std::convertible_to<int>;
  { t.every_step } -> std::convertible_to<bool>;
};

/// Runs the simulation on the ranks of a communicator (mpi/decomposition.hpp): it shares the particles out,
/// brings other ranks' particles as halos with the ghosts, refreshes them after a pass and makes the ranks agree
/// on time steps and checks. It names no MPI type, so the driver needs nothing of MPI.
template <class T, int D>
concept DomainDecomposition = requires(T& t, const T& c, ParticleSet<D, false>& p, const Box<D>& box,
                                       std::vector<double>& f, std::span<const double> work, double& x) {
  requires T::decomposes_domain;
  t.distribute(p);
  t.balance(p, work);
  t.make_ghosts(p, box, 1.0);
  t.refresh_halos(f);
  { c.ranks() } -> std::convertible_to<int>;
  { c.min(1.0) } -> std::same_as<double>;
  { c.max(1.0) } -> std::same_as<double>;
  c.min_max(x, x);
  { c.any(true) } -> std::same_as<bool>;
  { c.all(true) } -> std::same_as<bool>;
};

template <class T, int D>
concept Term =
    PairTerm<T, D> || StressTerm<T, D> || BodyForce<T, D> || SmoothingLengthSolver<T> || PrescribedMotion<T, D> ||
    BoundaryZone<T, D> || VelocityDamping<T, D> || GradientCorrection<T> || DomainDecomposition<T, D>;

/// Whether term T, if it names a dimension (`static constexpr int dim`), was made for dimension D.
template <class T, int D>
constexpr bool made_for_dimension() {
  if constexpr (requires { T::dim; })
    return T::dim == D;
  else
    return true;
}

/// Position in a pack of the first type of a kind (the kinds a simulation takes at most one of); 0 if none.
template <std::size_t N>
constexpr std::size_t first_of_kind(std::array<bool, N> is_kind) {
  for (std::size_t i = 0; i < N; ++i)
    if (is_kind[i]) return i;
  return 0;
}

template <class T, int D>
constexpr bool check_term() {
  static_assert(Term<T, D>,
                "a physics term must provide one of: `PairRates<D> pair(const Pair<D>&) const` (pair term; a "
                "switched one adds `double switch_factor(const Mat<D>& grad_v, double cs, double h) const` and "
                "`bool active() const`), "
                "`Mat<D> stress(const Mat<D>& grad_v, double rho) const` with `double signal_speed(double h) const` "
                "(viscous stress), `Vec<D> acceleration(const Vec<D>& x, double t) const` (body force), "
                "`solves_smoothing_length` with `rho_of_h` and `h_of_rho` (adaptive h), or "
                "`void prescribe(size_t i, Vec<D>& x, Vec<D>& v, double t) const` (prescribed motion), or "
                "`bool contains(const Vec<D>&) const` with `void advance(Vec<D>& x, Vec<D>& v, double dt) const` "
                "(boundary zone), or `void damp(const Vec<D>& x, Vec<D>& v, double dt) const` with `bool active() "
                "const` (damping zone), or "
                "`corrects_gradient` with `tolerance`, `max_iterations` and `every_step` "
                "(consistent pair gradients), or `decomposes_domain` with `distribute`, `balance`, `make_ghosts`, "
                "`refresh_halos` and the reductions `ranks`, `min`, `max`, `min_max`, `any`, `all` (many ranks)");
  return true;
}

}  // namespace rsph
