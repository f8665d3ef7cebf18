#pragma once
// Lattices new particles are created on: their sites and cells (the cells tile the line, the plane or space).
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/geometry/polygon.hpp"

#include <cmath>
#include <concepts>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

namespace rsph {

/// Integer index range [lo, hi] per axis.
template <int D>
struct IndexRange {
  std::array<std::int64_t, D> lo{}, hi{};
};

/// A regularization lattice with spacing Delta: sites indexed by integers, each owning a cell.
/// `cell` returns the cell in coordinates relative to `origin`.
template <class L, int D>
concept RegularLattice = requires(const L& l, const Box<D>& box, const Vec<D>& lo, const Vec<D>& hi,
                                  std::array<std::int64_t, D> idx) {
  { L::dim } -> std::convertible_to<int>;
  { l.spacing } -> std::convertible_to<double>;
  { l.cell_volume() } -> std::same_as<double>;
  { l.cells_touching(box, lo, hi) } -> std::same_as<IndexRange<D>>;  ///< every cell meeting [lo, hi]
  { l.site(box, idx) } -> std::same_as<Vec<D>>;
  { l.periods(box) } -> std::same_as<std::array<std::int64_t, D>>;  ///< cells per periodic axis (0: not periodic)
};

/// The new cells of a lattice whose sites each own a cell of their own (2D), placed for one remap: how many,
/// each site, its cell relative to a point (whether its bounding box meets a box, a bound on its diameter),
/// the area a full cell holds (for the hand-on of nearly empty cells), the sites next to one, the site whose
/// cell most likely holds a point (the remap clips it first), and the candidates whose cells may overlap a
/// polygon.
template <class S>
concept SiteCells = requires(const S& s, std::size_t c, const geometry::ConvexPolygon& polygon, const Vec<2>& x,
                             const geometry::Bounds& box) {
  { s.n_cells } -> std::convertible_to<std::size_t>;
  { s.site(c) } -> std::same_as<Vec<2>>;
  { s.cell(c, x) } -> std::same_as<geometry::ConvexPolygon>;
  { s.box_meets(c, x, box) } -> std::same_as<bool>;
  { s.diameter(c) } -> std::same_as<double>;
  { s.nearest_site(x) } -> std::same_as<std::size_t>;
  { s.nominal_area(c) } -> std::same_as<double>;
  s.for_each_neighbour(c, [](std::size_t) {});
  s.for_each_candidate(polygon, x, [](std::size_t) {});
};

/// A lattice whose sites are placed anew at every remap for the gas being remapped (lattice::Rings follows
/// its orbits): `following(x, m, reach)` gives the SiteCells for gas at x of masses m whose old cells reach
/// at most `reach` beyond their particles.
template <class L>
concept PerSiteLattice = requires(const L& l, std::span<const Vec<2>> x, std::span<const double> m, double reach) {
  requires L::per_site_cells;
  { l.following(x, m, reach) } -> SiteCells;
};

/// What a LatticeRegularizer takes as its lattice: a dimension and a spacing Delta, and either the sites
/// and cells of one level (RegularLattice), levels in factors of two (`finest()`, lattice::MultiLevel) or
/// sites with cells of their own (PerSiteLattice).
template <class L>
concept RegularizationLattice = requires(const L& l) {
  { L::dim } -> std::convertible_to<int>;
  { l.spacing } -> std::convertible_to<double>;
}
&&(RegularLattice<L, L::dim> || requires(const L& l) { l.finest(); } || PerSiteLattice<L>);

/// What the remap asks of a lattice's cells beyond the concept: in 1D each cell's bounds; in 2D and 3D whether
/// the cells are the boxes between grid lines (then the lines), or, in 2D, one convex shape moved to every site.
template <class L, int D>
constexpr bool check_lattice_cells() {
  if constexpr (D == 1) {
    static_assert(
        requires(const L& l, const Box<1>& box, std::int64_t i) {
          { l.cell(box, i) } -> std::same_as<std::pair<double, double>>;
        },
        "a 1D regularization lattice needs `std::pair<double, double> cell(box, i)`: the bounds of cell i");
  } else {
    static_assert(
        requires {
          { L::rectangular_cells } -> std::convertible_to<bool>;
        },
        "a regularization lattice needs `static constexpr bool rectangular_cells`: whether its cells are the boxes "
        "between grid lines");
    if constexpr (requires {
                    { L::rectangular_cells } -> std::convertible_to<bool>;
                  }) {
      if constexpr (L::rectangular_cells)
        static_assert(
            requires(const L& l, const Box<D>& box, int axis, std::int64_t i, double origin) {
              { l.line(box, axis, i, origin) } -> std::same_as<double>;
            },
            "a lattice of rectangular cells needs `double line(box, axis, index, origin)`: grid line `index` along "
            "`axis` (cell i spans lines i and i + 1), relative to `origin`");
      else
        static_assert(
            D == 2 &&
                requires(const L& l, const Box<D>& box, std::array<std::int64_t, D> idx, const Vec<D>& origin) {
                  { l.cell_shape() } -> std::same_as<geometry::ConvexPolygon>;
                  { l.cell(box, idx, origin) } -> std::same_as<geometry::ConvexPolygon>;
                },
            "a lattice whose cells are not rectangles needs `geometry::ConvexPolygon cell_shape() const` (every cell "
            "that shape moved to its site) and `cell(box, index, origin)`; in 3D only rectangular cells are remapped");
    }
  }
  return true;
}

template <class L>
constexpr bool check_lattice() {
  static_assert(
      requires {
        { L::dim } -> std::convertible_to<int>;
      },
      "a regularization lattice needs `static constexpr int dim`");
  static_assert(
      requires(const L& l) {
        { l.spacing } -> std::convertible_to<double>;
      },
      "a regularization lattice needs a spacing `double spacing` (Delta)");
  if constexpr (requires {
                  { L::dim } -> std::convertible_to<int>;
                })
    static_assert(
        RegularLattice<L, L::dim> || requires(const L& l) { l.finest(); } || PerSiteLattice<L>,
        "a regularization lattice needs `cell_volume()`, `cells_touching(box, lo, hi)`, `site(box, index)` "
        "and `periods(box)` (one level), `finest()` (levels in factors of two, lattice::MultiLevel), or "
        "`per_site_cells` and `following(x, m, reach)` giving sites with cells of their own (lattice::Rings), "
        "whose result has `n_cells`, `site(c)`, `cell(c, origin)`, `box_meets(c, origin, bounds)`, `diameter(c)`, "
        "`nominal_area(c)`, `for_each_neighbour(c, f)` and `for_each_candidate(polygon, origin, f)`");
  if constexpr (requires {
                  { L::dim } -> std::convertible_to<int>;
                })
    if constexpr (RegularLattice<L, L::dim>) static_assert(check_lattice_cells<L, L::dim>());
  return true;
}

namespace lattice {

namespace detail {
template <int D>
std::int64_t cells_along(const Box<D>& box, int k, double pitch, const char* name) {
  const double L = box.hi[k] - box.lo[k];
  const double n = L / pitch;
  const auto rounded = static_cast<std::int64_t>(std::llround(n));
  require(rounded >= 1 && std::abs(n - static_cast<double>(rounded)) < 1e-9 * std::max(1.0, n),
          std::string(name) + " lattice: the box length along axis " + std::to_string(k) + " (" + std::to_string(L) +
              ") must be a whole number of lattice rows (pitch " + std::to_string(pitch) + ")");
  return rounded;
}
/// Cells per periodic axis of a lattice of cubes of side `spacing` (0 on other axes); every closed axis must hold
/// a whole number of cells.
template <int D>
std::array<std::int64_t, D> rectangular_periods(const Box<D>& box, double spacing, const char* name) {
  std::array<std::int64_t, D> p{};
  for (int k = 0; k < D; ++k)
    if (box.edge[k] != Edge::open) {
      const auto n = cells_along(box, k, spacing, name);
      if (box.periodic(k)) p[static_cast<std::size_t>(k)] = n;
    }
  return p;
}
}  // namespace detail

/// Uniform 1D lattice: sites at lo + (i + 1/2) Delta, cells [lo + i Delta, lo + (i + 1) Delta].
struct Uniform1D {
  static constexpr int dim = 1;
  double spacing;

