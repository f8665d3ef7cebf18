#pragma once
// Checkpoints: the whole state a run needs to continue, bit for bit, in one HDF5 file. Whoever owns state
// lists it once in a `checkpoint(Archive&)` member, ar("name", field) per field, and the same list both
// saves and restores it (Simulation, the regularizer, the run loop, a scene's counters and curves). Every
// number keeps its bits: doubles as IEEE doubles, integers as 64-bit integers. The file is written to a
// temporary name and renamed, so a run killed while writing leaves the previous checkpoint whole.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/io/atomic_file.hpp"

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace rsph::io {

namespace detail {
/// HDF5's own error printing off while it lives: the archive reports failures itself, naming the field.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &function_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, function_, data_); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t function_ = nullptr;
  void* data_ = nullptr;
};
}  // namespace detail

/// Saves fields into memory and then to a file, or restores them from a file, with one interface.
class Archive {
 public:
  /// An archive that collects fields; write() puts them in a file.
  static Archive for_saving() { return Archive(); }
  /// An archive that restores fields from `path`; a missing file or field is an InputError naming it.
  static Archive load(const std::filesystem::path& path) {
    Archive ar;
    ar.saving_ = false;
    ar.path_ = path;
    const detail::QuietHdf5 quiet;
    if (!std::filesystem::is_regular_file(path)) throw InputError("no checkpoint '" + path.string() + "'");
    ar.file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (ar.file_ < 0) throw InputError("cannot read the checkpoint '" + path.string() + "'");
    return ar;
  }
  Archive(Archive&& o) noexcept
      : saving_(o.saving_),
        path_(std::move(o.path_)),
        file_(o.file_),
        prefix_(std::move(o.prefix_)),
        fields_(std::move(o.fields_)) {
    o.file_ = -1;
  }
  Archive& operator=(Archive&&) = delete;
  Archive(const Archive&) = delete;
  ~Archive() {
    if (file_ >= 0) H5Fclose(file_);
  }

  bool saving() const { return saving_; }

  /// Fields named inside `name/` while the scope lives: `const auto scope = ar.scope("sim");`.
  class Scope {
   public:
    Scope(Archive& ar, const std::string& name) : ar_(ar), saved_(ar.prefix_) { ar.prefix_ += name + "/"; }
    ~Scope() { ar_.prefix_ = saved_; }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    Archive& ar_;
    std::string saved_;
  };

  Scope scope(const std::string& name) { return Scope(*this, name); }

  /// Saves or restores one field: a number, a string, a vector of numbers or of Eigen vectors.
  template <class T>
  void operator()(const std::string& name, T& value) {
    const std::string key = prefix_ + name;
    if constexpr (std::is_same_v<T, double>) {
      std::vector<double> one{value};
      doubles(key, one);
      value = one.at(0);
    } else if constexpr (std::is_integral_v<T>) {
      std::vector<std::int64_t> one{static_cast<std::int64_t>(value)};
      integers(key, one);
      value = static_cast<T>(one.at(0));
    } else if constexpr (std::is_same_v<T, std::string>) {
      bytes(key, value);
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      doubles(key, value);
    } else if constexpr (std::is_integral_v<typename T::value_type>) {
      std::vector<std::int64_t> all(value.begin(), value.end());
      integers(key, all);
      value.assign(all.begin(), all.end());
    } else {  // std::vector of fixed-size Eigen vectors or matrices
      using E = typename T::value_type;
      constexpr auto k = static_cast<std::size_t>(E::SizeAtCompileTime);
      std::vector<double> flat(value.size() * k);
      for (std::size_t a = 0; a < value.size(); ++a)
        for (std::size_t j = 0; j < k; ++j) flat[a * k + j] = value[a].data()[j];
      doubles(key, flat);
      if (flat.size() % k != 0) throw InputError("checkpoint field '" + key + "' has the wrong shape");
      value.resize(flat.size() / k);
      for (std::size_t a = 0; a < value.size(); ++a)
        for (std::size_t j = 0; j < k; ++j) value[a].data()[j] = flat[a * k + j];
    }
  }

