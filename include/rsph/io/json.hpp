#pragma once
// A small ordered JSON object for summary.json: numbers, strings, arrays and nested objects.
#include "rsph/io/atomic_file.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rsph::io {

class Json {
 public:
  static std::string quote(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
      switch (c) {
        case '"':
          out += "\\\"";
          break;
        case '\\':
          out += "\\\\";
          break;
        case '\n':
          out += "\\n";
          break;
        case '\t':
          out += "\\t";
          break;
        default:
          if (static_cast<unsigned char>(c) < 0x20)
            out += fmt::format("\\u{:04x}", static_cast<int>(c));
          else
            out += c;
      }
    }
    return out + "\"";
  }
  static std::string number(double x) { return std::isfinite(x) ? fmt::format("{:.12g}", x) : "null"; }

  Json& set(const std::string& key, double x) { return raw(key, number(x)); }
  Json& set(const std::string& key, int x) { return raw(key, std::to_string(x)); }
  Json& set(const std::string& key, std::int64_t x) { return raw(key, std::to_string(x)); }
  Json& set(const std::string& key, std::uint64_t x) { return raw(key, std::to_string(x)); }
  Json& set(const std::string& key, bool x) { return raw(key, x ? "true" : "false"); }
  Json& set(const std::string& key, const char* s) { return raw(key, quote(s)); }
  Json& set(const std::string& key, const std::string& s) { return raw(key, quote(s)); }
  Json& set(const std::string& key, const Json& child) { return raw(key, child.dump()); }
  Json& set(const std::string& key, const std::vector<double>& xs) {
    std::string s = "[";
    for (std::size_t i = 0; i < xs.size(); ++i) s += (i ? ", " : "") + number(xs[i]);
    return raw(key, s + "]");
  }
  /// An array of objects, one per line.
  Json& set(const std::string& key, const std::vector<Json>& items) {
    std::string s = "[";
    for (std::size_t i = 0; i < items.size(); ++i) s += (i ? ",\n" : "\n") + items[i].dump();
    return raw(key, s + (items.empty() ? "]" : "\n]"));
  }

  /// Every entry of `other`, in its order (a key already here takes the new value in its place).
  Json& merge(const Json& other) {
    for (const auto& [key, value] : other.entries_) raw(key, value);
    return *this;
  }

  /// Pretty-printed with two-space indentation; nested objects are shifted to their depth.
  std::string dump() const {
    if (entries_.empty()) return "{}";
    std::string s = "{\n";
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      std::string value;
      for (char c : entries_[i].second) value += c == '\n' ? std::string("\n  ") : std::string(1, c);
      s += "  " + quote(entries_[i].first) + ": " + value + (i + 1 < entries_.size() ? ",\n" : "\n");
    }
    return s + "}";
  }

  void write(const std::filesystem::path& path) const { write_text_file(path, dump() + "\n"); }

 private:
  Json& raw(const std::string& key, std::string value) {
    for (auto& e : entries_)
      if (e.first == key) {
        e.second = std::move(value);
        return *this;
      }
    entries_.emplace_back(key, std::move(value));
    return *this;
  }
  std::vector<std::pair<std::string, std::string>> entries_;
};

}  // namespace rsph::io
