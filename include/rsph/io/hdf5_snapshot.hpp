#pragma once
// HDF5 snapshots: one dataset per field (x and v shaped N x dim), attributes `time`, `step` and `dim`; each
// with an XDMF description beside it (xdmf.hpp), so that ParaView, VisIt and meshio open it directly.
#include "rsph/core/particle_set.hpp"
#include "rsph/io/atomic_file.hpp"
#include "rsph/io/xdmf.hpp"

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
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
}  // namespace detail

/// Writes the real particles of `p` to `path` (atomically): x, v (N x D), m, rho, h, P, and u when the
/// gas carries it, index (0 .. N-1: rows, not identities, as a remap renews every particle), in 1D also xyz (N x 3, the
/// positions on the x axis, for viewers that need two or three); attributes time, step and dim. Then snap_NNNNN.xmf
/// beside it and the folder's snapshots.xmf.
template <int D, bool E>
void write_snapshot(const std::filesystem::path& path, const ParticleSet<D, E>& p, double time, std::uint64_t step) {
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
    if constexpr (D == 1) {
      std::vector<double> xyz(3 * n, 0.0);
      for (std::size_t a = 0; a < n; ++a) xyz[3 * a] = p.x[a][0];
      detail::write_dataset(file.id(), "xyz", xyz.data(), n, 3);
    }
    detail::write_attribute(file.id(), "time", time, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE);
    detail::write_attribute(file.id(), "step", static_cast<std::uint64_t>(step), H5T_NATIVE_UINT64, H5T_STD_U64LE);
    detail::write_attribute(file.id(), "dim", static_cast<std::uint64_t>(D), H5T_NATIVE_UINT64, H5T_STD_U64LE);
    file.close();
  }
  commit_file(tmp, path);
  std::vector<XdmfField> fields{{"v", D}, {"m", 1}, {"rho", 1}, {"h", 1}, {"P", 1}};
  if constexpr (E) fields.push_back({"u", 1});
  write_xdmf(path, p.n_real, time, D == 1 ? "xyz" : "x", D == 1 ? 3 : D, fields);
}

/// snap_00042.h5
inline std::string snapshot_name(std::size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "snap_%05zu.h5", index);
  return buf;
}

}  // namespace rsph::io
