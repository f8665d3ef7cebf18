#pragma once
// A map from whole numbers to slots, for keys too sparse to index densely.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace rsph {

/// Slots by a whole-number key (lattice cells by flat index, for grids too sparse to hold densely; names kept on a
/// rank): open addressing with linear probing.
class SlotMap {
 public:
  void clear() {
    std::fill(key_.begin(), key_.end(), empty);
    size_ = 0;
  }
  /// The slot of `flat`; absent, it is inserted with slot `fresh`.
  std::uint32_t find_or_insert(std::size_t flat, std::uint32_t fresh) {
    if (2 * (size_ + 1) > key_.size()) grow();
    for (std::size_t i = home(flat);; i = (i + 1) & mask_) {
      if (key_[i] == flat) return slot_[i];
      if (key_[i] == empty) {
        key_[i] = flat;
        slot_[i] = fresh;
        ++size_;
        return fresh;
      }
    }
  }
  /// The slot of `flat`, -1 when absent.
  std::int64_t find(std::size_t flat) const {
    if (key_.empty()) return -1;
    for (std::size_t i = home(flat);; i = (i + 1) & mask_) {
      if (key_[i] == flat) return slot_[i];
      if (key_[i] == empty) return -1;
    }
  }

 private:
  static constexpr std::size_t empty = std::numeric_limits<std::size_t>::max();
  std::size_t home(std::size_t flat) const { return (flat * 0x9E3779B97F4A7C15ull >> 17) & mask_; }
  void grow() {
    std::vector<std::size_t> keys(std::max<std::size_t>(64, 2 * key_.size()), empty);
    std::vector<std::uint32_t> slots(keys.size());
    std::swap(keys, key_);
    std::swap(slots, slot_);
    mask_ = key_.size() - 1;
    size_ = 0;
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != empty) find_or_insert(keys[i], slots[i]);
  }
  std::vector<std::size_t> key_;
  std::vector<std::uint32_t> slot_;
  std::size_t mask_ = 0, size_ = 0;
};

}  // namespace rsph
