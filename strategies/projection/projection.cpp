// The projection family: its registry, one line per model, and the projection stage.
#include "strategies/projection/projection.hpp"

#include <algorithm>
#include <cstddef>
#include <type_traits>

#include "framework/numeric/parallel.hpp"

namespace ndc {
namespace {

/// A model's registry entry: its own spec, and a factory per scalar.
template <template <class> class P>
Registry<ProjectionFactory>::Entry entryOf() {
  return {
      P<double>::spec(),
      {[](const System<double>& s, const Parameters&) { return Projection<double>(P<double>(s)); },
       [](const System<Mpfr>& s, const Parameters&) { return Projection<Mpfr>(P<Mpfr>(s)); }}};
}

}  // namespace

//! [projection-registry]
Registry<ProjectionFactory>& projectionRegistry() {
  static Registry<ProjectionFactory> registry("projection", {entryOf<NewtonProjection>()});
  return registry;
}
//! [projection-registry]

template <class S>
Projection<S> createProjection(const StrategyChoice& choice, const System<S>& system) {
  const ProjectionFactory& factory = projectionRegistry().find(choice.name).create;
  if constexpr (std::is_same_v<S, double>)
    return factory.inDouble(system, choice.parameters);
  else
    return factory.inMpfr(system, choice.parameters);
}

template <class S>
Projection<S> createProjection(std::string_view spec, const System<S>& system) {
  return createProjection<S>(projectionRegistry().parse(spec), system);
}

template <class S>
Projections<S> projectCells(const Projection<S>& projection, const SolutionCells& cells,
                            const Box<S>& domain, const Progress& progress) {
  const int n = cells.grid.n;
  const std::size_t count = cells.size();
  Projections<S> out;
  out.n = n;
  out.point.resize(count * n);
  out.converged.resize(count);
  out.iterations.resize(count);
  //! [project-cells]
  // One dispatch for the whole stage, not one per cell; the cells in parallel, each writing its
  // own slots (framework/numeric/parallel.hpp), in blocks so that progress is reported in order.
  std::visit(
      [&](const auto& strategy) {
        const std::size_t block = std::max<std::size_t>(1024, count / 100);
        for (std::size_t first = 0; first < count; first += block) {
          const std::size_t size = std::min(block, count - first);
          parallelFor(size, [&](std::size_t i) {
            const std::size_t c = first + i;
            // Alg. 1: start from the centroid of the cell's closed box.
            const Box<S> box = cellBox<S>(cells.grid, domain, cells.cell(c));
            std::span<S> x(out.point.data() + c * n, static_cast<std::size_t>(n));
            for (int j = 0; j < n; ++j) x[j] = (box.lo[j] + box.hi[j]) / 2;
            const ProjectedPoint<S> r = strategy.project(x);
            out.converged[c] = r.converged ? 1 : 0;
            out.iterations[c] = r.iterations;
          });
          if (progress) progress("projection", double(first + size) / double(count));
        }
      },
      projection);
  //! [project-cells]
  if (progress) progress("projection", 1.0);
  return out;
}

template <class S>
Projector<S> makeProjector(const Projection<S>& projection) {
  return [projection](std::span<S> x) {
    return std::visit([&](const auto& strategy) { return strategy.project(x); }, projection);
  };
}

template Projection<double> createProjection(const StrategyChoice&, const System<double>&);
template Projection<Mpfr> createProjection(const StrategyChoice&, const System<Mpfr>&);
template Projection<double> createProjection(std::string_view, const System<double>&);
template Projection<Mpfr> createProjection(std::string_view, const System<Mpfr>&);
template Projections<double> projectCells(const Projection<double>&, const SolutionCells&,
                                          const Box<double>&, const Progress&);
template Projections<Mpfr> projectCells(const Projection<Mpfr>&, const SolutionCells&,
                                        const Box<Mpfr>&, const Progress&);
template Projector<double> makeProjector(const Projection<double>&);
template Projector<Mpfr> makeProjector(const Projection<Mpfr>&);

}  // namespace ndc
