/// \file paper.hpp
/// The `paper` classification model (Sec. 4.1): a solution cell is normal when its projected
/// point lies in the closed cell (strategies/classification/classification.hpp has the family).
#pragma once

#include <span>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc {

/// Sec. 4.1: a cell is normal if Newton converged to a point inside the closed cell
/// (`lo_j <= p_j <= hi_j` for every axis, so a point on a face, edge or corner is inside),
/// abnormal if it converged to a point outside, and failed if Newton did not converge.
class PaperClassification final {
 public:
  /// The model's name, sentence and parameters (its registry entry).
  static ModelSpec spec() {
    return {"paper",
            "Sec. 4.1: normal when Newton converged inside the closed cell, abnormal outside, "
            "failed when it did not converge.",
            {}};
  }

  /// Classifies one cell from its closed box and its projected point.
  template <class S>
  CellClass classify(const Box<S>& cell, std::span<const S> point, bool converged) const {
    if (!converged) return CellClass::kFailed;
    for (int j = 0; j < cell.dim(); ++j) {
      // Closed box: the faces belong to the cell.
      if (!(cell.lo[j] <= point[j] && point[j] <= cell.hi[j])) return CellClass::kAbnormal;
    }
    return CellClass::kNormal;
  }
};

static_assert(ClassificationStrategy<PaperClassification, double>);
static_assert(ClassificationStrategy<PaperClassification, Mpfr>);

}  // namespace ndc
