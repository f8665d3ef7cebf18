#pragma once
// Errors the library raises; it never prints, callers decide what the user sees.
#include <stdexcept>
#include <string>

namespace rsph {

/// Invalid parameters or initial data: the message names the cause.
struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// The run became unphysical (NaN, negative density or energy): the message names particle and field.
struct NumericalError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A rank of a decomposed run cannot decide its share of a remap from the particles it gathered: an old cell, or
/// the particle nearest to a new site, may reach beyond them. Every rank raises it at the same point; the caller
/// gathers farther and remaps again.
struct HaloTooNarrow : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline void require(bool condition, const std::string& message) {
  if (!condition) throw InputError(message);
}

}  // namespace rsph
