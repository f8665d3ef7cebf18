#pragma once
// Particle data as structure of arrays; ghosts live at the tail, after the n_real real particles.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace rsph {

/// Stands in for a field a scene does not carry (u and du_dt of an isothermal gas): it has no storage.
struct NoField {
  static constexpr std::size_t size() { return 0; }
  void resize(std::size_t) {}
  void clear() {}
};

template <int D, bool HasEnergy>
struct ParticleSet {
  static constexpr int dim = D;
  static constexpr bool has_energy = HasEnergy;
  using Scalars = std::vector<double>;
  using Vectors = std::vector<Vec<D>>;
  using EnergyField = std::conditional_t<HasEnergy, Scalars, NoField>;

  Scalars m, rho, h, P, cs;
  Vectors x, v;
  EnergyField u;  ///< specific internal energy e_a of eq. (4)
  Vectors dv_dt;
  EnergyField du_dt;
  std::vector<std::uint8_t> frozen;         ///< 1: motion prescribed, not integrated
  std::vector<std::uint32_t> ghost_source;  ///< for ghost g (index n_real + g): its real particle
  /// Each real particle's identity: kept through its life (steps, removals), never reused; a remap makes every
  /// particle anew, and the simulation numbers the new ones on from next_id.
  std::vector<std::uint64_t> id;
  std::uint64_t next_id = 0;
  std::size_t n_real = 0;

  /// Every point, real particles and ghosts; n_real counts the real ones.
  std::size_t size_with_ghosts() const { return x.size(); }
  std::size_t n_ghost() const { return size_with_ghosts() - n_real; }

  /// Appends one real particle; only valid while there are no ghosts.
  void add(double mass, const Vec<D>& pos, const Vec<D>& vel, double smoothing, double energy = 0.0) {
    m.push_back(mass);
    x.push_back(pos);
    v.push_back(vel);
    h.push_back(smoothing);
    rho.push_back(0.0);
    P.push_back(0.0);
    cs.push_back(0.0);
    dv_dt.push_back(Vec<D>::Zero());
    if constexpr (HasEnergy) {
      u.push_back(energy);
      du_dt.push_back(0.0);
    }
    frozen.push_back(0);
    id.push_back(next_id++);
    n_real = x.size();
  }

  /// New identities for every real particle (after a remap made them anew).
  void renumber() {
    id.resize(n_real);
    for (auto& i : id) i = next_id++;
  }

  /// Saves or restores (ar.saving()) the real particles through a checkpoint archive (io/checkpoint.hpp):
  /// every field the next step reads, rates included, as per-particle rows (on many ranks each rank's, loaded as
  /// a share of them). Ghosts are left out, for the next step rebuilds them, and when saving they stay in
  /// place for whatever reads them before that step.
  template <class Archive>
  void checkpoint(Archive& ar) {
    const auto scope = ar.scope("particles");
    ParticleSet real;
    if (ar.saving()) {
      real = *this;
      real.clear_ghosts();
    }
    ParticleSet& p = ar.saving() ? real : *this;
    ar.rows("m", p.m);
    ar.rows("rho", p.rho);
    ar.rows("h", p.h);
    ar.rows("P", p.P);
    ar.rows("cs", p.cs);
    ar.rows("x", p.x);
    ar.rows("v", p.v);
    ar.rows("dv_dt", p.dv_dt);
    if constexpr (HasEnergy) {
      ar.rows("u", p.u);
      ar.rows("du_dt", p.du_dt);
    }
    ar.rows("frozen", p.frozen);
    ar.rows("id", p.id);
    ar("next_id", p.next_id);
    if (ar.saving()) return;
    n_real = x.size();
    ghost_source.clear();
    const auto n = n_real;
    if (m.size() != n || h.size() != n || rho.size() != n || P.size() != n || cs.size() != n || v.size() != n ||
        dv_dt.size() != n || u.size() != (HasEnergy ? n : 0) || du_dt.size() != u.size() || frozen.size() != n ||
        id.size() != n)
      throw InputError("checkpoint: the particle fields differ in length");
  }

  /// Drops every ghost.
  void clear_ghosts() {
    resize_all(n_real);
    ghost_source.clear();
  }

  /// Appends real particle a of q, every field and its identity (while there are no ghosts).
  void append_from(const ParticleSet& q, std::size_t a) {
    m.push_back(q.m[a]);
    x.push_back(q.x[a]);
    v.push_back(q.v[a]);
    h.push_back(q.h[a]);
    rho.push_back(q.rho[a]);
    P.push_back(q.P[a]);
    cs.push_back(q.cs[a]);
    dv_dt.push_back(q.dv_dt[a]);
    if constexpr (HasEnergy) {
      u.push_back(q.u[a]);
      du_dt.push_back(q.du_dt[a]);
    }
    frozen.push_back(q.frozen[a]);
    id.push_back(q.id[a]);
    n_real = x.size();
  }

