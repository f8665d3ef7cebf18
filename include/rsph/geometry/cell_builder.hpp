#pragma once
// The cell builder policy axis: what a Voronoi cell builder offers, and the builder a lattice of each dimension
// gets by default (LocalVoronoi in 2D, LocalVoronoi3 in 3D; 1D cells are intervals and need none).
#include "rsph/core/dimension.hpp"
#include "rsph/geometry/voronoi.hpp"
#include "rsph/geometry/voronoi3d.hpp"

#include <vector>

namespace rsph::geometry {

namespace detail {
/// A visitor of the builders' protocol, for the concept below.
struct CellProbe {
  template <class Cell>
  void operator()(int, std::size_t, const Cell&) {}
  void restart() {}
};
}  // namespace detail

/// A Voronoi cell builder for D dimensions: build(x, box, closing_radius, visit) hands visit(thread, a, cell)
/// the cell of each particle (relative to x[a]: a ConvexPolygon in 2D, a ConvexPolyhedron in 3D), closed
/// against the box's walls and open edges.
template <class B, int D>
concept CellBuilder = requires(B& b, const std::vector<Vec<D>>& x, const Box<D>& box, const std::vector<double>& r,
                               detail::CellProbe visit) {
  b.build(x, box, r, visit);
};

template <class B, int D>
constexpr bool check_cell_builder() {
  static_assert(D == 1 || CellBuilder<B, D>,
                "a Voronoi cell builder needs `void build(const std::vector<Vec<D>>& x, const Box<D>& box, const "
                "std::vector<double>& closing_radius, Visitor&& visit)` calling visit(thread, a, cell) per particle, "
                "for the lattice's dimension D");
  return true;
}

/// The builder a lattice of dimension D is given unless another is named.
template <int D>
struct DefaultCellBuilder {
  using type = LocalVoronoi;
};
template <>
struct DefaultCellBuilder<3> {
  using type = LocalVoronoi3;
};

}  // namespace rsph::geometry
