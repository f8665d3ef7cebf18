#pragma once
// The force pass: accelerations (eq. 3), heating (eq. 4) and, where asked, the continuity equation,
// summed over neighbour lists, with every pair term, stress and body force a scene names inlined. The
// pair physics are the small functions of hydro.hpp, shear_viscosity.hpp and each term's pair(); this
// file is only the loop that gathers a pair and adds them up.
#include "rsph/core/parallel.hpp"
#include "rsph/kernel/kernel.hpp"
#include "rsph/neighbors/neighbor_list.hpp"
#include "rsph/physics/concept.hpp"
#include "rsph/physics/consistent_gradient.hpp"
#include "rsph/physics/hydro.hpp"
#include "rsph/physics/loops/scheme.hpp"
#include "rsph/physics/shear_viscosity.hpp"

#include <algorithm>
#include <cstdint>
#include <span>
#include <tuple>
#include <type_traits>
#include <vector>

namespace rsph::physics::loops {

/// Per-point fields the force pass reads beside the particle set (real points and ghosts); those a
/// scheme does not use stay empty.
template <int D>
struct ForceFields {
  std::span<const double> P_over_rho2;    ///< P / rho^2, refreshed with the pressure (has_pressure)
  std::span<const double> Omega;          ///< grad-h factors (grad_h)
  std::span<const Mat<D>> S_over_rho2;    ///< viscous stress / rho^2 (has_stress)
  std::span<const Vec<D>> psi;            ///< the consistent gradient's psi (corrected)
  std::span<const std::uint8_t> band;     ///< whether a point takes part in the corrected gradient (corrected)
  std::span<const double> switch_factor;  ///< a viscosity switch's factor of each point (has_switch)
};

/// What the force pass writes besides dv/dt and du/dt: the signal speed of each real point, and d rho/dt
/// when asked for.
struct ForceRates {
  std::vector<double>& v_sig;
  std::vector<double>& drho_dt;
};

namespace detail {

template <int D, bool has_energy, class T>
[[gnu::always_inline]] inline void add_pair_term(const T& term, const physics::Pair<D>& pr, Vec<D>& dv, double& du,
                                                 double& v_sig) {
  if constexpr (PairTerm<T, D>) {
    const physics::PairRates<D> r = term.pair(pr);
    dv += r.dv_dt;
    if constexpr (has_energy) du += r.du_dt;
    v_sig = std::max(v_sig, r.v_sig);
  }
}

struct NoBodyForce {};
template <class T, int D>
struct BodyForceAt {
  const T* term;
  double time;
  Vec<D> acceleration(const Vec<D>& x) const { return term->acceleration(x, time); }
};
template <int D, class T>
auto body_force_now(const T& term, double time) {
  if constexpr (BodyForceAtTime<T, D>)
    return term.at(time);
  else if constexpr (BodyForce<T, D>)
    return BodyForceAt<T, D>{&term, time};
  else
    return NoBodyForce{};
}
template <int D, class F>
[[gnu::always_inline]] inline void add_body_force(const F& force, const Vec<D>& x, Vec<D>& dv) {
  if constexpr (!std::is_same_v<F, NoBodyForce>) dv += force.acceleration(x);
}

/// The first stress term among the terms (the simulation allows at most one).
template <int D, class... Terms>
const auto& stress_term(const std::tuple<Terms...>& terms) {
  return std::get<first_of_kind<sizeof...(Terms)>({StressTerm<Terms, D>...})>(terms);
}

}  // namespace detail

/// Each term's body force at `time` (nothing for other terms), taken once per force pass.
template <int D, class... Terms>
auto body_forces_at(const std::tuple<Terms...>& terms, double time) {
  return std::apply([&](const auto&... term) { return std::tuple{detail::body_force_now<D>(term, time)...}; }, terms);
}

/// a's side of the pair data (physics::Pair), taken once per particle. The helpers the pair loop calls are
/// forced inline: as separate calls they cost the force pass 60 % more instructions.
template <class S, class P>
[[gnu::always_inline]] inline void set_pair_a(physics::Pair<S::dim>& pr, const P& p, const ForceFields<S::dim>& f,
                                              std::size_t a) {
  pr.m_a = p.m[a];
  pr.rho_a = p.rho[a];
  if constexpr (S::has_pressure) {
    pr.P_a = p.P[a];
    pr.P_over_rho2_a = f.P_over_rho2[a];
  }
  pr.cs_a = p.cs[a];
  pr.u_a = energy_of<S::has_energy>(p, a);
  if constexpr (S::grad_h) pr.Omega_a = f.Omega[a];
  if constexpr (S::has_switch) pr.switch_a = f.switch_factor[a];
}

/// Accelerations and heating rates of the points of `rows` at time `time` (for body forces);
/// with_drho also sums the continuity equation's d rho / dt, which predicts the density of particles
/// between their steps.
template <class S, bool with_drho, class P, class Rows, class... Terms>
void force_rows(P& p, const neighbors::NeighborList& nl, const Rows& rows, const ForceFields<S::dim>& f,
                const std::tuple<Terms...>& terms, double time, ForceRates out) {
  constexpr int D = S::dim;
  using Kernel = typename S::Kernel;
  const std::size_t n = p.n_real;
  out.v_sig.resize(n);
  if constexpr (with_drho) out.drho_dt.resize(n);
  const std::size_t n_rows = rows.size();
  const auto forces_now = body_forces_at<D>(terms, time);
#pragma omp parallel for schedule(dynamic, kRowChunk) if (n_rows >= kParallelMin)
  for (std::size_t i = 0; i < n_rows; ++i) {
    const std::uint32_t a = rows[i];
    Vec<D> dv = Vec<D>::Zero();
    double drho = 0.0;
    double du = 0.0;
    double v_sig = p.cs[a];
    physics::Pair<D> pr;
    set_pair_a<S>(pr, p, f, a);
    const double h_a = p.h[a], inv_h_a = 1.0 / h_a;
    for (auto k = nl.offset[i]; k < nl.offset[i + 1]; ++k) {
      const std::uint32_t b = nl.index[k];
      pr.r_ab = p.x[a] - p.x[b];
      pr.r = pr.r_ab.norm();
      if (pr.r <= 0.0) continue;
      const double h_b = p.h[b];
      if constexpr (S::grad_h)
        if (pr.r >= Kernel::support * std::max(h_a, h_b)) continue;  // inside the search margin only
      pr.v_ab = p.v[a] - p.v[b];
      pr.h_ab = 0.5 * (h_a + h_b);
      pr.m_b = p.m[b];
      pr.rho_b = p.rho[b];
      if constexpr (S::has_pressure) {
        pr.P_b = p.P[b];
        pr.P_over_rho2_b = f.P_over_rho2[b];
      }
      pr.cs_b = p.cs[b];
      pr.u_b = energy_of<S::has_energy>(p, b);
      if constexpr (S::has_switch) pr.switch_b = f.switch_factor[b];
      if constexpr (S::grad_h) {
        pr.grad_W_a = kernel::grad_W_inv_h<Kernel, D>(pr.r_ab, pr.r, inv_h_a);
        pr.grad_W_b = kernel::grad_W<Kernel, D>(pr.r_ab, pr.r, h_b);
        pr.grad_W = 0.5 * (pr.grad_W_a + pr.grad_W_b);
        pr.Omega_b = f.Omega[b];
        if constexpr (S::has_pressure) dv += physics::pressure_acceleration_grad_h(pr);
        if constexpr (S::has_pressure && S::has_energy) du += physics::pressure_heating_grad_h(pr);
      } else {
        const double inv_h = kernel::inv_h_ab(h_a, inv_h_a, h_b);
        pr.grad_W = kernel::grad_W_inv_h<Kernel, D>(pr.r_ab, pr.r, inv_h);
        if constexpr (S::corrected)
          if (f.band[a] && f.band[b])
            pr.grad_W =
                physics::consistent_gradient<D>(pr.grad_W, kernel::W_inv_h<Kernel, D>(pr.r, inv_h), f.psi[a], f.psi[b]);
        if constexpr (S::corrected)
          drho += physics::continuity_term_by_volume(pr.rho_a, pr.m_b / pr.rho_b, pr.v_ab, pr.grad_W);
        else if constexpr (with_drho)
          drho += physics::continuity_term(pr.m_b, pr.v_ab, pr.grad_W);
        if constexpr (S::has_pressure) dv += physics::pressure_acceleration(pr);
        if constexpr (S::has_pressure && S::has_energy) du += physics::pressure_heating(pr);
      }
      std::apply([&](const auto&... term) { (detail::add_pair_term<D, S::has_energy>(term, pr, dv, du, v_sig), ...); },
                 terms);
      if constexpr (S::has_stress) {
        dv += physics::stress_acceleration<D>(pr.m_b, f.S_over_rho2[a], f.S_over_rho2[b], pr.grad_W);
        if constexpr (S::has_energy) du += physics::stress_heating<D>(pr.m_b, f.S_over_rho2[a], pr.v_ab, pr.grad_W);
      }
    }
    if constexpr (S::has_stress) v_sig = std::max(v_sig, detail::stress_term<D>(terms).signal_speed(h_a));
    std::apply([&](const auto&... force) { (detail::add_body_force<D>(force, p.x[a], dv), ...); }, forces_now);
    p.dv_dt[a] = dv;
    if constexpr (S::has_energy) p.du_dt[a] = du;
    if constexpr (with_drho) out.drho_dt[a] = drho;
    out.v_sig[a] = v_sig;
  }
}

}  // namespace rsph::physics::loops
