/// \file projection.hpp
/// The projection family (docs/algorithm1.md, docs/projection.md): its variant of models, its
/// registry and the projection stage of Algorithm 1 over all solution cells. Models:
/// NewtonProjection (`newton.hpp`).
#pragma once

#include <string_view>
#include <variant>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/problem/system.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/projection/newton.hpp"

namespace ndc {

/// The projection family: one closed variant, dispatched once per stage.
/// Models: NewtonProjection.
template <class S>
using Projection = std::variant<NewtonProjection<S>>;

/// A projection factory: the model for a system (in either scalar) with the spec's parameter
/// values. A new model is one file, one alternative in Projection and one registry line
/// (docs/adding-a-strategy.md).
struct ProjectionFactory {
  Projection<double> (*inDouble)(const System<double>&, const Parameters&);
  Projection<Mpfr> (*inMpfr)(const System<Mpfr>&, const Parameters&);
};

/// The projection family's registry (strategies/projection/projection.cpp; `projection` in
/// experiment configs).
Registry<ProjectionFactory>& projectionRegistry();

/// Makes the projection a parsed spec names, for `system`.
template <class S>
Projection<S> createProjection(const StrategyChoice& choice, const System<S>& system);
/// Makes the projection of a spec; UsageError on an unknown name, parameter or value.
template <class S>
Projection<S> createProjection(std::string_view spec, const System<S>& system);

/// Alg. 1, projection step for every solution cell: projects the centroid of each cell's
/// closed box (cellBox on `domain`, the grid's domain in S) onto M. Reports progress as
/// ("projection", fraction) when `progress` is set.
template <class S>
Projections<S> projectCells(const Projection<S>& projection, const SolutionCells& cells,
                            const Box<S>& domain, const Progress& progress);

/// Wraps a projection as the Projector the connection and analysis stages call (copies the
/// projection; the system it refers to must outlive the Projector).
template <class S>
Projector<S> makeProjector(const Projection<S>& projection);

extern template Projection<double> createProjection(const StrategyChoice&, const System<double>&);
extern template Projection<Mpfr> createProjection(const StrategyChoice&, const System<Mpfr>&);
extern template Projection<double> createProjection(std::string_view, const System<double>&);
extern template Projection<Mpfr> createProjection(std::string_view, const System<Mpfr>&);
extern template Projections<double> projectCells(const Projection<double>&, const SolutionCells&,
                                                 const Box<double>&, const Progress&);
extern template Projections<Mpfr> projectCells(const Projection<Mpfr>&, const SolutionCells&,
                                               const Box<Mpfr>&, const Progress&);
extern template Projector<double> makeProjector(const Projection<double>&);
extern template Projector<Mpfr> makeProjector(const Projection<Mpfr>&);

}  // namespace ndc
