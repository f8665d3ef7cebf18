#pragma once
// The old cells of a 3D second-order remap, as cells.hpp keeps the 2D ones: each cell's volume, centroid and
// central second moments, and its Voronoi neighbours with the shared faces' areas (the builder labels every
// face with the particle whose bisector made it). A polyhedron costs too much to keep, so each cell's pieces
// on the lattice are listed as it is built, by volume and first and second moments, for the hand-out.
#include "rsph/core/particle_set.hpp"
#include "rsph/geometry/moments.hpp"
#include "rsph/geometry/polyhedron.hpp"
#include "rsph/regularize/old_cells_3d.hpp"
#include "rsph/regularize/remap.hpp"
#include "rsph/regularize/second_order/cells.hpp"

#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

namespace rsph::regularize::second_order {

inline PieceMoments<3> piece_moments(const geometry::Moments3& m) {
  PieceMoments<3> p;
  p.area = m.volume;
  p.first = m.first;
  p.second = m.second;
  return p;
}

/// Per-thread buffers of the 3D collection: which cells a thread built, and their faces.
struct FacesByThread {
  struct alignas(64) Part {
    std::vector<std::uint32_t> who, count;
    std::vector<Face<3>> faces;
    detail::LatticePieceScratch pieces;
    std::array<geometry::ConvexPolyhedron, 2> closed;  ///< the cell cut by the region
  };
  std::vector<Part> parts;
};

/// Cell a's faces with a neighbour: the neighbour's offset d from a, the nearest image across periodic axes of
/// the site whose bisector holds the face (twice the face's foot from a), weighted by the face's area. Faces
/// on walls and on the closing polyhedron have none.
template <bool E>
void add_faces(const ParticleSet<3, E>& p, const Box<3>& box, std::size_t a, const geometry::ConvexPolyhedron& cell,
               std::vector<Face<3>>& faces) {
  for (int f = 0; f < cell.nf; ++f) {
    const std::int32_t b = cell.label[static_cast<std::size_t>(f)];
    if (b < 0) continue;
    const Vec<3> area = geometry::area_vector(cell, f);
    const double A = area.norm();
    if (!(A > 0.0)) continue;
    const Vec<3> n = area / A;
    const Vec<3> predicted = 2.0 * n.dot(cell[cell.corner[cell.face_start[static_cast<std::size_t>(f)]]]) * n;
    faces.push_back(
        {static_cast<std::uint32_t>(b), image_offset<3>(p.x[a], p.x[static_cast<std::size_t>(b)], predicted, box), A});
  }
}

/// The builder's visitor: each cell's geometry into the store, its faces and lattice pieces into its thread's
/// buffers.
template <class Lattice, bool E, class Region, class W>
struct KeepCells3 {
  const ParticleSet<3, E>* p;
  const Lattice* lattice;
  const Box<3>* box;
  const detail::CellGrid<3>* grid;
  const Region* region;
  W* ws;
  void restart() {
    for (auto& t : ws->faces_by_thread.parts) {
      t.who.clear();
      t.count.clear();
      t.faces.clear();
    }
    for (auto& t : ws->threads) t.pieces.clear();
  }
  void operator()(int thread, std::size_t a, const geometry::ConvexPolyhedron& built) {
    const auto t = static_cast<std::size_t>(thread);
    auto& own = ws->faces_by_thread.parts[t];
    const geometry::ConvexPolyhedron* closed = &built;
    if constexpr (Region::clips) {
      geometry::ConvexPolyhedron* cut = &own.closed[0];
      geometry::ConvexPolyhedron* spare = &own.closed[1];
      *cut = built;
      region->clip(p->x[a], cut, spare);
      closed = cut;
    }
    const geometry::ConvexPolyhedron& cell = *closed;
    const std::size_t before = own.faces.size();
    add_faces(*p, *box, a, cell, own.faces);
    own.who.push_back(static_cast<std::uint32_t>(a));
    own.count.push_back(static_cast<std::uint32_t>(own.faces.size() - before));
    auto& pieces = ws->threads[t].pieces;
    const std::size_t first = pieces.flat.size();
    // the cell's geometry is the sum of its kept pieces', as the hand-out takes it: no second pass over the cell
    const double crumb = 1e-13 * geometry::volume(cell);
    geometry::Moments3 kept;
    detail::for_each_lattice_piece<geometry::MomentMeasure>(*lattice, *box, *grid, p->x[a], cell, own.pieces,
                                                            [&](std::int64_t flat, const geometry::Moments3& m) {
                                                              if (!(m.volume > crumb)) return;
                                                              if (flat < 0) throw detail::beyond_grid_3d(a);
                                                              pieces.flat.push_back(static_cast<std::size_t>(flat));
                                                              pieces.moments.push_back(piece_moments(m));
                                                              kept += m;
                                                            });
    set_geometry<3>(ws->cells, a, piece_moments(kept));
    ws->cells.reach[a] = detail::cell_reach(cell);
    ws->piece_thread[a] = static_cast<std::uint32_t>(thread);
    ws->piece_first[a] = static_cast<std::uint32_t>(first);
    ws->piece_count[a] = static_cast<std::uint32_t>(pieces.flat.size() - first);
  }
};

/// 3D: builds every old cell (or those `only` names) once (closed by the region), keeps its geometry and faces in
/// ws.cells and lists its pieces on the cells of `grid` (ws.threads[t].pieces, ws.piece_*); a cell not built has no
/// volume and no pieces.
template <class Lattice, class Builder, bool E, class Region, class W>
void collect_cells_and_pieces(const ParticleSet<3, E>& p, const Box<3>& box, const Lattice& lattice, Builder& builder,
                              const RemapParams& params, const Region& region, const detail::CellGrid<3>& grid,
                              std::vector<double>& closing, W& ws, std::span<const std::uint32_t> only = {}) {
  const std::size_t n = p.n_real;
  detail::set_closing_radii(p, box, params, closing);
  const auto n_threads = static_cast<std::size_t>(std::max(geometry::builder_threads(), max_threads()));
  ws.faces_by_thread.parts.resize(n_threads);
  ws.threads.resize(n_threads);
  ws.piece_thread.assign(n, 0);
  ws.piece_first.assign(n, 0);
  ws.piece_count.assign(n, 0);
  CellStore<3>& s = ws.cells;
  s.volume.assign(n, 0.0);
  s.reach.assign(n, -1.0);
  s.centroid.resize(n);
  s.inertia.resize(n);
  KeepCells3<Lattice, E, Region, W> keep{&p, &lattice, &box, &grid, &region, &ws};
  keep.restart();
  builder.build(p.x, box, closing, keep, only);
  s.start.assign(n + 1, 0);
  for (const auto& t : ws.faces_by_thread.parts)
    for (std::size_t k = 0; k < t.who.size(); ++k) s.start[t.who[k] + 1] = t.count[k];
  std::partial_sum(s.start.begin(), s.start.end(), s.start.begin());
  s.faces.resize(s.start[n]);
  for (const auto& t : ws.faces_by_thread.parts) {
    std::size_t from = 0;
    for (std::size_t k = 0; k < t.who.size(); ++k) {
      std::copy_n(t.faces.begin() + static_cast<std::ptrdiff_t>(from), t.count[k],
                  s.faces.begin() + static_cast<std::ptrdiff_t>(s.start[t.who[k]]));
      from += t.count[k];
    }
  }
}

}  // namespace rsph::regularize::second_order
