/// \file box.hpp
/// Axis-aligned boxes in R^n.
#pragma once

#include <cstddef>
#include <vector>

namespace ndc {

/// An axis-aligned box `[lo_0, hi_0] x ... x [lo_{n-1}, hi_{n-1}]` with `lo_j < hi_j`.
template <class S>
struct Box {
  std::vector<S> lo;  ///< lower corner
  std::vector<S> hi;  ///< upper corner

  /// Dimension n.
  int dim() const { return static_cast<int>(lo.size()); }
  /// Width along axis j.
  S width(int j) const { return hi[j] - lo[j]; }
};

}  // namespace ndc
