#include "strategies/classification/classification.hpp"

#include <string>

#include "framework/core/errors.hpp"

namespace ndc {

//! [classification-factory]
Classification createClassification(std::string_view name) {
  if (name == "paper") return PaperClassification{};
  std::string known;
  for (std::string_view k : kClassificationNames) {
    known += (known.empty() ? "" : ", ") + std::string(k);
  }
  throw InputError("unknown classification '" + std::string(name) + "' (known: " + known + ")");
}
//! [classification-factory]

template <class S>
std::vector<CellClass> classifyCells(const Classification& classification,
                                     const SolutionCells& cells, const Box<S>& domain,
                                     const Projections<S>& projections) {
  std::vector<CellClass> classes(cells.size());
  // One dispatch for the whole stage, not one per cell.
  std::visit(
      [&](const auto& strategy) {
        for (std::size_t c = 0; c < cells.size(); ++c) {
          const Box<S> box = cellBox<S>(cells.grid, domain, cells.cell(c));
          classes[c] = strategy.classify(box, projections.at(c), projections.converged[c] != 0);
        }
      },
      classification);
  return classes;
}

template std::vector<CellClass> classifyCells(const Classification&, const SolutionCells&,
                                              const Box<double>&, const Projections<double>&);
template std::vector<CellClass> classifyCells(const Classification&, const SolutionCells&,
                                              const Box<Mpfr>&, const Projections<Mpfr>&);

}  // namespace ndc
