#pragma once
// HDF5 snapshots: one dataset per field (x and v shaped N x dim), attributes `time`, `step` and `dim`; each
// with an XDMF description beside it (xdmf.hpp), so that ParaView, VisIt and meshio open it directly. Several
// processes (the ranks of a decomposed run, mpi::FileTurns) write one file in the same layout, each its own rows:
// the first creates every dataset at its full length and the others add theirs in turn, or, with parallel HDF5,
// all create it together and write their rows in one collective call per dataset.
#include "rsph/core/particle_set.hpp"
#include "rsph/io/atomic_file.hpp"
#include "rsph/io/writing_turns.hpp"
#include "rsph/io/xdmf.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsph::io {

namespace detail {
class H5File {
 public:
  /// Creates the file `path` with file access list `access` (the default, or MPI-IO's for many processes).
  explicit H5File(const std::filesystem::path& path, hid_t access = H5P_DEFAULT) {
    id_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access);
    if (id_ < 0) throw std::runtime_error("cannot create HDF5 file " + path.string());
  }
  ~H5File() {
    if (id_ >= 0) H5Fclose(id_);
  }
  H5File(const H5File&) = delete;
  H5File& operator=(const H5File&) = delete;
  hid_t id() const { return id_; }
  void close() {
    if (id_ >= 0 && H5Fclose(id_) < 0) throw std::runtime_error("HDF5 close failed");
    id_ = -1;
  }

 private:
  hid_t id_ = -1;
};

/// One dataset of a snapshot with this process's rows of it: `cols` numbers per row (0: one, a vector dataset),
/// doubles or 64-bit unsigned integers.
struct Column {
  std::string name;
  hsize_t cols = 0;
  std::vector<double> d;
  std::vector<std::uint64_t> u;
  bool integer = false;

  hsize_t rows() const { return (integer ? u.size() : d.size()) / std::max<hsize_t>(cols, 1); }
};

/// Writes each column's rows from row `first` of its dataset in `file` with transfer list `transfer`; with
/// `total` (not on a later turn), the dataset is created first with that many rows. Every column is visited
/// whatever failed, so that processes writing together make the same calls.
inline bool write_rows(hid_t file, const std::vector<Column>& columns, hsize_t first, std::optional<hsize_t> total,
                       hid_t transfer = H5P_DEFAULT) {
  bool ok = true;
  for (const auto& c : columns) {
    hid_t set = -1;
    if (total) {
      const hsize_t dims[2] = {*total, c.cols};
      const hid_t space = H5Screate_simple(c.cols == 0 ? 1 : 2, dims, nullptr);
      set = H5Dcreate2(file, c.name.c_str(), c.integer ? H5T_STD_U64LE : H5T_IEEE_F64LE, space, H5P_DEFAULT,
                       H5P_DEFAULT, H5P_DEFAULT);
      H5Sclose(space);
    } else {
      set = H5Dopen2(file, c.name.c_str(), H5P_DEFAULT);
    }
    if (set < 0) {
      ok = false;
      continue;
    }
    const void* values = c.integer ? static_cast<const void*>(c.u.data()) : static_cast<const void*>(c.d.data());
    ok =
        write_slab(set, c.integer ? H5T_NATIVE_UINT64 : H5T_NATIVE_DOUBLE, first, c.rows(), c.cols, values, transfer) &&
        ok;
    ok = H5Dclose(set) >= 0 && ok;
  }
  return ok;
}

template <class T>
inline void write_attribute(hid_t file, const std::string& name, T value, hid_t mem_type, hid_t file_type) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(file, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t status = attr >= 0 ? H5Awrite(attr, mem_type, &value) : -1;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  if (status < 0) throw std::runtime_error("HDF5: writing attribute " + name + " failed");
}
inline void write_string_attribute(hid_t file, const std::string& name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, std::max<std::size_t>(value.size(), 1));
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(file, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  std::string padded = value;
  padded.resize(std::max<std::size_t>(value.size(), 1), '\0');
  const herr_t status = attr >= 0 ? H5Awrite(attr, type, padded.data()) : -1;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
  if (status < 0) throw std::runtime_error("HDF5: writing attribute " + name + " failed");
}

