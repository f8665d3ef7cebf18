#pragma once
// The planet disk in 3D: the 2D disk's Sigma_0 spread over a vertically isothermal disk with the same c_s / v_K
// (H = aspect R), the same star and planet on the same orbit in the plane z = 0, the same boundary zones as
// cylindrical shells. RSPH regularizes onto the cubic lattice inside the flared disk |z| <= surface H(R), whose
// cones close the cells at the disk's surface: no lattice site, and so no particle, fills the empty space above
// the disk, and the particle count follows the gas. Plain SPH stacks equal-mass particles in columns at the
// profile's mass quantiles.
#include "common/disk_sites.hpp"
#include "rsph/paper/keplerian_zones.hpp"
#include "rsph/paper/star_planet.hpp"
#include "rsph/rsph.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace rsph::scenes {

/// The vertical structure of a disk with c_s = aspect v_K(R) in hydrostatic equilibrium: rho(R, z) = Sigma_0 /
/// (R I) exp((R / r - 1) / aspect^2), r = sqrt(R^2 + z^2), the same shape in zeta = z / R at every R. I is the
/// integral of that shape over |zeta| <= zeta_max, so that the column inside the surface holds Sigma_0.
class VerticalProfile {
 public:
  VerticalProfile(double aspect, double zeta_max, int n = 4096) : aspect_(aspect), zeta_max_(zeta_max), cdf_(n + 1) {
    require(aspect > 0.0 && zeta_max > 0.0 && n >= 2, "vertical profile: need c_s / v_K > 0 and a surface above 0");
    const double d = 2.0 * zeta_max / n;
    cdf_[0] = 0.0;
    for (int k = 0; k < n; ++k) {  // Simpson on each interval
      const double a = -zeta_max + k * d;
      cdf_[k + 1] = cdf_[k] + d / 6.0 * (shape(a) + 4.0 * shape(a + 0.5 * d) + shape(a + d));
    }
  }
  /// exp((1 / sqrt(1 + zeta^2) - 1) / aspect^2): 1 in the plane, about exp(-zeta^2 / (2 aspect^2)) above it.
  double shape(double zeta) const { return std::exp((1.0 / std::sqrt(1.0 + zeta * zeta) - 1.0) / (aspect_ * aspect_)); }
  /// The integral I of the shape over the column.
  double integral() const { return cdf_.back(); }
  double density(const Vec<3>& x, double sigma0) const {
    const double R = std::hypot(x.x(), x.y());
    return sigma0 / (R * integral()) * shape(x.z() / R);
  }
  /// The column's mass-weighted rms of zeta = z / R: about aspect (H / R) for a surface a few H up.
  double rms_zeta() const {
    const auto n = cdf_.size() - 1;
    const double d = 2.0 * zeta_max_ / static_cast<double>(n);
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double z = -zeta_max_ + (static_cast<double>(k) + 0.5) * d;
      sum += z * z * (cdf_[k + 1] - cdf_[k]);
    }
    return std::sqrt(sum / integral());
  }
  /// zeta below which the fraction f of the column lies.
  double zeta_at_fraction(double f) const {
    const double target = f * integral();
    const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), target);
    const auto k = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(it - cdf_.begin(), 1, std::ssize(cdf_) - 1));
    const double d = 2.0 * zeta_max_ / static_cast<double>(cdf_.size() - 1);
    const double w = (target - cdf_[k - 1]) / std::max(cdf_[k] - cdf_[k - 1], 1e-300);
    return -zeta_max_ + (static_cast<double>(k - 1) + w) * d;
  }

 private:
  double aspect_, zeta_max_;
  std::vector<double> cdf_;
};

/// The 3D disk's cubic box, open on every axis, with the plane z = 0 on cell faces (sites at z = +-Delta / 2).
inline Box<3> disk_box_3d(double r_out, double spacing) {
  const double half = spacing * std::ceil((r_out + 1.0) / spacing);
  Box<3> b;
  b.lo = Vec<3>::Constant(-half);
  b.hi = Vec<3>::Constant(half);
  b.edge = {Edge::open, Edge::open, Edge::open};
  return b;
}