  /// Saves or restores a list, each element's fields (fields(ar, element)) under name/0/, name/1/, ...
  template <class T, class Fields>
  void records(const std::string& name, std::vector<T>& list, Fields&& fields) {
    const auto outer = scope(name);
    std::size_t n = list.size();
    (*this)("count", n);
    list.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const auto inner = scope(std::to_string(k));
      fields(*this, list[k]);
    }
  }

  /// Writes the collected fields to `path`, atomically.
  void write(const std::filesystem::path& path) const {
    const detail::QuietHdf5 quiet;
    const auto tmp = temporary_sibling(path);
    const hid_t file = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file < 0) throw std::runtime_error("cannot create the checkpoint " + tmp.string());
    const hid_t groups = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(groups, 1);
    bool ok = true;
    for (const auto& [key, f] : fields_) {
      const bool real = f.kind == 'd', text = f.kind == 'b';
      hsize_t n = real ? f.d.size() : text ? f.b.size() : f.i.size();
      const hid_t file_type = real ? H5T_IEEE_F64LE : text ? H5T_STD_U8LE : H5T_STD_I64LE;
      const hid_t mem_type = real ? H5T_NATIVE_DOUBLE : text ? H5T_NATIVE_UCHAR : H5T_NATIVE_INT64;
      const void* data = real   ? static_cast<const void*>(f.d.data())
                         : text ? static_cast<const void*>(f.b.data())
                                : static_cast<const void*>(f.i.data());
      const hid_t space = H5Screate_simple(1, &n, nullptr);
      const hid_t set = H5Dcreate2(file, key.c_str(), file_type, space, groups, H5P_DEFAULT, H5P_DEFAULT);
      ok = ok && set >= 0 && (n == 0 || H5Dwrite(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0);
      if (set >= 0) H5Dclose(set);
      H5Sclose(space);
    }
    H5Pclose(groups);
    ok = H5Fclose(file) >= 0 && ok;
    if (!ok) {
      std::filesystem::remove(tmp);
      throw std::runtime_error("writing the checkpoint " + tmp.string() + " failed");
    }
    commit_file(tmp, path);
  }

 private:
  struct Field {
    char kind = 'd';
    std::vector<double> d;
    std::vector<std::int64_t> i;
    std::string b;
  };
  Archive() = default;

  void doubles(const std::string& key, std::vector<double>& v) {
    if (saving_)
      fields_[key] = Field{'d', v, {}, {}};
    else
      read(key, H5T_NATIVE_DOUBLE, H5T_FLOAT, v);
  }
  void integers(const std::string& key, std::vector<std::int64_t>& v) {
    if (saving_)
      fields_[key] = Field{'i', {}, v, {}};
    else
      read(key, H5T_NATIVE_INT64, H5T_INTEGER, v);
  }
  void bytes(const std::string& key, std::string& text) {
    if (saving_) {
      fields_[key] = Field{'b', {}, {}, text};
      return;
    }
    std::vector<unsigned char> raw;
    read(key, H5T_NATIVE_UCHAR, H5T_INTEGER, raw);
    text.assign(raw.begin(), raw.end());
  }
  template <class T>
  void read(const std::string& key, hid_t mem_type, H5T_class_t kind, std::vector<T>& v) const {
    const std::string where = "checkpoint '" + path_.string() + "': ";
    const detail::QuietHdf5 quiet;
    bool present = true;  // each group on the path first: H5Lexists fails where a parent is missing
    for (auto slash = key.find('/'); present && slash != std::string::npos; slash = key.find('/', slash + 1))
      present = H5Lexists(file_, key.substr(0, slash).c_str(), H5P_DEFAULT) > 0;
    if (!present || H5Lexists(file_, key.c_str(), H5P_DEFAULT) <= 0)
      throw InputError(where + "no field '" + key + "' (written by another program or version?)");
    const hid_t set = H5Dopen2(file_, key.c_str(), H5P_DEFAULT);
    const hid_t type = H5Dget_type(set), space = H5Dget_space(set);
    const bool right_kind = H5Tget_class(type) == kind;
    const hssize_t n = H5Sget_simple_extent_npoints(space);
    H5Tclose(type);
    H5Sclose(space);
    if (!right_kind || n < 0) {
      H5Dclose(set);
      throw InputError(where + "field '" + key + "' has the wrong type");
    }
    v.resize(static_cast<std::size_t>(n));
    const bool ok = n == 0 || H5Dread(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0;
    H5Dclose(set);
    if (!ok) throw InputError(where + "cannot read field '" + key + "'");
  }

  bool saving_ = true;
  std::filesystem::path path_;
  hid_t file_ = -1;
  std::string prefix_;
  std::map<std::string, Field> fields_;
};

}  // namespace rsph::io
