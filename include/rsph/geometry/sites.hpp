#pragma once
// What the Voronoi cell builders of every dimension share: the sites (the particles and their periodic
// images), the checks of their positions, the mean spacing, and the build that widens the images until
// every cell's security sphere lies inside them.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace rsph::geometry {

/// The points a cell builder sees: the real particles, then periodic images (with their sources).
template <int D>
struct PeriodicSites {
  std::vector<Vec<D>> x;
  std::vector<std::uint32_t> source;
  std::size_t n_real = 0;
  double margin = 0.0;  ///< images cover this distance beyond each periodic face
};

/// Number of threads the builders use (visitors keep per-thread state).
inline int builder_threads() { return max_threads(); }

namespace detail {

/// The box a cell is cut from, relative to the particle at xa, as (lo, hi): the box (walls), the box widened by
/// the image margin (periodic), the cube circumscribing the closing sphere (open axes).
template <int D>
std::pair<Vec<D>, Vec<D>> initial_bounds(const Vec<D>& xa, const Box<D>& box, double margin, double closing_radius) {
  Vec<D> lo, hi;
  for (int k = 0; k < D; ++k) {
    if (box.edge[k] == Edge::open) {
      lo[k] = -closing_radius;
      hi[k] = closing_radius;
    } else {
      const double widen = box.periodic(k) ? margin : 0.0;
      lo[k] = box.lo[k] - widen - xa[k];
      hi[k] = box.hi[k] + widen - xa[k];
    }
  }
  return {lo, hi};
}

/// Throws for the first particle (lowest index) that is not finite or lies outside a closed axis.
template <int D>
inline void check_sites(const std::vector<Vec<D>>& x, const Box<D>& box) {
  // 0: fine, 1: not finite, 2 + k: outside along axis k
  auto problem = [&](std::size_t a) {
    if (!x[a].allFinite()) return 1;
    for (int k = 0; k < D; ++k)
      if (box.edge[k] != Edge::open && (x[a][k] < box.lo[k] || x[a][k] > box.hi[k])) return 2 + k;
    return 0;
  };
  std::vector<std::size_t> first_bad(static_cast<std::size_t>(max_threads()), x.size());
  run_parallel(x.size(), [&](int t, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a)
      if (problem(a) != 0) {
        first_bad[static_cast<std::size_t>(t)] = a;
        return;
      }
  });
  const std::size_t a = *std::min_element(first_bad.begin(), first_bad.end());
  if (a == x.size()) return;
  const int what = problem(a);
  if (what == 1) throw InputError("Voronoi cells: particle " + std::to_string(a) + " has a non-finite position");
  throw InputError("Voronoi cells: particle " + std::to_string(a) + " lies outside the domain along axis " +
                   std::to_string(what - 2));
}

/// Fills `s` with the particles and their periodic images (reusing its storage from call to call). Both
/// are written in parallel; the images come in the order of a serial pass (by particle, then by shift),
/// each thread writing its particles' images from the count of those before them on.
template <int D>
inline void add_periodic_images(const std::vector<Vec<D>>& x, const Box<D>& box, double margin, PeriodicSites<D>& s) {
  const std::size_t n_real = x.size();
  s.n_real = n_real;
  s.margin = margin;
  s.x.resize(n_real);
  s.source.resize(n_real);
  run_parallel(n_real, [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      s.x[a] = x[a];
      s.source[a] = static_cast<std::uint32_t>(a);
    }
  });
  for (int k = 0; k < D; ++k) {
    if (!box.periodic(k)) continue;
    const double L = box.hi[k] - box.lo[k], lo = box.lo[k] - margin, hi = box.hi[k] + margin;
    const auto reach = static_cast<int>(std::ceil(margin / L));  // a wide margin needs several periods
    // calls f(shifted point) for each image of point i that lies within the margin, shifts ascending
    auto for_each_image = [&](std::size_t i, auto&& f) {
      const double c = s.x[i][k];
      if (c - L >= lo || c + L <= hi || reach > 1)  // almost every point has no image at all
        for (int shift = -reach; shift <= reach; ++shift) {
          const double shifted = c + shift * L;
          if (shift == 0 || shifted < lo || shifted > hi) continue;
          Vec<D> p = s.x[i];
          p[k] = shifted;
          f(p);
        }
    };
    const std::size_t n = s.x.size();
    run_parallel_packed(
        n,
        [&](std::size_t begin, std::size_t end) {
          std::size_t count = 0;
          for (std::size_t i = begin; i < end; ++i) for_each_image(i, [&](const Vec<D>&) { ++count; });
          return count;
        },
        [&](std::size_t n_images) {
          s.x.resize(n + n_images);
          s.source.resize(n + n_images);
        },
        [&](int, std::size_t begin, std::size_t end, std::size_t first) {
          std::size_t at = n + first;
          for (std::size_t i = begin; i < end; ++i)
            for_each_image(i, [&](const Vec<D>& p) {
              s.x[at] = p;
              s.source[at++] = s.source[i];
            });
        });
  }
}

