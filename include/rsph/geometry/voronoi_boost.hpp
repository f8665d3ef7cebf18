#pragma once
// The Boost.Polygon builder of 2D Voronoi cells (see voronoi.hpp): Voronoi neighbours from construct_voronoi on
// quantized positions, each cell cut by their bisectors in double precision. The fallback of LocalVoronoi for
// nearly collinear sets, and its oracle in the tests.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/core/parallel.hpp"
#include "rsph/geometry/polygon.hpp"
#include "rsph/geometry/sites.hpp"
#include "rsph/geometry/voronoi_cells2d.hpp"
#include "rsph/neighbors/cell_list.hpp"

#include <boost/polygon/voronoi.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace rsph::geometry {

/// Boost.Polygon builder: Voronoi neighbours from construct_voronoi on quantized positions, cells cut
/// in double precision. Same visitor protocol as LocalVoronoi.
class BoostVoronoi : public detail::WideningBuilder<BoostVoronoi> {
 public:
  static constexpr double quantization_levels = 1073741824.0;  ///< 2^30 steps over the extent of the points

 private:
  friend class detail::WideningBuilder<BoostVoronoi>;

  /// The chosen particles (ascending) with a site of their own or an adjacent group closer than 1e4 quanta:
  /// there the quantized diagram's neighbours may not be the true ones (pairs 1e-9 of a spacing apart; far
  /// outliers that coarsen the quanta), so their cells are checked against every site that can cut them.
  static std::vector<std::uint32_t> doubtful_cells(const SitesWithImages& sites,
                                                   const std::vector<std::uint32_t>& group_of,
                                                   const std::vector<std::vector<std::uint32_t>>& members,
                                                   const std::vector<std::vector<std::uint32_t>>& adjacent,
                                                   double quantum, std::span<const std::uint32_t> only) {
    const double close2 = (1e4 * quantum) * (1e4 * quantum);
    std::vector<std::uint32_t> doubtful;
    for (std::size_t k = 0; k < detail::chosen_count(sites.n_real, only); ++k) {
      const std::size_t a = detail::chosen(only, k);
      bool close = false;
      auto near = [&](std::uint32_t group) {
        for (const std::uint32_t b : members[group])
          close = close || (b != a && (sites.x[b] - sites.x[a]).squaredNorm() < close2);
      };
      near(group_of[a]);
      for (const std::uint32_t nb : adjacent[group_of[a]]) near(nb);
      if (close) doubtful.push_back(static_cast<std::uint32_t>(a));
    }
    std::sort(doubtful.begin(), doubtful.end());
    return doubtful;
  }

  template <class Visitor>
  bool try_build(const std::vector<Point>& x, const Box<2>& box, const std::vector<double>& closing_radius,
                 double margin, Visitor& visit, std::span<const std::uint32_t> only) {
    SitesWithImages sites;
    detail::add_periodic_images(x, box, margin, sites);
    const std::size_t n_sites = sites.x.size();
    // Quantize; points that share integer coordinates form one group (Boost keeps one of them).
    Point lo = sites.x[0], hi = sites.x[0];
    for (const auto& p : sites.x) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
    const double scale = quantization_levels / extent;
    std::vector<boost::polygon::point_data<int>> unique;
    std::vector<std::uint32_t> group_of(n_sites);
    std::vector<std::vector<std::uint32_t>> members;
    std::unordered_map<std::uint64_t, std::uint32_t> index_of;
    index_of.reserve(n_sites);
    for (std::size_t i = 0; i < n_sites; ++i) {
      const auto qx = static_cast<int>(std::llround((sites.x[i].x() - lo.x()) * scale));
      const auto qy = static_cast<int>(std::llround((sites.x[i].y() - lo.y()) * scale));
      const std::uint64_t key = (static_cast<std::uint64_t>(qx) << 32) | static_cast<std::uint32_t>(qy);
      auto [it, fresh] = index_of.emplace(key, static_cast<std::uint32_t>(unique.size()));
      if (fresh) {
        unique.emplace_back(qx, qy);
        members.emplace_back();
      }
      group_of[i] = it->second;
      members[it->second].push_back(static_cast<std::uint32_t>(i));
    }
    boost::polygon::voronoi_diagram<double> vd;
    boost::polygon::construct_voronoi(unique.begin(), unique.end(), &vd);
    std::vector<std::vector<std::uint32_t>> adjacent(unique.size());
    for (const auto& c : vd.cells()) {
      const auto* e = c.incident_edge();
      if (!e) continue;
      auto& adj = adjacent[c.source_index()];
      do {
        adj.push_back(static_cast<std::uint32_t>(e->twin()->cell()->source_index()));
        e = e->next();
      } while (e != c.incident_edge());
    }
    const auto doubtful = doubtful_cells(sites, group_of, members, adjacent, extent / quantization_levels, only);
    neighbors::CellList<2> lookup;  // only where quantization may have hidden a neighbour
    if (!doubtful.empty()) lookup.build(sites.x, detail::mean_spacing(x, box));
    std::atomic<bool> ok{true};
    rsph::run_parallel(detail::chosen_count(sites.n_real, only), [&](int thread, std::size_t begin, std::size_t end) {
      ConvexPolygon buffers[2];
      for (std::size_t k = begin; k < end && ok.load(std::memory_order_relaxed); ++k) {
        const std::size_t a = detail::chosen(only, k);
        const Point xa = sites.x[a];
        const double closing = closing_radius.empty() ? 0.0 : closing_radius[a];
        ConvexPolygon* cell = &buffers[0];
        ConvexPolygon* scratch = &buffers[1];
        *cell = detail::initial_cell(xa, box, margin, closing);
        const std::uint32_t g = group_of[a];
        auto cut_group = [&](std::uint32_t group) {
          for (std::uint32_t b : members[group]) {
            if (b == a) continue;
            const Point d = sites.x[b] - xa;
            if (d.squaredNorm() == 0.0) {
              cell->clear();
              return;
            }
            if (detail::cut_by_bisector(*cell, d, *scratch)) std::swap(cell, scratch);
          }
        };
        cut_group(g);
        for (std::uint32_t nb : adjacent[g]) {
          if (cell->empty()) break;
          cut_group(nb);
        }
        if (!cell->empty() && std::binary_search(doubtful.begin(), doubtful.end(), static_cast<std::uint32_t>(a))) {
          // every site that can still cut the cell lies within twice its farthest vertex: cut by them all
          const double reach = 2.0 * std::sqrt(detail::max_radius2_origin(*cell));
          lookup.for_each_within(xa, reach, [&](std::uint32_t b) {
            const Point d = sites.x[b] - xa;
            if (b == a || cell->empty() || d.squaredNorm() >= reach * reach) return;
            if (d.squaredNorm() == 0.0) return cell->clear();
            if (detail::cut_by_bisector(*cell, d, *scratch)) std::swap(cell, scratch);
          });
        }
        if (!detail::finish_cell(cell, scratch, a, xa, box, margin, closing, detail::max_radius2_origin(*cell))) {
          ok.store(false, std::memory_order_relaxed);
          break;
        }
        visit(thread, a, *cell);
      }
    });
    return ok.load();
  }
};

}  // namespace rsph::geometry
