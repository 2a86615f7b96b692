// The bounding family: its registry, one line per model, and its factory.
#include "strategies/bounding/bounding.hpp"

#include <string>
#include <type_traits>

namespace ndc {
namespace {

/// A model's registry entry: its own spec and the factory of the class template.
template <template <class> class B>
Registry<BoundingFactory>::Entry entryOf() {
  return {B<double>::spec(), boundingFactory<B>()};
}

}  // namespace

//! [bounding-registry]
Registry<BoundingFactory>& boundingRegistry() {
  static Registry<BoundingFactory> registry(
      "bounding",
      {entryOf<BernsteinBounding>(), entryOf<IntervalBounding>(), entryOf<LinearizedBounding>()});
  return registry;
}
//! [bounding-registry]

template <class S>
Bounding<S> createBounding(const StrategyChoice& choice, const Problem& problem,
                           const Box<S>& domain) {
  const BoundingFactory& factory = boundingRegistry().find(choice.name).create;
  if constexpr (std::is_same_v<S, double>)
    return factory.inDouble(problem, domain, choice.parameters);
  else
    return factory.inMpfr(problem, domain, choice.parameters);
}

template <class S>
Bounding<S> createBounding(std::string_view spec, const Problem& problem, const Box<S>& domain) {
  return createBounding<S>(boundingRegistry().parse(spec), problem, domain);
}

template Bounding<double> createBounding<double>(const StrategyChoice&, const Problem&,
                                                 const Box<double>&);
template Bounding<Mpfr> createBounding<Mpfr>(const StrategyChoice&, const Problem&,
                                             const Box<Mpfr>&);
template Bounding<double> createBounding<double>(std::string_view, const Problem&,
                                                 const Box<double>&);
template Bounding<Mpfr> createBounding<Mpfr>(std::string_view, const Problem&, const Box<Mpfr>&);

}  // namespace ndc
