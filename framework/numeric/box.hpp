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

/// `box` in the scalar S (every bound converted exactly: S holds every double). The one
/// conversion of a double box (a problem domain, a grid cell) to the run's scalar.
template <class S>
Box<S> toScalar(const Box<double>& box) {
  Box<S> out;
  out.lo.reserve(box.lo.size());
  out.hi.reserve(box.hi.size());
  for (int j = 0; j < box.dim(); ++j) {
    out.lo.push_back(S(box.lo[j]));
    out.hi.push_back(S(box.hi[j]));
  }
  return out;
}

}  // namespace ndc