inline void write_array_attribute(hid_t file, const std::string& name, const std::vector<double>& values) {
  const hsize_t n = values.size();
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t attr = H5Acreate2(file, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t status = attr >= 0 ? H5Awrite(attr, H5T_NATIVE_DOUBLE, values.data()) : -1;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  if (status < 0) throw std::runtime_error("HDF5: writing attribute " + name + " failed");
}
}  // namespace detail

/// What a reader needs beside the fields: the domain, the gas, the unit system and the scene's bodies.
struct SnapshotInfo {
  std::vector<double> box_lo, box_hi, periodic;  ///< per axis; periodic 1 or 0
  std::string edges;                             ///< per axis: open, periodic or reflecting, comma-separated
  std::string eos;                               ///< the equation of state, in words
  std::vector<std::pair<std::string, double>> eos_constants;
  std::string units = "dimensionless code units";
  std::vector<std::pair<std::string, std::vector<double>>> objects;  ///< bodies by name: their positions
};

/// The domain and gas of a run with box `box` and equation of state `eos`, in the unit system `units`.
template <int D, class EOS>
SnapshotInfo describe_run(const Box<D>& box, const EOS& eos, std::string units) {
  SnapshotInfo info;
  const char* edge_names[] = {"open", "periodic", "reflecting"};
  for (int k = 0; k < D; ++k) {
    info.box_lo.push_back(box.lo[k]);
    info.box_hi.push_back(box.hi[k]);
    info.periodic.push_back(box.periodic(k) ? 1.0 : 0.0);
    info.edges += std::string(k ? "," : "") + edge_names[static_cast<int>(box.edge[k])];
  }
  info.eos = EOS::name;
  eos.describe([&](const char* name, double value) { info.eos_constants.emplace_back(name, value); });
  info.units = std::move(units);
  return info;
}

namespace detail {
inline void write_info(hid_t file, const SnapshotInfo& info) {
  if (!info.box_lo.empty()) {
    write_array_attribute(file, "box_lo", info.box_lo);
    write_array_attribute(file, "box_hi", info.box_hi);
    write_array_attribute(file, "periodic", info.periodic);
    write_string_attribute(file, "edges", info.edges);
  }
  if (!info.eos.empty()) write_string_attribute(file, "eos", info.eos);
  for (const auto& [name, value] : info.eos_constants)
    write_attribute(file, "eos_" + name, value, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE);
  write_string_attribute(file, "units", info.units);
  for (const auto& [name, position] : info.objects) write_array_attribute(file, "object_" + name, position);
}
}  // namespace detail

