#pragma once
// HDF5 snapshots: one dataset per field (x and v shaped N x dim), attributes `time`, `step` and `dim`; each
// with an XDMF description beside it (xdmf.hpp), so that ParaView, VisIt and meshio open it directly.
#include "rsph/core/particle_set.hpp"
#include "rsph/io/atomic_file.hpp"
#include "rsph/io/xdmf.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsph::io {

namespace detail {
class H5File {
 public:
  explicit H5File(const std::filesystem::path& path) {
    id_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
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

/// rows values (cols == 0) or a rows x cols matrix.
inline void write_dataset(hid_t file, const std::string& name, const double* data, std::size_t rows,
                          std::size_t cols = 0, hid_t file_type = H5T_IEEE_F64LE, hid_t mem_type = H5T_NATIVE_DOUBLE,
                          const void* raw = nullptr) {
  hsize_t dims[2] = {rows, cols};
  const int rank = cols == 0 ? 1 : 2;
  const hid_t space = H5Screate_simple(rank, dims, nullptr);
  const hid_t set = H5Dcreate2(file, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t status =
      set >= 0 ? H5Dwrite(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw ? raw : static_cast<const void*>(data))
               : -1;
  if (set >= 0) H5Dclose(set);
  H5Sclose(space);
  if (status < 0) throw std::runtime_error("HDF5: writing dataset " + name + " failed");
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

/// Writes the real particles of `p` to `path` (atomically): x, v (N x D), m, rho, h, P, and u when the
/// gas carries it, index (0 .. N-1, the rows) and id (each particle's identity, renewed by a remap), in 1D also
/// xyz (N x 3, the positions on the x axis, for viewers that need two or three); attributes time, step and dim,
/// and what `info` gives: box_lo, box_hi, periodic and edges, eos and its constants eos_NAME, units, and each
/// body's position object_NAME. Then snap_NNNNN.xmf
/// beside it and the folder's snapshots.xmf.
template <int D, bool E>
void write_snapshot(const std::filesystem::path& path, const ParticleSet<D, E>& p, double time, std::uint64_t step,
                    const SnapshotInfo& info = {}) {
  const auto tmp = temporary_sibling(path);
  {
    detail::H5File file(tmp);
    const std::size_t n = p.n_real;
    std::vector<double> buf(n * D);
    auto vectors = [&](const std::vector<Vec<D>>& field, const char* name) {
      for (std::size_t a = 0; a < n; ++a)
        for (int k = 0; k < D; ++k) buf[a * D + static_cast<std::size_t>(k)] = field[a][k];
      detail::write_dataset(file.id(), name, buf.data(), n, D);
    };
    vectors(p.x, "x");
    vectors(p.v, "v");
    detail::write_dataset(file.id(), "m", p.m.data(), n);
    detail::write_dataset(file.id(), "rho", p.rho.data(), n);
    detail::write_dataset(file.id(), "h", p.h.data(), n);
    detail::write_dataset(file.id(), "P", p.P.data(), n);
    if constexpr (E) detail::write_dataset(file.id(), "u", p.u.data(), n);
    std::vector<std::uint64_t> index(n);  // each particle's row: the vertices of a viewer's polyvertex
    for (std::size_t a = 0; a < n; ++a) index[a] = a;
    detail::write_dataset(file.id(), "index", nullptr, n, 1, H5T_STD_U64LE, H5T_NATIVE_UINT64, index.data());
    if (p.id.size() >= n)
      detail::write_dataset(file.id(), "id", nullptr, n, 1, H5T_STD_U64LE, H5T_NATIVE_UINT64, p.id.data());
    if constexpr (D == 1) {
      std::vector<double> xyz(3 * n, 0.0);
      for (std::size_t a = 0; a < n; ++a) xyz[3 * a] = p.x[a][0];
      detail::write_dataset(file.id(), "xyz", xyz.data(), n, 3);
    }
    detail::write_attribute(file.id(), "time", time, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE);
    detail::write_attribute(file.id(), "step", static_cast<std::uint64_t>(step), H5T_NATIVE_UINT64, H5T_STD_U64LE);
    detail::write_attribute(file.id(), "dim", static_cast<std::uint64_t>(D), H5T_NATIVE_UINT64, H5T_STD_U64LE);
    detail::write_info(file.id(), info);
    file.close();
  }
  commit_file(tmp, path);
  std::vector<XdmfField> fields{{"v", D}, {"m", 1}, {"rho", 1}, {"h", 1}, {"P", 1}};
  if constexpr (E) fields.push_back({"u", 1});
  write_xdmf(path, p.n_real, time, D == 1 ? "xyz" : "x", D == 1 ? 3 : D, fields);
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
