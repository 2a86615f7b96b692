/// \file cell_forms.hpp
/// The Bernstein forms a cell's patches are restricted from: one polynomial per equation on the
/// whole domain, or, for B-spline input, one per patch of the knot grid (Problem::roots at
/// `rootLevel`). Built on first use and kept for the solve, so the connection and the singular
/// point search ask one service instead of each keeping its own cache (docs/architecture.md).
#pragma once

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/expression.hpp"

namespace ndc {

/// The root Bernstein forms of the equations, per patch of a grid of `rootLevel` (0: the one
/// domain box). A cell at any level `>= rootLevel` maps to the patch that contains it.
template <class S>
class CellForms {
 public:
  /// `equations` and `grid` must outlive this object; `domain` is the grid's domain in S.
  CellForms(std::span<const Expression> equations, const Grid& grid, Box<S> domain, int rootLevel);

  /// The forms (one per equation) on the patch that contains the cell `index` of the grid of
  /// depth `level` (`level >= rootLevel`); computed on the first request for that patch.
  const std::vector<Bernstein<S>>& root(std::span<const std::int32_t> index, int level);

  /// The patch level (0 for a polynomial on the whole domain).
  int rootLevel() const { return rootLevel_; }

 private:
  std::span<const Expression> equations_;
  const Grid& grid_;
  Box<S> domain_;
  int rootLevel_;
  std::vector<std::int32_t> patch_;  ///< scratch: the patch index of the current request
  CellMap<std::vector<Bernstein<S>>> forms_;
};

extern template class CellForms<double>;
extern template class CellForms<Mpfr>;

}  // namespace ndc
