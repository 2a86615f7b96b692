/// \file bernstein.hpp
/// The paper's bounding test (`bernstein`): the convex hull of a box's Bernstein coefficients.
#pragma once

#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/problem.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc {

/// Bernstein bounding (`bernstein`), the paper's test (Sec. 4: the constraints are subdivided
/// as B-spline / Bernstein functions and a box is discarded when some F_i's coefficients all
/// have one sign). Each box carries the Bernstein patches of all m equations restricted to it;
/// a child's patches are derived from its parent's by one de Casteljau halving, so the
/// polynomials are converted to Bernstein form only once, on the domain.
///
/// The test uses the convex hull property: the range of a patch on its box lies between its
/// smallest and largest coefficient. It is exact up to the rounding of S in the halvings.
template <class S>
class BernsteinBounding final {
 public:
  /// The model's name, what it does and its parameters (defined in bernstein.cpp, next to the
  /// model; the family's registry lists it in one line).
  static ModelSpec spec();

  /// Per-box state: the box and one patch per equation; and what LinearizedBounding's test of
  /// the box showed about its halves (its children).
  struct State {
    Box<S> box;
    std::vector<Bernstein<S>> patches;
    /// Halves of the box that hold no common zero by the test of the box itself (bit 2 j: the
    /// half x_j <= c_j, bit 2 j + 1: x_j >= c_j, c the centre; n <= 32), written by
    /// LinearizedBounding::mayContainZero.
    mutable std::uint64_t emptyHalves = 0;
    /// This box is such a half of its parent: it holds no common zero, without a test.
    bool emptyByParent = false;
    /// A point of the box within `pointError` (max norm) of a common zero, carried down from
    /// an ancestor by LinearizedBounding (docs/subdivision.md, "Points carried down"); valid
    /// when hasPoint.
    std::vector<S> point;
    S pointError = 0;
    bool hasPoint = false;
    /// Where Newton's iteration for this box's point starts: a point of the linearized zero
    /// set inside the box that its test found (valid when hasStart), else the centre.
    mutable std::vector<S> start;
    mutable bool hasStart = false;
  };

  /// Converts every equation of `problem` to Bernstein form on `domain`.
  BernsteinBounding(const Problem& problem, const Box<S>& domain);

  /// Number of variables n.
  int dim() const { return domain_.dim(); }
  /// State of the whole domain (a copy of the root patches).
  void root(State& state) const;
  /// Children of `parent` at the midpoint of `axis`; reuses the children's storage, so it
  /// allocates nothing once `lower` and `upper` have been used for a box of the same problem.
  void halve(const State& parent, int axis, State& lower, State& upper) const;
  /// Alg. 1 step (1): false when some patch's coefficients exclude 0 (then no F_i vanishes
  /// there and the box holds no common zero).
  bool mayContainZero(const State& state) const;

 private:
  Box<S> domain_;
  std::vector<Bernstein<S>> patches_;  // on the domain, one per equation
};

static_assert(BoundingStrategy<BernsteinBounding<double>>);
static_assert(BoundingStrategy<BernsteinBounding<Mpfr>>);
extern template class BernsteinBounding<double>;
extern template class BernsteinBounding<Mpfr>;

}  // namespace ndc