/// RSPH's start: the cubic lattice's sites inside the flared disk, on circular orbits of the zones' rotation law
/// Omega(R, z). Each column of sites holds Sigma_0 Delta^2, shared in proportion to the profile's density at its
/// sites: the surface density is exact where the scale height is not resolved (H = 0.02 at r = 0.4).
inline ParticleSet<3, false> flared_disk_lattice(const Box<3>& box, double spacing, double h, double r_in, double r_out,
                                                 double slope, const VerticalProfile& profile, double sigma0,
                                                 const paper::KeplerianZones& zones) {
  const lattice::Cubic lat{spacing};
  Box<2> plane;  // the cubic lattice's columns are the square lattice's sites in the box's plane
  plane.lo = box.lo.head<2>();
  plane.hi = box.hi.head<2>();
  const auto range = lat.cells_touching(box, Vec<3>(0.0, 0.0, -slope * r_out), Vec<3>(0.0, 0.0, slope * r_out));
  ParticleSet<3, false> p;
  std::vector<Vec<3>> column;
  std::vector<double> weight;
  examples::for_each_site_in_annulus(lattice::Square{spacing}, plane, r_in, r_out, [&](const Vec<2>& xy, double) {
    column.clear();
    weight.clear();
    double total = 0.0;
    for (std::int64_t k = range.lo[2]; k <= range.hi[2]; ++k) {
      const Vec<3> x(xy.x(), xy.y(), lat.site(box, {0, 0, k}).z());
      if (std::abs(x.z()) > slope * xy.norm()) continue;
      column.push_back(x);
      weight.push_back(profile.density(x, sigma0));
      total += weight.back();
    }
    for (std::size_t c = 0; c < column.size(); ++c)
      p.add(sigma0 * spacing * spacing * weight[c] / total, column[c], zones.velocity(column[c]), h);
  });
  return p;
}

/// Plain SPH's start: equal-mass particles in columns on the square lattice of spacing `spacing` in the plane,
/// n_z in each at the profile's mass quantiles (k + 1/2) / n_z, so that the column holds Sigma_0 spacing^2 and
/// every particle the same mass; h from eta and the local density.
inline ParticleSet<3, false> flared_disk_columns(const Box<2>& plane, double spacing, int n_z, double eta, double r_in,
                                                 double r_out, const VerticalProfile& profile, double sigma0,
                                                 const paper::KeplerianZones& zones) {
  std::vector<double> zeta(static_cast<std::size_t>(n_z));
  for (int k = 0; k < n_z; ++k) zeta[static_cast<std::size_t>(k)] = profile.zeta_at_fraction((k + 0.5) / n_z);
  const double m = sigma0 * spacing * spacing / n_z;
  ParticleSet<3, false> p;
  examples::for_each_site_in_annulus(lattice::Square{spacing}, plane, r_in, r_out, [&](const Vec<2>& xy, double) {
    const double R = xy.norm();
    for (const double z : zeta) {
      const Vec<3> x(xy.x(), xy.y(), z * R);
      p.add(m, x, zones.velocity(x), eta * std::cbrt(m / profile.density(x, sigma0)));
    }
  });
  return p;
}

/// The disk's thickness against hydrostatic equilibrium's: the mass-weighted rms of z / R over R_lo <= R <= R_hi,
/// over the profile's (1 in equilibrium; the lattice's first sample of a thin disk reads what its sites resolve).
/// `sum` adds the two sums over the ranks (a decomposed run's own particles), or leaves them.
template <bool E, class Sum = void (*)(std::vector<double>&)>
double thickness_ratio(
    const ParticleSet<3, E>& p, const VerticalProfile& profile, double R_lo, double R_hi,
    Sum&& sum = [](std::vector<double>&) {}) {
  double mz2 = 0.0, m = 0.0;
  for (std::size_t a = 0; a < p.n_real; ++a) {
    const double R = std::hypot(p.x[a].x(), p.x[a].y());
    if (R < R_lo || R > R_hi) continue;
    mz2 += p.m[a] * (p.x[a].z() / R) * (p.x[a].z() / R);
    m += p.m[a];
  }
  std::vector<double> sums{mz2, m};
  sum(sums);
  return sums[1] > 0.0 ? std::sqrt(sums[0] / sums[1]) / profile.rms_zeta() : 0.0;
}

/// The particles seen from above: positions (x, y), masses and smoothing lengths; what the 2D disk's
/// measurements (the SPH sum of Sigma on a polar grid, the maps and cuts) read in 3D. A 2D set is itself.
template <bool E>
const ParticleSet<2, E>& seen_from_above(const ParticleSet<2, E>& p) {
  return p;
}
template <bool E>
ParticleSet<2, false> seen_from_above(const ParticleSet<3, E>& p) {
  ParticleSet<2, false> q;
  for (std::size_t a = 0; a < p.n_real; ++a)
    q.add(p.m[a], Vec<2>(p.x[a].x(), p.x[a].y()), Vec<2>(p.v[a].x(), p.v[a].y()), p.h[a]);
  return q;
}

}  // namespace rsph::scenes
