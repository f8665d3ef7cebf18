#pragma once
// CSV curves, written whole at the end (atomic) or streamed row by row to a temporary file that is
// renamed on close(), so an interrupted run never leaves a truncated CSV under the final name.
#include "rsph/io/atomic_file.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsph::io {

class CsvWriter {
 public:
  CsvWriter(std::filesystem::path target, const std::vector<std::string>& columns)
      : target_(std::move(target)), tmp_(temporary_sibling(target_)), n_columns_(columns.size()) {
    file_ = std::fopen(tmp_.c_str(), "w");
    if (!file_) throw std::runtime_error("cannot write " + tmp_.string());
    std::string header;
    for (std::size_t i = 0; i < columns.size(); ++i) header += (i ? "," : "") + columns[i];
    fmt::print(file_, "{}\n", header);
  }
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  ~CsvWriter() {
    if (file_) {  // not closed: the run failed, leave no result behind
      std::fclose(file_);
      std::filesystem::remove(tmp_);
    }
  }

  void row(std::initializer_list<double> values) { row(std::vector<double>(values)); }
  void row(const std::vector<double>& values) {
    if (values.size() != n_columns_) throw std::logic_error("CSV row width differs from header in " + target_.string());
    for (std::size_t i = 0; i < values.size(); ++i) fmt::print(file_, "{}{:.12g}", i ? "," : "", values[i]);
    std::fputc('\n', file_);
  }

  /// Saves or restores, through a checkpoint archive (checkpoint.hpp), the rows written so far: a resumed run
  /// goes on from the same text.
  template <class Archive>
  void checkpoint(Archive& ar, const std::string& name) {
    if (!file_) throw std::logic_error("CSV " + target_.string() + " is closed");
    std::string text;
    if (ar.saving()) {
      std::fflush(file_);
      text = read_text_file(tmp_);
    }
    ar(name, text);
    if (ar.saving()) return;
    std::fclose(file_);
    file_ = std::fopen(tmp_.c_str(), "w");
    if (!file_ || std::fwrite(text.data(), 1, text.size(), file_) != text.size())
      throw std::runtime_error("cannot write " + tmp_.string());
  }

  /// Finishes the file and moves it to its final name.
  void close() {
    if (!file_) return;
    const bool ok = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!ok) throw std::runtime_error("failed writing " + tmp_.string());
    commit_file(tmp_, target_);
  }

 private:
  std::filesystem::path target_, tmp_;
  std::size_t n_columns_;
  std::FILE* file_ = nullptr;
};

}  // namespace rsph::io
