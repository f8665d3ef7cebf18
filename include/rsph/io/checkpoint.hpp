#pragma once
// Checkpoints: the whole state a run needs to continue, bit for bit, in one HDF5 file. Whoever owns state
// lists it once in a `checkpoint(Archive&)` member, ar("name", field) per field, and the same list both
// saves and restores it (Simulation, the regularizer, the run loop, a scene's counters and curves). Every
// number keeps its bits: doubles as IEEE doubles, integers as 64-bit integers. The file is written to a
// temporary name and renamed, so a run killed while writing leaves the previous checkpoint whole.
//
// Written by many processes (the ranks of a decomposed run), a checkpoint is still one file in the same layout:
// a per-particle field (`rows`) holds every process's rows in process order, a figure that adds up over the
// processes (`total`) holds the sum, and any other field the first process's value (the others hold the same,
// or a figure of their own that is reported from the first). Loaded by any number of processes, each gets a
// contiguous share of every per-particle field and the first one the totals, so that a checkpoint written by 4
// ranks resumes on 2 or on 1.
#include "rsph/core/dimension.hpp"
#include "rsph/core/errors.hpp"
#include "rsph/io/atomic_file.hpp"
#include "rsph/io/writing_turns.hpp"

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

/// Which share of a checkpoint one of several processes loads: part `part` of `parts`.
struct Share {
  std::size_t part = 0, parts = 1;
};