  /// Appends a ghost copy of particle `source` (itself possibly a ghost) at `pos` with velocity `vel`.
  void add_ghost(std::size_t source, const Vec<D>& pos, const Vec<D>& vel) {
    const std::size_t real = source < n_real ? source : ghost_source[source - n_real];
    m.push_back(m[source]);
    x.push_back(pos);
    v.push_back(vel);
    h.push_back(h[source]);
    rho.push_back(rho[source]);
    P.push_back(P[source]);
    cs.push_back(cs[source]);
    dv_dt.push_back(Vec<D>::Zero());
    if constexpr (HasEnergy) {
      u.push_back(u[source]);
      du_dt.push_back(0.0);
    }
    frozen.push_back(frozen[source]);
    ghost_source.push_back(static_cast<std::uint32_t>(real));
  }

  /// Resizes every field to n (drops the tail; new entries zero).
  void resize_all(std::size_t n) {
    m.resize(n);
    rho.resize(n);
    h.resize(n);
    P.resize(n);
    cs.resize(n);
    x.resize(n, Vec<D>::Zero());
    v.resize(n, Vec<D>::Zero());
    dv_dt.resize(n, Vec<D>::Zero());
    u.resize(n);
    du_dt.resize(n);
    frozen.resize(n);
    id.resize(std::min(n, n_real));  // real particles only: ghosts have none
  }

  /// Zeroes, over [from, to), every field but the state m, x, v, h, rho and u: pressure, sound speed, rates
  /// and frozen flags, which a writer of whole new particles (the remap) leaves to the next force pass.
  void clear_all_but_state(std::size_t from, std::size_t to) {
    const auto a = static_cast<std::ptrdiff_t>(from), b = static_cast<std::ptrdiff_t>(to);
    std::fill(P.begin() + a, P.begin() + b, 0.0);
    std::fill(cs.begin() + a, cs.begin() + b, 0.0);
    std::fill(dv_dt.begin() + a, dv_dt.begin() + b, Vec<D>::Zero());
    if constexpr (HasEnergy) std::fill(du_dt.begin() + a, du_dt.begin() + b, 0.0);
    std::fill(frozen.begin() + a, frozen.begin() + b, std::uint8_t{0});
  }

  /// Removes every ghost and the real particles for which remove(a) holds; the rest keep their order.
  /// Returns how many were removed.
  template <class Predicate>
  std::size_t erase_if(Predicate&& remove) {
    clear_ghosts();
    std::size_t kept = 0;
    for (std::size_t a = 0; a < n_real; ++a) {
      if (remove(a)) continue;
      if (kept != a) {
        m[kept] = m[a];
        rho[kept] = rho[a];
        h[kept] = h[a];
        P[kept] = P[a];
        cs[kept] = cs[a];
        x[kept] = x[a];
        v[kept] = v[a];
        dv_dt[kept] = dv_dt[a];
        if constexpr (HasEnergy) {
          u[kept] = u[a];
          du_dt[kept] = du_dt[a];
        }
        frozen[kept] = frozen[a];
        id[kept] = id[a];
      }
      ++kept;
    }
    const std::size_t removed = n_real - kept;
    resize_all(kept);
    n_real = kept;
    return removed;
  }

  /// Moves the real particles for which take(a) holds, every field and identity with them, into a set of their
  /// own; the rest stay, in order. Ghosts are dropped.
  template <class Predicate>
  ParticleSet take_if(Predicate&& take) {
    clear_ghosts();
    ParticleSet out;
    for (std::size_t a = 0; a < n_real; ++a)
      if (take(a)) out.append_from(*this, a);
    out.next_id = next_id;
    erase_if(take);
    return out;
  }
  /// Appends q's real particles, every field and identity kept (no ghosts on either side).
  void append(const ParticleSet& q) {
    clear_ghosts();
    for (std::size_t a = 0; a < q.n_real; ++a) append_from(q, a);
  }

  void reserve(std::size_t n) {
    m.reserve(n);
    rho.reserve(n);
    h.reserve(n);
    P.reserve(n);
    cs.reserve(n);
    x.reserve(n);
    v.reserve(n);
    dv_dt.reserve(n);
    frozen.reserve(n);
    if constexpr (HasEnergy) {
      u.reserve(n);
      du_dt.reserve(n);
    }
  }
};

}  // namespace rsph