  double cell_volume() const { return spacing; }
  IndexRange<1> cells_touching(const Box<1>& box, const Vec<1>& lo, const Vec<1>& hi) const {
    return {{floor_index((lo[0] - box.lo[0]) / spacing)}, {floor_index((hi[0] - box.lo[0]) / spacing)}};
  }
  Vec<1> site(const Box<1>& box, std::array<std::int64_t, 1> i) const {
    return Vec<1>(box.lo[0] + (i[0] + 0.5) * spacing);
  }
  std::array<std::int64_t, 1> periods(const Box<1>& box) const {
    if (box.edge[0] == Edge::open) return {0};
    const double n = (box.hi[0] - box.lo[0]) / spacing;
    const auto rounded = static_cast<std::int64_t>(std::llround(n));
    require(rounded >= 1 && std::abs(n - static_cast<double>(rounded)) < 1e-9 * std::max(1.0, n),
            "uniform lattice: the box length must be a whole number of spacings (" + std::to_string(n) + ")");
    return {box.edge[0] == Edge::periodic ? rounded : 0};
  }
  /// Cell bounds [a, b] of site i, absolute.
  std::pair<double, double> cell(const Box<1>& box, std::int64_t i) const {
    return {box.lo[0] + i * spacing, box.lo[0] + (i + 1) * spacing};
  }
};

/// Square lattice of spacing Delta: sites at lo + ((i + 1/2) Delta, (j + 1/2) Delta), square cells.
struct Square {
  static constexpr int dim = 2;
  double spacing;

