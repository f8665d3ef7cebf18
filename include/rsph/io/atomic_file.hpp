#pragma once
// Files appear whole or not at all: written to a temporary name in the same folder, then renamed.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <system_error>

namespace rsph::io {

inline std::filesystem::path temporary_sibling(const std::filesystem::path& target) {
  std::string name = ".";  // built step by step: GCC 12 misreports -Wrestrict on "." + s + "..."
  name += target.filename().string();
  name += ".partial";
  return target.parent_path() / name;
}

/// Renames the finished temporary file onto its target.
inline void commit_file(const std::filesystem::path& tmp, const std::filesystem::path& target) {
  std::error_code ec;
  std::filesystem::rename(tmp, target, ec);
  if (ec) throw std::runtime_error("cannot move " + tmp.string() + " to " + target.string() + ": " + ec.message());
}

/// Writes `text` to `target` atomically.
inline void write_text_file(const std::filesystem::path& target, const std::string& text) {
  const auto tmp = temporary_sibling(target);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("failed writing " + tmp.string());
  }
  commit_file(tmp, target);
}

/// The whole of a text file; an error names the path.
inline std::string read_text_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Creates the output folder (and parents); an error names the path.
inline void ensure_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::runtime_error("cannot create output folder " + dir.string() + (ec ? ": " + ec.message() : ""));
}

}  // namespace rsph::io
