#pragma once
// Run-loop pieces every example shares: the conservation log and snapshot times.
#include "rsph/core/diagnostics.hpp"
#include "rsph/io/csv.hpp"
#include "rsph/io/json.hpp"

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace rsph::examples {

/// conservation.csv: one row per step of the conserved totals.
template <int D>
class ConservationLog {
 public:
  explicit ConservationLog(const std::filesystem::path& path) : csv_(path, columns()) {}
  void record(double time, std::uint64_t step, const Conservation<D>& c) {
    std::array<double, 7 + D> row;  // fixed size: no reallocation for GCC 12's overflow checker to misread
    row[0] = time;
    row[1] = static_cast<double>(step);
    row[2] = c.mass;
    for (int k = 0; k < D; ++k) row[static_cast<std::size_t>(3 + k)] = c.momentum[k];
    row[3 + D] = c.angular_momentum;
    row[4 + D] = c.kinetic;
    row[5 + D] = c.thermal;
    row[6 + D] = c.total_energy();
    csv_.row(std::vector<double>(row.begin(), row.end()));
  }
  void close() { csv_.close(); }

 private:
  static std::vector<std::string> columns() {
    std::vector<std::string> c{"time", "step", "mass"};
    const char* axis[] = {"momentum_x", "momentum_y", "momentum_z"};
    for (int k = 0; k < D; ++k) c.emplace_back(axis[k]);
    c.insert(c.end(), {"angular_momentum", "kinetic", "thermal", "total_energy"});
    return c;
  }
  io::CsvWriter csv_;
};

/// Relative change of a conserved quantity, guarded against a zero reference.
inline double relative_change(double now, double start) {
  return std::abs(now - start) / std::max(std::abs(start), 1e-300);
}

/// The phase timings as a JSON object.
template <class Times>
io::Json phase_json(const Times& t) {
  io::Json j;
  j.set("neighbors", t.neighbors).set("density", t.density).set("forces", t.forces);
  j.set("integrate", t.integrate).set("regularization", t.regularization);
  return j;
}

}  // namespace rsph::examples