namespace detail {
/// The datasets of a snapshot with the real particles of `p` as its rows from `first` on.
template <int D, bool E>
std::vector<Column> snapshot_columns(const ParticleSet<D, E>& p, std::uint64_t first) {
  const std::size_t n = p.n_real;
  std::vector<Column> c;
  const auto vectors = [&](const std::vector<Vec<D>>& field, const char* name) {
    Column col{name, D, std::vector<double>(n * D), {}, false};
    for (std::size_t a = 0; a < n; ++a)
      for (int k = 0; k < D; ++k) col.d[a * D + static_cast<std::size_t>(k)] = field[a][k];
    c.push_back(std::move(col));
  };
  const auto scalars = [&](const std::vector<double>& field, const char* name) {
    c.push_back(
        {name, 0, std::vector<double>(field.begin(), field.begin() + static_cast<std::ptrdiff_t>(n)), {}, false});
  };
  vectors(p.x, "x");
  vectors(p.v, "v");
  scalars(p.m, "m");
  scalars(p.rho, "rho");
  scalars(p.h, "h");
  scalars(p.P, "P");
  if constexpr (E) scalars(p.u, "u");
  Column index{"index", 1, {}, std::vector<std::uint64_t>(n), true};  // each row's number: a viewer's polyvertex
  for (std::size_t a = 0; a < n; ++a) index.u[a] = first + a;
  c.push_back(std::move(index));
  if (p.id.size() >= n)
    c.push_back(
        {"id", 1, {}, std::vector<std::uint64_t>(p.id.begin(), p.id.begin() + static_cast<std::ptrdiff_t>(n)), true});
  if constexpr (D == 1) {
    Column xyz{"xyz", 3, std::vector<double>(3 * n, 0.0), {}, false};
    for (std::size_t a = 0; a < n; ++a) xyz.d[3 * a] = p.x[a][0];
    c.push_back(std::move(xyz));
  }
  return c;
}

/// Creates the snapshot file `tmp` with every column at `total` rows, writes this process's rows at `first` and
/// the attributes, through `turns`' access and transfer lists; false where that failed.
template <int D, WritingTurns Turns>
bool create_snapshot(const std::filesystem::path& tmp, const std::vector<Column>& columns, hsize_t first, hsize_t total,
                     double time, std::uint64_t step, const SnapshotInfo& info, const Turns& turns) {
  try {
    H5File file(tmp, turns.file_access());
    const bool ok = write_rows(file.id(), columns, first, total, turns.transfer());
    write_attribute(file.id(), "time", time, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE);
    write_attribute(file.id(), "step", step, H5T_NATIVE_UINT64, H5T_STD_U64LE);
    write_attribute(file.id(), "dim", static_cast<std::uint64_t>(D), H5T_NATIVE_UINT64, H5T_STD_U64LE);
    write_info(file.id(), info);
    file.close();
    return ok;
  } catch (const std::runtime_error&) {
    return false;
  }
}

/// Adds this process's rows at `first` to the snapshot file `tmp` another process created.
inline bool add_snapshot_rows(const std::filesystem::path& tmp, const std::vector<Column>& columns, hsize_t first) {
  const hid_t file = H5Fopen(tmp.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return false;
  const bool ok = write_rows(file, columns, first, std::nullopt);
  return H5Fclose(file) >= 0 && ok;
}
}  // namespace detail

/// Writes the real particles of `p` to `path` (atomically): x, v (N x D), m, rho, h, P, and u when the
/// gas carries it, index (0 .. N-1, the rows) and id (each particle's identity, renewed by a remap), in 1D also
/// xyz (N x 3, the positions on the x axis, for viewers that need two or three); attributes time, step and dim,
/// and what `info` gives: box_lo, box_hi, periodic and edges, eos and its constants eos_NAME, units, and each
/// body's position object_NAME. Then snap_NNNNN.xmf beside it and the folder's snapshots.xmf.
/// Written by several processes (`turns`; every one calls it with the same path, time, step and info), the file
/// holds every process's particles in process order, and each process only its own in memory; if one fails, all
/// throw.
template <int D, bool E, WritingTurns Turns = OneWriter>
void write_snapshot(const std::filesystem::path& path, const ParticleSet<D, E>& p, double time, std::uint64_t step,
                    const SnapshotInfo& info = {}, const Turns& turns = {}) {
  const std::uint64_t n = p.n_real, first = turns.first_rows({n}).at(0), total = turns.total_rows({n}).at(0);
  const auto columns = detail::snapshot_columns(p, first);
  const auto tmp = temporary_sibling(path);
  const auto commit = [&] {
    try {
      commit_file(tmp, path);
      std::vector<XdmfField> fields{{"v", D}, {"m", 1}, {"rho", 1}, {"h", 1}, {"P", 1}};
      if constexpr (E) fields.push_back({"u", 1});
      write_xdmf(path, total, time, D == 1 ? "xyz" : "x", D == 1 ? 3 : D, fields);
      return true;
    } catch (const std::runtime_error&) {
      return false;
    }
  };
  write_in_turns(
      turns, tmp, [&] { return detail::create_snapshot<D>(tmp, columns, first, total, time, step, info, turns); },
      [&] { return detail::add_snapshot_rows(tmp, columns, first); }, commit,
      "writing the snapshot " + path.string() + " failed");
}

/// The snapshot of a simulation: its particles, time and step, its box and gas, in `units`, with `objects`.
template <class Sim>
void write_snapshot(const std::filesystem::path& path, const Sim& sim, std::string units,
                    std::vector<std::pair<std::string, std::vector<double>>> objects = {}) {
  auto info = describe_run(sim.box(), sim.eos(), std::move(units));
  info.objects = std::move(objects);
  write_snapshot(path, sim.particles(), sim.time(), sim.steps(), info);
}

/// snap_00042.h5
inline std::string snapshot_name(std::size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "snap_%05zu.h5", index);
  return buf;
}

}  // namespace rsph::io
