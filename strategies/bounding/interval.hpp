/// \file interval.hpp
/// Interval bounding (`interval`): outward-rounded interval arithmetic on the equations' programs.
#pragma once

#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/problem.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc {

/// Interval bounding (`interval`): each F_i is enclosed over the box in outward-rounded
/// interval arithmetic, once by its natural extension and once by the mean-value form
/// `F(m) + sum_j G_j (X_j - m_j)` (m the box midpoint, G the interval gradient over the box);
/// the box is kept iff the intersection of both enclosures contains 0 for every F_i. Unlike the
/// Bernstein test it is rigorous: rounding never discards a box that holds a zero.
///
/// Evaluation works on the compiled programs directly (no Bernstein form), so the per-box state is
/// the box alone. An instance keeps scratch buffers: use one instance per thread.
template <class S>
class IntervalBounding final {
 public:
  /// The model's name, what it does and its parameters (defined in interval.cpp, next to the model;
  /// the family's registry lists it in one line).
  static ModelSpec spec();

  /// Per-box state: the box.
  struct State {
    Box<S> box;
  };

  IntervalBounding(const Problem& problem, const Box<S>& domain);

  /// Number of variables n.
  int dim() const { return domain_.dim(); }
  /// State of the whole domain.
  void root(State& state) const;
  /// Children of `parent` at the midpoint of `axis`.
  void halve(const State& parent, int axis, State& lower, State& upper) const;
  /// Alg. 1 step (1) with interval arithmetic: false when the enclosure of some F_i over the
  /// box (the tighter of natural extension and mean-value form) excludes 0.
  bool mayContainZero(const State& state) const;

 private:
  Box<S> domain_;
  std::vector<Expression> equations_;
  // Scratch, reused by mayContainZero so that it does not allocate per box.
  mutable std::vector<Interval<S>> x_, mid_, gradient_;
};

static_assert(BoundingStrategy<IntervalBounding<double>>);
static_assert(BoundingStrategy<IntervalBounding<Mpfr>>);
extern template class IntervalBounding<double>;
extern template class IntervalBounding<Mpfr>;

}  // namespace ndc
