#pragma once
// Scratch storage reused from one particle or cell to the next.
#include <cstddef>
#include <vector>

namespace rsph {

/// The storage of `v`, grown to at least n elements, doubling (never shrunk: hot loops keep their scratch).
template <class T>
T* grown(std::vector<T>& v, std::size_t n) {
  if (v.size() < n) v.resize(2 * n);
  return v.data();
}

}  // namespace rsph
