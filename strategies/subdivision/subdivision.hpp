/// \file subdivision.hpp
/// The subdivision stage (paper Sec. 4 and Algorithm 1 step (1), ZeroSetSubdiv): recursively
/// halve the domain, discard boxes the bounding strategy proves free of common zeros, and
/// return the surviving boxes of the final depth L as solution cells of the uniform grid.
///
/// The subdivision tree, common to every subdivision strategy: a binary tree of depth n L in
/// which the box at depth `d` (after `d` halvings; the root has depth 0) is split along axis
/// `d mod n`. After n L halvings every box is a cell of the grid of 2^L cells per axis. A
/// subdivision strategy only decides at which depths a box is bounded: the box at depth `d` is
/// bounded iff `boundsAfter(d, n)`. Every model bounds the root (d = 0) and the final depth
/// (d = n L), so binary's solution cells are always a subset of uniform's, and the two agree
/// when the bounding is monotone (a sub-box of a discarded box is discarded too). The Bernstein
/// hull is, up to rounding: a sub-box's coefficients are convex combinations of its parent's.
/// The mean-value form of the interval test is not monotone in general, but the two agreed on
/// every test problem (tests/strategies/test_subdivision.cpp).
#pragma once

#include <array>
#include <string_view>
#include <variant>

#include "framework/numeric/grid.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/subdivision/binary.hpp"
#include "strategies/subdivision/uniform.hpp"

namespace ndc {

static_assert(SubdivisionStrategy<UniformSubdivision>);
static_assert(SubdivisionStrategy<BinarySubdivision>);

/// The subdivision family: one closed variant.
using Subdivision = std::variant<UniformSubdivision, BinarySubdivision>;

/// A subdivision factory: the model with the spec's parameter values. The traversal is
/// instantiated per model, so each model is an alternative of the variant: a new model is one
/// file, one alternative in Subdivision and one registry line (docs/adding-a-strategy.md).
using SubdivisionFactory = Subdivision (*)(const Parameters& parameters);

/// The subdivision family's registry (strategies/subdivision/subdivision.cpp; the CLI's
/// `--subdivision`).
Registry<SubdivisionFactory>& subdivisionRegistry();

/// The subdivision strategy a parsed spec names.
Subdivision createSubdivision(const StrategyChoice& choice);
/// The subdivision strategy of a spec; UsageError on an unknown name, parameter or value.
Subdivision createSubdivision(std::string_view spec);

/// ZeroSetSubdiv (Alg. 1 step (1)): the solution cells of depth `grid.depth` of the problem
/// that `bounding` was built for, on `grid` (whose domain must be the bounding's domain).
///
/// Depth-first traversal of the subdivision tree (see above): the box at depth d is bounded
/// (counted in `visited`) iff `subdivision.boundsAfter(d, n)`, and discarded with its whole
/// subtree when the bounding says it holds no common zero; the boxes of depth n L never
/// discarded are the solution cells, in depth-first order (lower child first). Memory is one
/// pair of bounding states per depth plus the output, so it grows with the number of solution
/// cells, not with 2^(n L). `progress`, when set, receives ("subdivision", share of the domain's
/// volume done) at most about 100 times. Throws InputError when the grid does not fit a CellKey
/// (the packed cell index needs n * L <= 128), std::invalid_argument when grid and bounding
/// disagree on n. `maxCells` > 0 is a budget: when more solution cells are found the traversal
/// stops with ndc::CellBudgetExceeded (a zero set of a higher dimension than the problem's k).
template <class S>
SolutionCells subdivide(const Bounding<S>& bounding, const Subdivision& subdivision,
                        const Grid& grid, const Progress& progress = {}, std::int64_t maxCells = 0);

extern template SolutionCells subdivide<double>(const Bounding<double>&, const Subdivision&,
                                                const Grid&, const Progress&, std::int64_t);
extern template SolutionCells subdivide<Mpfr>(const Bounding<Mpfr>&, const Subdivision&,
                                              const Grid&, const Progress&, std::int64_t);

}  // namespace ndc
