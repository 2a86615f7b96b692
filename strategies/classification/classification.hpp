/// \file classification.hpp
/// The classification family (docs/algorithm1.md): the paper's normal / abnormal / failed labels of
/// the solution cells (Sec. 4.1, Algorithm 1: "classify whether c is normal or abnormal").
#pragma once

#include <memory>
#include <span>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/classification/paper.hpp"

namespace ndc {

/// A classification model that is none of the variant's own alternatives (a new strategy in
/// one file, or a test-only one): one virtual call per cell, for both scalars.
class DynamicClassification final {
 public:
  template <class T>
  explicit DynamicClassification(T model) : model_(std::make_shared<Holder<T>>(std::move(model))) {}

  template <class S>
  CellClass classify(const Box<S>& cell, std::span<const S> point, bool converged) const {
    return model_->classify(cell, point, converged);
  }

 private:
  struct Model {
    virtual ~Model() = default;
    virtual CellClass classify(const Box<double>& cell, std::span<const double> point,
                               bool converged) const = 0;
    virtual CellClass classify(const Box<Mpfr>& cell, std::span<const Mpfr> point,
                               bool converged) const = 0;
  };
  template <class T>
  struct Holder final : Model {
    explicit Holder(T m) : model(std::move(m)) {}
    CellClass classify(const Box<double>& cell, std::span<const double> point,
                       bool converged) const override {
      return model.classify(cell, point, converged);
    }
    CellClass classify(const Box<Mpfr>& cell, std::span<const Mpfr> point,
                       bool converged) const override {
      return model.classify(cell, point, converged);
    }
    T model;
  };
  std::shared_ptr<const Model> model_;
};

/// The classification family: one variant, dispatched once per stage. Models:
/// PaperClassification, and any other registered model through DynamicClassification.
using Classification = std::variant<PaperClassification, DynamicClassification>;

/// `model` as a Classification: its own alternative when it has one, else a
/// DynamicClassification.
template <class T>
Classification holdClassification(T model) {
  if constexpr (std::is_same_v<T, PaperClassification>)
    return Classification(std::in_place_type<T>, std::move(model));
  else
    return Classification(std::in_place_type<DynamicClassification>,
                          DynamicClassification(std::move(model)));
}

/// A classification factory: the model built with the spec's parameter values.
using ClassificationFactory = Classification (*)(const Parameters& parameters);

/// The classification family's registry (the CLI's `--classification`). Mutable so that tests
/// can register test-only models.
Registry<ClassificationFactory>& classificationRegistry();

/// Makes the classification a parsed spec names, with its parameters.
Classification createClassification(const StrategyChoice& choice);
/// Makes the classification of a spec; UsageError on an unknown name, parameter or value.
Classification createClassification(std::string_view spec);

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
