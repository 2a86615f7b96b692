/// \file classification.hpp
/// The classification family (docs/algorithm1.md): the paper's normal / abnormal / failed labels of
/// the solution cells (Sec. 4.1, Algorithm 1: "classify whether c is normal or abnormal").
#pragma once

#include <array>
#include <span>
#include <string_view>
#include <variant>
#include <vector>

#include "framework/core/box.hpp"
#include "framework/core/complex.hpp"
#include "framework/core/grid.hpp"
#include "framework/core/scalar.hpp"
#include "framework/core/strategy.hpp"

namespace ndc {

/// Sec. 4.1: a cell is normal if Newton converged to a point inside the closed cell
/// (`lo_j <= p_j <= hi_j` for every axis, so a point on a face, edge or corner is inside),
/// abnormal if it converged to a point outside, and failed if Newton did not converge.
class PaperClassification final {
 public:
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

/// The classification family: one closed variant, dispatched once per stage.
/// Models: PaperClassification.
using Classification = std::variant<PaperClassification>;

/// The names `createClassification` accepts (the CLI's `--classification`).
inline constexpr std::array<std::string_view, 1> kClassificationNames{"paper"};

/// Makes the classification called `name`; throws InputError on an unknown name.
Classification createClassification(std::string_view name);

/// Alg. 1, classification step for every solution cell: the class of cell c from its closed
/// box (cellBox on `domain`, the grid's domain in S) and `projections.at(c)`.
template <class S>
std::vector<CellClass> classifyCells(const Classification& classification,
                                     const SolutionCells& cells, const Box<S>& domain,
                                     const Projections<S>& projections);

extern template std::vector<CellClass> classifyCells(const Classification&, const SolutionCells&,
                                                     const Box<double>&,
                                                     const Projections<double>&);
extern template std::vector<CellClass> classifyCells(const Classification&, const SolutionCells&,
                                                     const Box<Mpfr>&, const Projections<Mpfr>&);

}  // namespace ndc
