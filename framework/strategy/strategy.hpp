/// \file strategy.hpp
/// The five strategy families of the pipeline (docs/algorithm1.md) as C++20 concepts. Each family
/// has plain `final` implementations in strategies/(family)/ and one closed std::variant with
/// a `create...(name)` that rejects unknown names. Strategies are dispatched once per box and
/// per stage (std::visit outside the loops), never per coefficient.
#pragma once

#include <concepts>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/problem/budget.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"
#include "framework/problem/system.hpp"

namespace ndc {

/// Progress report of a long stage: `fraction` in [0, 1] of `stage` ("subdivision", ...).
using Progress = std::function<void(const char* stage, double fraction)>;

/// A one-line notice of a run before its long work (the time estimate of a long run); the CLI
/// prints it on standard error. May be empty.
using Notice = std::function<void(const std::string& line)>;

/// Bounding: can a box contain a common zero of every F_i? A bounding strategy carries a
/// per-box `State` down the subdivision (e.g. the Bernstein patches of the box) so that a
/// child is derived from its parent, not from the root.
/// Models: BernsteinBounding, IntervalBounding (strategies/bounding/bounding.hpp).
template <class B>
concept BoundingStrategy = requires(const B b, typename B::State& st, const typename B::State& cst,
                                    int axis) {
  typename B::State;
  { b.root(st) } -> std::same_as<void>;                  // state of the whole domain
  { b.halve(cst, axis, st, st) } -> std::same_as<void>;  // children at the axis midpoint
  { b.mayContainZero(cst) } -> std::same_as<bool>;       // false: discard the box
};

/// Subdivision: the order of splitting. Every model halves axis `level mod n` at halving
/// number `level` and ends on the same uniform grid of 2^L cells per axis; they differ in
/// after which halvings a box is bounded.
/// Models: UniformSubdivision (2^n children per level, as in the paper), BinarySubdivision.
template <class D>
concept SubdivisionStrategy = requires(const D d, int level, int n) {
  { d.boundsAfter(level, n) } -> std::same_as<bool>;
};

/// Projection: moves a point onto M in place, and says for each equation how large a residual
/// at x cannot be told from zero at the working precision (the singular-point search accepts its
/// points by that tolerance, so it follows the chosen model). Models: NewtonProjection.
template <class P, class S>
concept ProjectionStrategy = requires(const P p, std::span<S> x, std::span<const S> at,
                                      std::span<S> tolerance) {
  { p.project(x) } -> std::same_as<ProjectedPoint<S>>;
  { p.residualTolerance(at, tolerance) } -> std::same_as<void>;
};

/// Classification of one solution cell from its closed box and its projected point.
/// Models: PaperClassification. `classify` is const and called for many cells at once, from
/// the run's threads (ndc::classifyCells), so it must not write shared state.
template <class C, class S>
concept ClassificationStrategy = requires(const C c, const Box<S>& cell, std::span<const S> point,
                                          bool converged) {
  { c.classify(cell, point, converged) } -> std::same_as<CellClass>;
};

/// Everything a connection strategy may use.
template <class S>
struct ConnectionInput {
  const Problem& problem;
  const System<S>& system;
  const SolutionCells& cells;
  const Projections<S>& projections;
  const std::vector<CellClass>& classes;
  Projector<S> project;  ///< Newton projection onto M (for centroids, dual vertices)
  int k = 1;             ///< manifold dimension
  /// Adaptive refinement (docs/certificate.md): the children of a cell (its halves along every
  /// axis) that may hold M, from the run's bounding: n entries per child, entry j 1 where the
  /// child holds the upper half of axis j. Only these are listed, so that a refinement costs
  /// the bounding's search for them, not 2^n. Empty function: no refinement.
  std::function<std::vector<std::uint8_t>(const Box<double>& cell)> refine;
  /// The deepest level refinement may reach (at least the grid's depth).
  int maxLevel = 0;
  /// Chord error target (`--tolerance`): leaves whose mesh pieces lie farther from M are
  /// refined too, up to maxLevel; 0: none.
  double tolerance = 0;
  /// Seconds of the time model (budget.hpp) refinement may spend on its solution leaves:
  /// kRefineSeconds, or a quarter of `--timeout` when that is less, so a run with a time limit
  /// ends with an uncertified result rather than being stopped.
  double refineSeconds = kRefineSeconds;
  /// Per equation: a bound on the rounding error of its Bernstein coefficients on the domain,
  /// relative to the largest (certificates treat smaller coefficients as unknown signs).
  std::vector<double> coefficientError;
  /// Progress within the connection (may be empty): the crossing connection reports each
  /// round of refinement as the stage "connection" with its round and leaves, and the share of
  /// the round's leaves walked.
  Progress progress;
};

/// What a connection strategy returns.
template <class S>
struct ConnectionOutput {
  Complex<S> complex;
  std::int64_t ambiguousCells = 0;  ///< cells whose piece of M is not one simple piece
  std::int64_t singularCells = 0;   ///< cells with a rank-deficient Jacobian near M
  /// Dual vertices whose Newton projection onto M did not converge.
  std::int64_t offManifoldVertices = 0;
  /// The level perturbation the connection used (crossing), else empty.
  PerturbationRecord perturbation;
  /// The topology certificate (crossing); other connections leave it uncertified.
  TopologyRecord topology;
};

/// Connection: builds the k-simplices. Models: PaperConnection, NaiveConnection
/// (strategies/connection/connection.hpp).
template <class C, class S>
concept ConnectionStrategy = requires(const C c, const ConnectionInput<S>& in) {
  { c.connect(in) } -> std::same_as<ConnectionOutput<S>>;
};

}  // namespace ndc
