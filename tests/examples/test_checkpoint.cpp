// Checkpoints: N steps, a checkpoint, a fresh simulation restored from it and N more steps equal 2N steps
// to the bit, for a fixed-step scene (Kelvin-Helmholtz, regularized every 48 steps), the disk (Appendix A's
// schedule, individual time steps, boundary zones, particles leaving; with and without a switched viscosity)
// and a multi-level lattice with consistent gradients (the strong shock on levels).
#include "kelvin_helmholtz/scene.hpp"
#include "planet_disk/scene.hpp"
#include "rsph/io/checkpoint.hpp"
#include "strong_shock/scene.hpp"

#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>

using namespace rsph;

namespace {

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// Every field of the real particles, the clocks and the regularization log of a and b agree bit for bit.
template <class Sim>
void check_identical(const Sim& a, const Sim& b) {
  const auto& p = a.particles();
  const auto& q = b.particles();
  REQUIRE(p.n_real == q.n_real);
  auto real = [](const auto& field, std::size_t n) { return std::vector(field.begin(), field.begin() + long(n)); };
  const std::size_t n = p.n_real;
  CHECK(same_bits(real(p.x, n), real(q.x, n)));
  CHECK(same_bits(real(p.v, n), real(q.v, n)));
  CHECK(same_bits(real(p.m, n), real(q.m, n)));
  CHECK(same_bits(real(p.h, n), real(q.h, n)));
  CHECK(same_bits(real(p.rho, n), real(q.rho, n)));
  CHECK(same_bits(real(p.dv_dt, n), real(q.dv_dt, n)));
  if constexpr (Sim::has_energy) CHECK(same_bits(real(p.u, n), real(q.u, n)));
  CHECK(same_bits(std::vector{a.time()}, std::vector{b.time()}));
  CHECK(a.steps() == b.steps());
  CHECK(a.particle_updates() == b.particle_updates());
  CHECK(a.regularizations() == b.regularizations());
  if constexpr (requires { a.regularizer().log(); }) {
    REQUIRE(a.regularizer().log().size() == b.regularizer().log().size());
    for (std::size_t k = 0; k < a.regularizer().log().size(); ++k) {
      CHECK(a.regularizer().log()[k].step == b.regularizer().log()[k].step);
      CHECK(a.regularizer().log()[k].stats.n_after == b.regularizer().log()[k].stats.n_after);
      CHECK(a.regularizer().log()[k].stats.per_level == b.regularizer().log()[k].stats.per_level);
    }
  }
}

/// make() twice: one runs 2n calls of step_once; the other runs n, is checkpointed to a file, and a third
/// simulation restored from that file runs the other n. Returns the regularizations in each half.
template <class Make, class StepOnce>
std::pair<std::uint64_t, std::uint64_t> resume_matches(Make&& make, StepOnce&& step_once, int n) {
  auto whole = make();
  for (int k = 0; k < 2 * n; ++k) step_once(whole);
  auto first = make();
  for (int k = 0; k < n; ++k) step_once(first);
  const auto file = std::filesystem::temp_directory_path() / "rsph_test_checkpoint.h5";
  {
    auto ar = io::Archive::for_saving();
    first.checkpoint(ar);
    ar.write(file);
  }
  auto resumed = make();
  {
    auto ar = io::Archive::load(file);
    resumed.checkpoint(ar);
  }
  std::filesystem::remove(file);
  for (int k = 0; k < n; ++k) step_once(resumed);
  check_identical(whole, resumed);
  return {first.regularizations(), whole.regularizations() - first.regularizations()};
}

}  // namespace

TEST_CASE("checkpoint: Kelvin-Helmholtz (fixed steps, second-order remap) resumes bit for bit",
          "[examples][checkpoint]") {
  scenes::KelvinHelmholtzParams s;
  s.cells = 48;
  s.wavelengths = 1;
  const auto [before, after] = resume_matches([&] { return scenes::make_rsph_kh(s, regularize::SecondOrder{}); },
                                              [](auto& sim) { sim.step(); }, 60);
  CHECK(before == 1);  // the checkpoint falls between regularizations 1 and 2
  CHECK(after == 1);
}

TEST_CASE("checkpoint: the disk (Appendix A, individual time steps, leaving gas) resumes bit for bit",
          "[examples][checkpoint][disk]") {
  scenes::PlanetDiskParams s;
  s.particles = 3000;
  const lattice::Square lat{s.spacing()};
  const eos::LocallyIsothermal<scenes::DiskSoundSpeed> eos(scenes::DiskSoundSpeed{s.aspect, 1.0});
  const double r_lo = s.r_in - s.spacing(), r_hi = s.r_out + s.spacing();
  std::size_t removed = 0;
  auto step_once = [&](auto& sim) {
    sim.step();
    examples::remove_particles(
        sim, [&](const Vec<2>& x) { return x.squaredNorm() < r_lo * r_lo || x.squaredNorm() > r_hi * r_hi; }, removed);
  };
  for (const double alpha : {0.0, 1.0}) {  // with the switched viscosity, whose factors a block's substeps read
    s.rsph_alpha = alpha;
    s.rsph_beta = 2.0 * alpha;
    const auto [before, after] = resume_matches([&] { return scenes::make_rsph_disk(s, lat, eos); }, step_once, 40);
    CHECK(before >= 1);
    CHECK(after >= 1);
  }
}

TEST_CASE("checkpoint: the strong shock on levels (consistent gradients) resumes bit for bit",
          "[examples][checkpoint]") {
  scenes::StrongShockParams s;
  s.nx = 128;
  s.ny = 8;
  s.refinement.levels = 1;
  s.refinement.block_cells = 4;
  s.max_steps = 20;
  const auto [before, after] =
      resume_matches([&] { return scenes::make_rsph_levels_shock(s); }, [](auto& sim) { sim.step(); }, 30);
  CHECK(before >= 1);
  CHECK(after >= 1);
}

TEST_CASE("checkpoint: a missing file or field is refused by name", "[checkpoint]") {
  CHECK_THROWS_WITH(io::Archive::load("/nonexistent/checkpoint.h5"), Catch::Contains("no checkpoint"));
  const auto file = std::filesystem::temp_directory_path() / "rsph_test_checkpoint_fields.h5";
  {
    auto ar = io::Archive::for_saving();
    double t = 1.5;
    std::vector<std::uint64_t> ids{1, 2, 3};
    ar("time", t);
    ar("ids", ids);
    ar.write(file);
  }
  auto ar = io::Archive::load(file);
  double t = 0.0;
  std::vector<std::uint64_t> ids;
  ar("time", t);
  ar("ids", ids);
  CHECK(t == 1.5);
  CHECK(ids == std::vector<std::uint64_t>{1, 2, 3});
  double missing = 0.0;
  CHECK_THROWS_WITH(ar("nowhere/step", missing), Catch::Contains("no field 'nowhere/step'"));
  CHECK_THROWS_WITH(ar("ids", t), Catch::Contains("wrong type"));
  std::filesystem::remove(file);
}
