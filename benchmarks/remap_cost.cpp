// Runs a fixed number of remaps of a benchmark set, untimed, for a cost model to count: on a shared machine
// timings drift by tens of per cent, instruction and branch counts do not. scripts/remap-cost.sh runs this
// under cachegrind with one and with three remaps and reports the difference per remap.
//
//   remap_cost LAYOUT PARTICLES REMAPS [ORDER]   (LAYOUT: jittered or sheared; ORDER: first or second)
//
// Every run copies the set three times, whatever REMAPS is, so that the difference holds remaps only.
#include "remap_sets.hpp"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

using namespace rsph;

namespace {
long whole_number(const char* text, const std::string& what) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  require(end != text && *end == '\0', what + " must be a whole number (got '" + text + "')");
  return value;
}
}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc != 4 && argc != 5)
      throw InputError("usage: remap_cost jittered|sheared PARTICLES REMAPS [first|second] (REMAPS from 0 to 3)");
    const std::string order = argc == 5 ? argv[4] : "first";
    require(order == "first" || order == "second", "the order is first or second");
    const std::string layout = argv[1];
    require(layout == "jittered" || layout == "sheared", "the layout is jittered or sheared");
    const long n = whole_number(argv[2], "PARTICLES");
    const long remaps = whole_number(argv[3], "REMAPS");
    require(n >= 16, "at least 16 particles");
    require(remaps >= 0 && remaps <= 3, "from 0 to 3 remaps");
    const auto p0 = bench::make_set(n, layout == "jittered" ? bench::jittered : bench::sheared);
    const lattice::Square square{bench::spacing_of(p0)};
    geometry::LocalVoronoi builder;
    regularize::RemapWorkspace<2> workspace;
    regularize::second_order::Workspace<2> second;
    auto p = p0;
    std::size_t n_after = 0;
    for (int k = 0; k < 3; ++k) {
      p = p0;
      if (k < remaps)
        n_after = order == "second" ? regularize::remap_second_order(p, bench::domain(), square, builder, {}, {},
                                                                     region::Unbounded{}, &workspace, &second)
                                          .n_after
                                    : regularize::remap_onto_lattice(p, bench::domain(), square, builder, {},
                                                                     region::Unbounded{}, &workspace)
                                          .n_after;
    }
    std::printf("%zu old particles, %ld remaps, %zu new particles\n", p0.n_real, remaps, n_after);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "remap_cost: %s\n", e.what());
    return 1;
  }
}