  double cell_volume() const { return spacing * spacing; }
  IndexRange<2> cells_touching(const Box<2>& box, const Vec<2>& lo, const Vec<2>& hi) const {
    IndexRange<2> r;
    for (int k = 0; k < 2; ++k) {
      r.lo[k] = floor_index((lo[k] - box.lo[k]) / spacing);
      r.hi[k] = floor_index((hi[k] - box.lo[k]) / spacing);
    }
    return r;
  }
  Vec<2> site(const Box<2>& box, std::array<std::int64_t, 2> idx) const {
    return Vec<2>(box.lo[0] + (idx[0] + 0.5) * spacing, box.lo[1] + (idx[1] + 0.5) * spacing);
  }
  std::array<std::int64_t, 2> periods(const Box<2>& box) const {
    return detail::rectangular_periods(box, spacing, "square");
  }
  /// The cell of idx relative to `origin`.
  geometry::ConvexPolygon cell(const Box<2>& box, std::array<std::int64_t, 2> idx, const Vec<2>& origin) const {
    const double x0 = box.lo[0] + idx[0] * spacing - origin[0], y0 = box.lo[1] + idx[1] * spacing - origin[1];
    return geometry::ConvexPolygon::rectangle(x0, y0, x0 + spacing, y0 + spacing);
  }
  /// Rectangular cells: the grid line `index` along `axis` (cells span lines i to i + 1), relative to `origin`.
  double line(const Box<2>& box, int axis, std::int64_t index, double origin) const {
    return box.lo[axis] + static_cast<double>(index) * spacing - origin;
  }
  static constexpr bool rectangular_cells = true;
};

/// Hexagonal lattice of nearest-neighbour distance Delta: rows Delta sqrt(3)/2 apart, odd rows shifted by
/// Delta/2; cells are regular hexagons of area Delta^2 sqrt(3)/2. Periodic y needs an even row count.
struct Hexagonal {
  static constexpr int dim = 2;
  double spacing;

