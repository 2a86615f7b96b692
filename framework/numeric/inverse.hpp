/// \file inverse.hpp
/// The approximate inverse of a small square point matrix, the preconditioner Y of the
/// interval tests (the graph certificate's ||I - Y A|| < 1, the Krawczyk operator, the face
/// preconditioners), in storage the caller keeps: no allocation once warm, and none of the
/// per-call set-up of Eigen's dynamic-size decompositions, which cost more than the arithmetic
/// for these 2 x 2 to 8 x 8 matrices.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "framework/numeric/iteration.hpp"
#include "framework/numeric/scalar.hpp"

namespace ndc {

/// Y ~ A^-1 for the m x m matrix `a` (column-major, overwritten) into `y` (column-major, m x m)
/// by Gauss-Jordan elimination with partial pivoting; false when a pivot is 0, not finite, or
/// at most m eps times the largest |entry| of A (numerically singular). The tests that use Y
/// check what they prove with Y itself (outward rounded), so how accurate Y is affects only how
/// often they succeed, never what they prove.
template <class S>
bool invertGaussJordan(int m, std::vector<S>& a, std::vector<S>& y) {
  using std::abs;
  const auto mm = static_cast<std::size_t>(m);
  const auto at = [mm](std::vector<S>& v, int i, int j) -> S& {
    return v[static_cast<std::size_t>(j) * mm + static_cast<std::size_t>(i)];
  };
  S largest = 0;
  for (const S& v : a) largest = std::max<S>(largest, abs(v));
  const S floor = S(m) * ScalarTraits<S>::epsilon() * largest;
  y.assign(mm * mm, S(0));
  for (int i = 0; i < m; ++i) at(y, i, i) = 1;
  for (int k = 0; k < m; ++k) {
    int p = k;
    for (int i = k + 1; i < m; ++i)
      if (abs(at(a, i, k)) > abs(at(a, p, k))) p = i;
    const S pivot = at(a, p, k);
    if (!isFinite(pivot) || !(abs(pivot) > floor)) return false;
    if (p != k) {
      for (int j = 0; j < m; ++j) {
        std::swap(at(a, p, j), at(a, k, j));
        std::swap(at(y, p, j), at(y, k, j));
      }
    }
    // Row k scaled to a unit pivot, then eliminated from every other row.
    for (int j = 0; j < m; ++j) {
      at(a, k, j) /= pivot;
      at(y, k, j) /= pivot;
    }
    for (int i = 0; i < m; ++i) {
      if (i == k) continue;
      const S factor = at(a, i, k);
      if (factor == 0) continue;
      for (int j = 0; j < m; ++j) {
        at(a, i, j) -= factor * at(a, k, j);
        at(y, i, j) -= factor * at(y, k, j);
      }
    }
  }
  return true;
}

}  // namespace ndc
