// Private helpers of the bounding models (not part of the public surface).
#pragma once

#include <stdexcept>
#include <string>

#include "framework/numeric/box.hpp"
#include "framework/problem/problem.hpp"

namespace ndc::bounding_detail {

/// Both children of a box at the midpoint of `axis`. The vector assignments reuse the
/// children's storage, and both children get the same midpoint value, so siblings share their
/// face exactly (no gap where a zero could hide).
template <class S>
inline void halveBox(const Box<S>& parent, int axis, Box<S>& lower, Box<S>& upper) {
  lower.lo = parent.lo;
  lower.hi = parent.hi;
  upper.lo = parent.lo;
  upper.hi = parent.hi;
  lower.hi[axis] = (parent.lo[axis] + parent.hi[axis]) / 2;
  upper.lo[axis] = lower.hi[axis];
}

/// std::invalid_argument unless the domain has the problem's n axes.
template <class S>
inline void checkDomain(const Problem& problem, const Box<S>& domain) {
  if (domain.dim() != problem.n() || static_cast<int>(domain.hi.size()) != problem.n())
    throw std::invalid_argument("bounding: the domain has " + std::to_string(domain.dim()) +
                                " axes, the problem " + std::to_string(problem.n()) + " variables");
}

}  // namespace ndc::bounding_detail
