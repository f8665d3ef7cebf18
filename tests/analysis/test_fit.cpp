#include "rsph/analysis/fit.hpp"

#include <catch2/catch.hpp>

using namespace rsph;

TEST_CASE("least-squares slope: exact on a line, numpy's value on scattered points, errors named", "[analysis]") {
  CHECK(analysis::least_squares_slope({0.0, 1.0, 2.0, 3.0}, {1.0, 3.0, 5.0, 7.0}) == Approx(2.0).epsilon(1e-14));
  // scattered points: the value numpy.polyfit gives
  CHECK(analysis::least_squares_slope({0.0, 1.0, 2.0, 3.0}, {0.5, -1.5, -1.5, -2.5}) == Approx(-0.9));
  CHECK_THROWS_WITH(analysis::least_squares_slope({1.0}, {2.0}), Catch::Contains("two or more points"));
  CHECK_THROWS_WITH(analysis::least_squares_slope({1.0, 1.0}, {2.0, 3.0}), Catch::Contains("all x are equal"));
}