/// Saves fields into memory and then to a file, or restores them from a file, with one interface.
class Archive {
 public:
  /// An archive that collects fields; write() puts them in a file.
  static Archive for_saving() { return Archive(); }
  /// An archive that restores fields from `path`, of which this process takes `share` (a contiguous share of
  /// every per-particle field; the totals go to part 0); a missing file or field is an InputError naming it.
  /// `reading`: alone, or together with the other ranks (whose properties must outlive the archive).
  static Archive load(const std::filesystem::path& path, Share share = {}, Reading reading = {}) {
    Archive ar;
    ar.saving_ = false;
    ar.path_ = path;
    ar.share_ = share;
    ar.transfer_ = reading.transfer;
    const detail::QuietHdf5 quiet;
    if (!std::filesystem::is_regular_file(path)) throw InputError("no checkpoint '" + path.string() + "'");
    ar.file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, reading.file_access);
    if (ar.file_ < 0) throw InputError("cannot read the checkpoint '" + path.string() + "'");
    return ar;
  }
  Archive(Archive&& o) noexcept
      : saving_(o.saving_),
        path_(std::move(o.path_)),
        file_(o.file_),
        share_(o.share_),
        transfer_(o.transfer_),
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
      doubles(key, one, 1);
      value = one.at(0);
    } else if constexpr (std::is_integral_v<T>) {
      std::vector<std::int64_t> one{static_cast<std::int64_t>(value)};
      integers(key, one);
      value = static_cast<T>(one.at(0));
    } else if constexpr (std::is_same_v<T, std::string>) {
      bytes(key, value);
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      doubles(key, value, 1);
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
      doubles(key, flat, k);
      if (flat.size() % k != 0) throw InputError("checkpoint field '" + key + "' has the wrong shape");
      value.resize(flat.size() / k);
      for (std::size_t a = 0; a < value.size(); ++a)
        for (std::size_t j = 0; j < k; ++j) value[a].data()[j] = flat[a * k + j];
    }
  }

  /// Saves or restores a per-particle field: every process's rows, in process order; loaded, this process's
  /// share of them. On one process the same as operator().
  template <class T>
  void rows(const std::string& name, std::vector<T>& value) {
    const Spread before = spread_;
    spread_ = Spread::rows;
    (*this)(name, value);
    spread_ = before;
  }

  /// Saves or restores a figure that adds up over the processes (a count of this process's updates): the
  /// file holds the sum; loaded, part 0 gets it and the others zero. On one process the same as operator().
  template <class T>
  void total(const std::string& name, T& value) {
    static_assert(std::is_arithmetic_v<T>, "a total is a single number");
    const Spread before = spread_;
    spread_ = Spread::total;
    (*this)(name, value);  // read on every part too: ranks reading together read every field together
    spread_ = before;
    if (!saving_ && share_.part > 0) value = T{};
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

  /// Writes the collected fields to `path`, atomically. Written by several processes (`turns`), each with its
  /// own archive of the same fields, it is one file: part 0 creates it with every field at its full length and
  /// writes its rows, the others then write theirs in turn, or all create it and write together. Every process
  /// calls it; if one fails, all throw.
  template <WritingTurns Turns = OneWriter>
  void write(const std::filesystem::path& path, const Turns& turns = {}) const {
    std::vector<std::uint64_t> counts, lengths;
    std::vector<double> reals;
    std::vector<std::int64_t> integers;
    for (const auto& [key, f] : fields_) {
      if (f.spread == Spread::rows) counts.push_back(length(f));
      if (f.spread == Spread::total && f.kind == 'd') reals.push_back(f.d.at(0));
      if (f.spread == Spread::total && f.kind == 'i') integers.push_back(f.i.at(0));
      if (f.spread == Spread::first) lengths.push_back(turns.part() == 0 ? length(f) : 0);
    }
    const Layout layout{turns.first_rows(counts), turns.total_rows(counts), turns.total_rows(lengths), turns.sum(reals),
                        turns.sum(integers)};
    const auto tmp = temporary_sibling(path);
    write_in_turns(
        turns, tmp, [&] { return create(tmp, layout, turns); }, [&] { return add_rows(tmp, layout); },
        [&] { return committed(tmp, path); }, "writing the checkpoint " + tmp.string() + " failed");
  }

 private:
  /// How a field written by many processes comes together: the first one's, every one's rows, or the sum.
  enum class Spread { first, rows, total };
  struct Field {
    char kind = 'd';
    std::vector<double> d;
    std::vector<std::int64_t> i;
    std::string b;
    Spread spread = Spread::first;
  };
  /// Where each process's rows go and how many there are (per `rows` field, in key order), the length of part
  /// 0's value of every other field, and the totals' sums (in key order).
  struct Layout {
    std::vector<std::uint64_t> first, total, lengths;
    std::vector<double> reals;
    std::vector<std::int64_t> integers;
  };
  Archive() = default;

  void doubles(const std::string& key, std::vector<double>& v, std::size_t row_size) {
    if (saving_)
      fields_[key] = Field{'d', v, {}, {}, spread_};
    else
      read(key, H5T_NATIVE_DOUBLE, H5T_FLOAT, v, row_size);
  }
  void integers(const std::string& key, std::vector<std::int64_t>& v) {
    if (saving_)
      fields_[key] = Field{'i', {}, v, {}, spread_};
    else
      read(key, H5T_NATIVE_INT64, H5T_INTEGER, v, 1);
  }
  void bytes(const std::string& key, std::string& text) {
    if (saving_) {
      fields_[key] = Field{'b', {}, {}, text, Spread::first};
      return;
    }
    std::vector<unsigned char> raw;
    read(key, H5T_NATIVE_UCHAR, H5T_INTEGER, raw, 1);
    text.assign(raw.begin(), raw.end());
  }

  /// The types of a field in the file and in memory, and its numbers.
  static hid_t file_type(const Field& f) {
    return f.kind == 'd' ? H5T_IEEE_F64LE : f.kind == 'b' ? H5T_STD_U8LE : H5T_STD_I64LE;
  }
  static hid_t memory_type(const Field& f) {
    return f.kind == 'd' ? H5T_NATIVE_DOUBLE : f.kind == 'b' ? H5T_NATIVE_UCHAR : H5T_NATIVE_INT64;
  }
  static const void* data(const Field& f) {
    return f.kind == 'd'   ? static_cast<const void*>(f.d.data())
           : f.kind == 'b' ? static_cast<const void*>(f.b.data())
                           : static_cast<const void*>(f.i.data());
  }
  static hsize_t length(const Field& f) { return f.kind == 'd' ? f.d.size() : f.kind == 'b' ? f.b.size() : f.i.size(); }

  /// Creates the file `tmp` with every field at `layout`'s lengths and sums, through `turns`' access and transfer
  /// lists, and writes this process's values into it: its rows, and on part 0 every other field. Every field is
  /// visited whatever failed, so that processes writing together make the same calls.
  template <WritingTurns Turns>
  bool create(const std::filesystem::path& tmp, const Layout& layout, const Turns& turns) const {
    const detail::QuietHdf5 quiet;
    const hid_t file = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, turns.file_access());
    if (file < 0) return false;
    const hid_t groups = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(groups, 1);
    const bool first_part = turns.part() == 0;
    std::size_t row = 0, other = 0, real = 0, integer = 0;
    bool ok = true;
    for (const auto& [key, f] : fields_) {
      hsize_t n = 1, at = 0, mine = first_part ? 1 : 0;  // a total: part 0 writes the sum
      const void* values = data(f);
      if (f.spread == Spread::rows) {
        n = layout.total.at(row);
        at = layout.first.at(row++);
        mine = length(f);
      } else if (f.spread == Spread::first) {
        n = layout.lengths.at(other++);
        mine = first_part ? n : 0;
      } else {
        values = f.kind == 'd' ? static_cast<const void*>(&layout.reals.at(real++))
                               : static_cast<const void*>(&layout.integers.at(integer++));
      }
      const hid_t space = H5Screate_simple(1, &n, nullptr);
      const hid_t set = H5Dcreate2(file, key.c_str(), file_type(f), space, groups, H5P_DEFAULT, H5P_DEFAULT);
      ok = set >= 0 && write_slab(set, memory_type(f), at, mine, 0, values, turns.transfer()) && ok;
      if (set >= 0) H5Dclose(set);
      H5Sclose(space);
    }
    H5Pclose(groups);
    return H5Fclose(file) >= 0 && ok;
  }

  /// commit_file, false where it failed.
  static bool committed(const std::filesystem::path& tmp, const std::filesystem::path& path) {
    try {
      commit_file(tmp, path);
      return true;
    } catch (const std::runtime_error&) {
      return false;
    }
  }

  /// Writes this process's rows of every per-particle field into the file `tmp` that part 0 created.
  bool add_rows(const std::filesystem::path& tmp, const Layout& layout) const {
    const detail::QuietHdf5 quiet;
    const hid_t file = H5Fopen(tmp.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (file < 0) return false;
    std::size_t row = 0;
    bool ok = true;
    for (const auto& [key, f] : fields_) {
      if (f.spread != Spread::rows) continue;
      const hid_t set = H5Dopen2(file, key.c_str(), H5P_DEFAULT);
      ok =
          ok && set >= 0 && write_slab(set, memory_type(f), layout.first.at(row++), length(f), 0, data(f), H5P_DEFAULT);
      if (set >= 0) H5Dclose(set);
    }
    return H5Fclose(file) >= 0 && ok;
  }

  template <class T>
  void read(const std::string& key, hid_t mem_type, H5T_class_t kind, std::vector<T>& v, std::size_t row_size) const {
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
    // this process's share of the rows of a per-particle field; all of any other field
    const auto rows = static_cast<hsize_t>(n) / row_size;
    const bool part = spread_ == Spread::rows && share_.parts > 1;
    const hsize_t first = part ? rows * share_.part / share_.parts * row_size : 0;
    hsize_t count = part ? (rows * (share_.part + 1) / share_.parts) * row_size - first : static_cast<hsize_t>(n);
    v.resize(static_cast<std::size_t>(count));
    const hsize_t one = 1;  // a process reading no rows together with others still takes part, selecting none
    const hid_t whole = H5Dget_space(set), memory = H5Screate_simple(1, count > 0 ? &count : &one, nullptr);
    T none{};
    bool ok = true;
    if (count > 0)
      ok = H5Sselect_hyperslab(whole, H5S_SELECT_SET, &first, nullptr, &count, nullptr) >= 0 &&
           H5Dread(set, mem_type, memory, whole, transfer_, v.data()) >= 0;
    else if (transfer_ != H5P_DEFAULT && n > 0)  // an empty field, empty everywhere, is read by none
      ok = H5Sselect_none(whole) >= 0 && H5Sselect_none(memory) >= 0 &&
           H5Dread(set, mem_type, memory, whole, transfer_, &none) >= 0;
    H5Sclose(memory);
    H5Sclose(whole);
    H5Dclose(set);
    if (!ok) throw InputError(where + "cannot read field '" + key + "'");
  }

  bool saving_ = true;
  std::filesystem::path path_;
  hid_t file_ = -1;
  Share share_;
  hid_t transfer_ = H5P_DEFAULT;   ///< collective reads where the file was opened together
  Spread spread_ = Spread::first;  ///< of the fields being named now (rows() and total() set it)
  std::string prefix_;
  std::map<std::string, Field> fields_;
};

}  // namespace rsph::io
