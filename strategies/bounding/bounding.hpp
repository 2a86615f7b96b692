/// \file bounding.hpp
/// The bounding strategies of the subdivision stage (paper Sec. 4, ZeroSetSubdiv in step (1)
/// of Algorithm 1): can a box contain a common zero of every F_i? Models of the concept
/// BoundingStrategy (framework/strategy/strategy.hpp), chosen at run time by name.
#pragma once

#include <string_view>
#include <variant>

#include "framework/numeric/box.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/problem.hpp"
#include "framework/strategy/registry.hpp"
#include "strategies/bounding/bernstein.hpp"
#include "strategies/bounding/interval.hpp"
#include "strategies/bounding/linearized.hpp"

namespace ndc {

/// The bounding family: one closed variant, dispatched once per subdivision (std::visit).
template <class S>
using Bounding = std::variant<BernsteinBounding<S>, IntervalBounding<S>, LinearizedBounding<S>>;

/// A bounding factory: the model for a problem on a domain (in either scalar) with the spec's
/// parameter values. A bounding is called once per box in the subdivision's inner loop, so each
/// model is an alternative of the variant (no virtual dispatch): a new model is one file, one
/// alternative in Bounding and one registry line (docs/adding-a-strategy.md).
struct BoundingFactory {
  Bounding<double> (*inDouble)(const Problem&, const Box<double>&, const Parameters&);
  Bounding<Mpfr> (*inMpfr)(const Problem&, const Box<Mpfr>&, const Parameters&);
};

/// The factory of model `B` (a class template over the scalar, built from problem and domain).
template <template <class> class B>
BoundingFactory boundingFactory() {
  return {[](const Problem& p, const Box<double>& d, const Parameters&) {
            return Bounding<double>(std::in_place_type<B<double>>, p, d);
          },
          [](const Problem& p, const Box<Mpfr>& d, const Parameters&) {
            return Bounding<Mpfr>(std::in_place_type<B<Mpfr>>, p, d);
          }};
}

/// The bounding family's registry (strategies/bounding/bounding.cpp; the CLI's `--bounding`).
Registry<BoundingFactory>& boundingRegistry();

/// The bounding strategy a parsed spec names, for `problem` on `domain` (the problem domain in
/// S, jitter applied).
template <class S>
Bounding<S> createBounding(const StrategyChoice& choice, const Problem& problem,
                           const Box<S>& domain);
/// The bounding strategy of a spec; UsageError on an unknown name, parameter or value.
template <class S>
Bounding<S> createBounding(std::string_view spec, const Problem& problem, const Box<S>& domain);

extern template Bounding<double> createBounding<double>(const StrategyChoice&, const Problem&,
                                                        const Box<double>&);
extern template Bounding<Mpfr> createBounding<Mpfr>(const StrategyChoice&, const Problem&,
                                                    const Box<Mpfr>&);
extern template Bounding<double> createBounding<double>(std::string_view, const Problem&,
                                                        const Box<double>&);
extern template Bounding<Mpfr> createBounding<Mpfr>(std::string_view, const Problem&,
                                                    const Box<Mpfr>&);

}  // namespace ndc