/// Mean spacing of n points over the part of the box they span: their bounding box, clipped to the box on
/// closed and periodic axes. A rank's particles fill a small part of the box, and the box's volume over their
/// count would start every cell's search √P times too wide.
template <int D>
inline double mean_spacing(const std::vector<Vec<D>>& x, const Box<D>& box) {
  Vec<D> lo = box.lo, hi = box.hi;
  if (!x.empty()) {
    Vec<D> plo = x.front(), phi = x.front();
    for (const auto& p : x) {
      plo = plo.cwiseMin(p);
      phi = phi.cwiseMax(p);
    }
    for (int k = 0; k < D; ++k) {
      const bool open = box.edge[k] == Edge::open;
      lo[k] = open ? plo[k] : std::max(plo[k], box.lo[k]);
      hi[k] = open ? phi[k] : std::min(phi[k], box.hi[k]);
    }
  }
  const double n = static_cast<double>(std::max<std::size_t>(x.size(), 1));
  // A set thinner than its spacing (collinear on an open axis) has the spacing along its length: the volume's
  // would be tiny, and every cell's search would start from nothing.
  const double along = (hi - lo).maxCoeff() / n;
  const double per_site = std::max((hi - lo).prod(), 0.0) / n;
  double spacing = per_site;
  if constexpr (D == 2) spacing = std::sqrt(per_site);
  if constexpr (D == 3) spacing = std::cbrt(per_site);
  return std::max(spacing, std::max(along, 1e-300));
}

/// Whether a cell may be missing a periodic image: its security sphere (twice its farthest vertex
/// distance, whose square is r2_max) reaches beyond the band the images cover. Then the margin is widened
/// and cells rebuilt.
template <int D>
inline bool needs_more_images(double r2_max, const Vec<D>& xa, const Box<D>& box, double margin) {
  const double security = 2.0 * std::sqrt(r2_max);
  for (int k = 0; k < D; ++k)
    if (box.periodic(k) && (xa[k] - security < box.lo[k] - margin || xa[k] + security > box.hi[k] + margin))
      return true;
  return false;
}

/// Runs try_build(margin) with periodic images over a margin of 4 mean spacings (at most 4 periods), doubling it (and
/// calling visit.restart()) until every cell's security disc is covered.
template <int D, class Visitor, class TryBuild>
void build_widening_images(const std::vector<Vec<D>>& x, const Box<D>& box, Visitor& visit, TryBuild&& try_build) {
  check_sites(x, box);
  // Four spacings, but never more than four periods (beyond which the widening below gives up anyway): a
  // particle far out on an open axis inflates the mean spacing, and images over a margin of thousands of periods
  // would number in the millions.
  double period = 0.0;
  for (int k = 0; k < D; ++k)
    if (box.periodic(k)) period = std::max(period, box.hi[k] - box.lo[k]);
  double margin = 4.0 * mean_spacing(x, box);
  if (period > 0.0) margin = std::min(margin, 4.0 * period);
  for (int attempt = 0;; ++attempt) {
    if (attempt > 0) visit.restart();
    if (try_build(margin)) return;
    margin *= 2.0;
    // Cells wider than twice the box: the set is too sparse to mean anything periodic. A cluster far smaller than
    // the box starts from its own spacing and doubles up to the box: tens of tries, each cheap for so few points.
    bool fits = true;
    for (int k = 0; k < D; ++k) fits &= !box.periodic(k) || margin < 4.0 * (box.hi[k] - box.lo[k]);
    if (!fits || attempt > 64)
      throw NumericalError("Voronoi cells: periodic cells wider than the box; too few particles for a periodic domain");
  }
}

/// The public face of both builders: build(x, box, closing_radius, visit, only) runs the builder's
/// try_build(x, box, closing_radius, margin, visit, only) with images widened until they suffice. Every
/// particle is a site; `only` (ascending, empty for all) names the particles whose cells are visited.
template <class Builder>
class WideningBuilder {
 public:
  template <int D, class Visitor>
  void build(const std::vector<Vec<D>>& x, const Box<D>& box, const std::vector<double>& closing_radius,
             Visitor&& visit, std::span<const std::uint32_t> only = {}) {
    auto& self = static_cast<Builder&>(*this);
    build_widening_images(x, box, visit,
                          [&](double margin) { return self.try_build(x, box, closing_radius, margin, visit, only); });
  }
};

/// How many cells a build visits, and the particle of the k-th: `only` or, when empty, all n.
inline std::size_t chosen_count(std::size_t n, std::span<const std::uint32_t> only) {
  return only.empty() ? n : only.size();
}
inline std::size_t chosen(std::span<const std::uint32_t> only, std::size_t k) {
  return only.empty() ? k : static_cast<std::size_t>(only[k]);
}

}  // namespace detail
}  // namespace rsph::geometry