  double row_pitch() const { return spacing * 0.86602540378443864676; }
  double cell_volume() const { return spacing * row_pitch(); }
  IndexRange<2> cells_touching(const Box<2>& box, const Vec<2>& lo, const Vec<2>& hi) const {
    IndexRange<2> r;
    // Row j's hexagons span (j + 1/2 -+ 2/3) row pitches in y; in x, hexagon i spans (i - 1/4, i + 3/4)
    // spacings on even rows and half a spacing more on odd ones. A cell that only touches [lo, hi] along a
    // line may be left out (it overlaps nothing).
    r.lo[1] = floor_index((lo[1] - box.lo[1]) / row_pitch() - 7.0 / 6.0) + 1;
    r.hi[1] = -floor_index(-((hi[1] - box.lo[1]) / row_pitch() + 1.0 / 6.0)) - 1;
    r.lo[0] = floor_index((lo[0] - box.lo[0]) / spacing - 1.25) + 1;
    r.hi[0] = -floor_index(-((hi[0] - box.lo[0]) / spacing + 0.25)) - 1;
    return r;
  }
  Vec<2> site(const Box<2>& box, std::array<std::int64_t, 2> idx) const {
    const double shift = (idx[1] & 1) ? 0.5 : 0.0;
    return Vec<2>(box.lo[0] + (idx[0] + 0.25 + shift) * spacing, box.lo[1] + (idx[1] + 0.5) * row_pitch());
  }
  std::array<std::int64_t, 2> periods(const Box<2>& box) const {
    std::array<std::int64_t, 2> p{0, 0};
    if (box.edge[0] != Edge::open) {
      const auto n = detail::cells_along(box, 0, spacing, "hexagonal");
      if (box.periodic(0)) p[0] = n;
    }
    if (box.edge[1] != Edge::open) {
      const auto n = detail::cells_along(box, 1, row_pitch(), "hexagonal");
      require(!box.periodic(1) || n % 2 == 0, "hexagonal lattice: a periodic y axis needs an even number of rows");
      if (box.periodic(1)) p[1] = n;
    }
    return p;
  }
  /// Every cell is this hexagon moved to its site: pointed along y, vertices at R (cos, sin)(30 + 60 k
  /// degrees) with the circumradius R = Delta / sqrt(3) (inradius Delta / 2).
  geometry::ConvexPolygon cell_shape() const {
    const double half = 0.5 * spacing, R = spacing / std::numbers::sqrt3;
    geometry::ConvexPolygon h;
    h.push(Vec<2>(half, 0.5 * R));
    h.push(Vec<2>(0.0, R));
    h.push(Vec<2>(-half, 0.5 * R));
    h.push(Vec<2>(-half, -0.5 * R));
    h.push(Vec<2>(0.0, -R));
    h.push(Vec<2>(half, -0.5 * R));
    return h;
  }
  /// The cell of idx relative to `origin`.
  geometry::ConvexPolygon cell(const Box<2>& box, std::array<std::int64_t, 2> idx, const Vec<2>& origin) const {
    geometry::ConvexPolygon h = cell_shape();
    h.translate(site(box, idx) - origin);
    return h;
  }
  static constexpr bool rectangular_cells = false;
};

/// Cubic lattice of spacing Delta: sites at lo + ((i + 1/2) Delta, (j + 1/2) Delta, (k + 1/2) Delta), cubic cells.
struct Cubic {
  static constexpr int dim = 3;
  double spacing;

  double cell_volume() const { return spacing * spacing * spacing; }
  IndexRange<3> cells_touching(const Box<3>& box, const Vec<3>& lo, const Vec<3>& hi) const {
    IndexRange<3> r;
    for (int k = 0; k < 3; ++k) {
      r.lo[k] = floor_index((lo[k] - box.lo[k]) / spacing);
      r.hi[k] = floor_index((hi[k] - box.lo[k]) / spacing);
    }
    return r;
  }
  Vec<3> site(const Box<3>& box, std::array<std::int64_t, 3> idx) const {
    return Vec<3>(box.lo[0] + (idx[0] + 0.5) * spacing, box.lo[1] + (idx[1] + 0.5) * spacing,
                  box.lo[2] + (idx[2] + 0.5) * spacing);
  }
  std::array<std::int64_t, 3> periods(const Box<3>& box) const {
    return detail::rectangular_periods(box, spacing, "cubic");
  }
  /// Rectangular cells: the lattice plane `index` along `axis` (cells span planes i to i + 1), relative to
  /// `origin`.
  double line(const Box<3>& box, int axis, std::int64_t index, double origin) const {
    return box.lo[axis] + static_cast<double>(index) * spacing - origin;
  }
  static constexpr bool rectangular_cells = true;
};

/// The Cartesian lattice of each dimension: Uniform1D, Square, Cubic.
template <int D>
using Cartesian = std::conditional_t<D == 1, Uniform1D, std::conditional_t<D == 2, Square, Cubic>>;

}  // namespace lattice
}  // namespace rsph

#include "rsph/regularize/rings.hpp"  // lattice::Rings: sites with cells of their own
