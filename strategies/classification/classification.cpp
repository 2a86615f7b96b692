#include "strategies/classification/classification.hpp"

#include <string>

#include "framework/numeric/parallel.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

//! [classification-registry]
Registry<ClassificationFactory>& classificationRegistry() {
  static Registry<ClassificationFactory> registry(
      "classification", {{PaperClassification::spec(), [](const Parameters&) {
                            return holdClassification(PaperClassification{});
                          }}});
  return registry;
}
//! [classification-registry]

Classification createClassification(const StrategyChoice& choice) {
  return classificationRegistry().find(choice.name).create(choice.parameters);
}

Classification createClassification(std::string_view spec) {
  return createClassification(classificationRegistry().parse(spec));
}

template <class S>
std::vector<CellClass> classifyCells(const Classification& classification,
                                     const SolutionCells& cells, const Box<S>& domain,
                                     const Projections<S>& projections) {
  std::vector<CellClass> classes(cells.size());
  // One dispatch for the whole stage, not one per cell; the cells in parallel, each writing
  // its own class.
  std::visit(
      [&](const auto& strategy) {
        parallelFor(
            cells.size(),
            [&](std::size_t c) {
              const Box<S> box = cellBox<S>(cells.grid, domain, cells.cell(c));
              classes[c] = strategy.classify(box, projections.at(c), projections.converged[c] != 0);
            },
            1024);
      },
      classification);
  return classes;
}

template std::vector<CellClass> classifyCells(const Classification&, const SolutionCells&,
                                              const Box<double>&, const Projections<double>&);
template std::vector<CellClass> classifyCells(const Classification&, const SolutionCells&,
                                              const Box<Mpfr>&, const Projections<Mpfr>&);

}  // namespace ndc
