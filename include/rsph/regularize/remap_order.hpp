#pragma once
// The remap's order, one policy axis of the lattice regularizer: the paper's piecewise-constant hand-out
// (eqs. 6-9) or the limited linear reconstruction of second_order/remap_second.hpp. Both conserve mass,
// momentum and total energy exactly; the second moves less across cells that the flow does not mix.
#include "rsph/regularize/second_order/remap_second_levels.hpp"

#include <concepts>

namespace rsph::regularize {

/// Eqs. (6)-(9): every old cell hands out its mean, in proportion to overlap volume.
struct FirstOrder {
  static constexpr int order = 1;
  static constexpr const char* name = "first";
};

/// Every old cell hands out its linear reconstruction, limited to the range of its neighbourhood.
struct SecondOrder {
  static constexpr int order = 2;
  static constexpr const char* name = "second";
  SecondOrderParams params;
  void validate() const { params.validate(); }
};

template <class R>
concept RemapOrder = requires {
  { R::order } -> std::convertible_to<int>;
  { R::name } -> std::convertible_to<const char*>;
}
&&(R::order == 1 || R::order == 2);

template <class R>
constexpr bool check_remap_order() {
  static_assert(RemapOrder<R>,
                "a remap order needs `static constexpr int order` (1: regularize::FirstOrder, 2: "
                "regularize::SecondOrder) and `static constexpr const char* name`");
  return true;
}

}  // namespace rsph::regularize
