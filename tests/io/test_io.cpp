#include "rsph/io/csv.hpp"
#include "rsph/io/hdf5_snapshot.hpp"
#include "rsph/io/json.hpp"
#include "rsph/rsph.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace rsph;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("rsph-test-io-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

TEST_CASE("HDF5 snapshot: one dataset per field, x and v shaped N x dim, time and step", "[io]") {
  const auto dir = scratch("h5");
  ParticleSet<2, true> p;
  for (int i = 0; i < 5; ++i) p.add(1.0 + i, Vec<2>(i, 2.0 * i), Vec<2>(-i, 0.5), 0.1, 3.0);
  p.P.assign(5, 7.0);
  io::write_snapshot(dir / "snap_00003.h5", p, 1.25, 42);
  REQUIRE(fs::exists(dir / "snap_00003.h5"));
  CHECK(!fs::exists(io::temporary_sibling(dir / "snap_00003.h5")));

  const hid_t f = H5Fopen((dir / "snap_00003.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const hid_t x = H5Dopen2(f, "x", H5P_DEFAULT);
  const hid_t space = H5Dget_space(x);
  hsize_t dims[2];
  CHECK(H5Sget_simple_extent_ndims(space) == 2);
  H5Sget_simple_extent_dims(space, dims, nullptr);
  CHECK(dims[0] == 5);
  CHECK(dims[1] == 2);
  double xs[10];
  H5Dread(x, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, xs);
  CHECK(xs[2 * 3 + 1] == 6.0);
  H5Sclose(space);
  H5Dclose(x);
  for (const char* name : {"v", "m", "rho", "u", "h", "P"}) CHECK(H5Lexists(f, name, H5P_DEFAULT) > 0);
  double t = 0;
  std::uint64_t step = 0;
  const hid_t at = H5Aopen(f, "time", H5P_DEFAULT);
  H5Aread(at, H5T_NATIVE_DOUBLE, &t);
  H5Aclose(at);
  const hid_t as = H5Aopen(f, "step", H5P_DEFAULT);
  H5Aread(as, H5T_NATIVE_UINT64, &step);
  H5Aclose(as);
  CHECK(t == 1.25);
  CHECK(step == 42);
  H5Fclose(f);
}

TEST_CASE("an isothermal snapshot has no u dataset", "[io]") {
  const auto dir = scratch("h5iso");
  ParticleSet<1, false> p;
  p.add(1.0, Vec<1>(0.5), Vec<1>(0.0), 0.1);
  io::write_snapshot(dir / "s.h5", p, 0.0, 0);
  const hid_t f = H5Fopen((dir / "s.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  CHECK(H5Lexists(f, "u", H5P_DEFAULT) == 0);
  CHECK(H5Lexists(f, "rho", H5P_DEFAULT) > 0);
  H5Fclose(f);
}

TEST_CASE("CSV appears only when closed; an abandoned writer leaves nothing", "[io]") {
  const auto dir = scratch("csv");
  {
    io::CsvWriter w(dir / "curve.csv", {"time", "amplitude"});
    w.row({0.0, 1.0});
    CHECK(!fs::exists(dir / "curve.csv"));
  }  // destroyed without close(): a failed run
  CHECK(!fs::exists(dir / "curve.csv"));
  CHECK(fs::is_empty(dir));
  io::CsvWriter w(dir / "curve.csv", {"time", "amplitude"});
  w.row({0.5, 0.25});
  CHECK_THROWS(w.row({1.0}));
  w.close();
  CHECK(slurp(dir / "curve.csv") == "time,amplitude\n0.5,0.25\n");
}

TEST_CASE("summary.json: ordered keys, nested objects, non-finite numbers as null", "[io]") {
  const auto dir = scratch("json");
  io::Json inner;
  inner.set("density", 0.5);
  io::Json j;
  j.set("test", "sod").set("L1_rho", 0.00339).set("steps", std::uint64_t{1215}).set("phase_seconds", inner);
  j.set("bad", std::nan("")).set("list", std::vector<double>{1, 2});
  j.write(dir / "summary.json");
  CHECK(slurp(dir / "summary.json") ==
        "{\n  \"test\": \"sod\",\n  \"L1_rho\": 0.00339,\n  \"steps\": 1215,\n  \"phase_seconds\": {\n    \"density\": "
        "0.5\n  },\n"
        "  \"bad\": null,\n  \"list\": [1, 2]\n}\n");
}
