/// \file bounding.hpp
/// The bounding strategies of the subdivision stage (paper Sec. 4, ZeroSetSubdiv in step (1)
/// of Algorithm 1): can a box contain a common zero of every F_i? Models of the concept
/// BoundingStrategy (framework/strategy.hpp), chosen at run time by name.
#pragma once

#include <array>
#include <string_view>
#include <variant>
#include <vector>

#include "bernstein.hpp"
#include "box.hpp"
#include "expression.hpp"
#include "interval.hpp"
#include "problem.hpp"
#include "scalar.hpp"
#include "strategy.hpp"

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
  /// Per-box state: the box and one patch per equation.
  struct State {
    Box<S> box;
    std::vector<Bernstein<S>> patches;
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

/// Interval bounding (`interval`): each F_i is enclosed over the box in outward-rounded
/// interval arithmetic, once by its natural extension and once by the mean-value form
/// `F(m) + sum_j G_j (X_j - m_j)` (m the box midpoint, G the interval gradient over the box);
/// the box is kept iff the intersection of both enclosures contains 0 for every F_i. Unlike the
/// Bernstein test it is rigorous: rounding never discards a box that holds a zero.
///
/// Evaluation works on the syntax trees directly (no Bernstein form), so the per-box state is
/// the box alone. An instance keeps scratch buffers: use one instance per thread.
template <class S>
class IntervalBounding final {
 public:
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

static_assert(BoundingStrategy<BernsteinBounding<double>>);
static_assert(BoundingStrategy<BernsteinBounding<Mpfr>>);
static_assert(BoundingStrategy<IntervalBounding<double>>);
static_assert(BoundingStrategy<IntervalBounding<Mpfr>>);

/// The bounding family: one closed variant, dispatched once per subdivision (std::visit).
template <class S>
using Bounding = std::variant<BernsteinBounding<S>, IntervalBounding<S>>;

/// Names accepted by createBounding, in the variant's order.
inline constexpr std::array<std::string_view, 2> kBoundingNames{"bernstein", "interval"};

/// The bounding strategy called `name` for `problem` on `domain` (the problem domain in S,
/// jitter applied); throws InputError on an unknown name.
template <class S>
Bounding<S> createBounding(std::string_view name, const Problem& problem, const Box<S>& domain);

extern template class BernsteinBounding<double>;
extern template class BernsteinBounding<Mpfr>;
extern template class IntervalBounding<double>;
extern template class IntervalBounding<Mpfr>;
extern template Bounding<double> createBounding<double>(std::string_view, const Problem&,
                                                        const Box<double>&);
extern template Bounding<Mpfr> createBounding<Mpfr>(std::string_view, const Problem&,
                                                    const Box<Mpfr>&);

}  // namespace ndc
