/// \file linearized.hpp
/// Linearized bounding (`linearized`, the default): the Bernstein hull or mean-value form per
/// equation, then a test of all equations together on their linearisation.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <variant>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/linearized_system.hpp"
#include "framework/numeric/midrad.hpp"
#include "framework/numeric/minimum_norm.hpp"
#include "framework/numeric/multipliers.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/bounding/bernstein.hpp"

namespace ndc {

/// Linearized bounding (`linearized`): a per-equation test of every F_i on its own, then,
/// for boxes that pass it and when m >= 2, a test of the m equations *together* on their
/// linearisation. In codimension m >= 2 the per-equation tests keep every box that meets each
/// hypersurface F_i = 0 separately, i.e. a neighbourhood of their pairwise intersections far
/// from M; the simultaneous test removes most of these.
///
/// Per-equation test. An equation is subdivided in Bernstein form and tested by its hull, as in
/// `bernstein`, unless it is affine (without piecewise leaves: its range over a box is exact
/// from its constant gradient, tested before the curved equations are evaluated) or its total
/// degree is at most 2 and its dense form has more than kMaxDensePatch coefficients (the
/// product of (degree + 1) over the variables). Such an
/// equation is enclosed by its mean-value form F_i(c) + J_i(X) (X - c) instead, from the same
/// midpoint-radius evaluation the simultaneous test uses: for total degree <= 2 it is as tight
/// as the hull up to O(h^2) (the exact range for an affine F_i), while the dense form is
/// exponential in n where the tape is not (a sphere in R^8 has 3^8 = 6561 coefficients, whose
/// halving and scan per box cost more than the whole linearized test). Above degree 2 the hull
/// is kept in any dimension: the mean-value form of a high-degree F_i is far looser.
///
/// Derivation. Let X be the box, c its centre, h_j >= |x_j - c_j| on X, J(X) an interval
/// enclosure of the Jacobian over X (midpoint-radius gradients of the equations' tapes; constant
/// rows for affine equations) and J_c any point matrix (the midpoint of J(X)). By the
/// mean value theorem, applied to each F_i, every zero x = c + d in X satisfies
///
///     J_c d = -g,   g in G := F(c) + [-r, r],   r_i = sum_j mag(J_ij(X) - J_c,ij) h_j,
///
/// with F(c) enclosed in interval arithmetic. With J_c^T = Q R (Householder; Q = [Q1 Q2], Q2
/// spanning ker J_c) put L = R^T (so L L^T = J_c J_c^T) and P = L^{-1}; then P J_c = Q1^T has
/// orthonormal rows and the box is discarded when one of these necessary conditions fails:
///  - row test: mig((P G)_i) <= sum_j |(P J_c)_ij| h_j for every i;
///  - ball test: sum_i mig((P G)_i)^2 <= |P J_c|_2^2 |h|_2^2 (|P J_c|_2 = 1 up to rounding);
///  - null-space test: with J^+ = Q1 P and N = Q2, d = -J^+ g + N t + D d for t = N^T d and
///    D = I - J^+ J_c - N N^T (zero up to rounding), so some t must satisfy
///    |(N t)_j - (J^+ mid G)_j| <= h_j + (|J^+| rad G)_j + (|D| h)_j for every axis j; this
///    is checked by interval constraint propagation on t (exact when k = n - m = 1: the
///    linearized curve is a thickened line and the test is whether it meets the box).
///  - multiplier test: every common zero also satisfies y^T (F(c) + J_c d + s) = 0, |s_i| <=
///    rad G_i, for any multipliers y in R^m, which is impossible when
///    |y . mid G| > sum_i |y_i| rad G_i + sum_j |(J_c^T y)_j| h_j. By Farkas' lemma such a y
///    exists exactly when the linearized system has no solution d in the box; the tests
///    above are this test for particular y (the rows of P) or relaxations of it, and each mixes
///    the remainders of all equations, so a box that misses the common zeros of the affine
///    equations alone (a flat) can pass them when one curved equation has a large remainder.
///    The y is found by reweighted least squares (MultiplierTest, at most
///    kMultiplierIterations steps) and checked with bounded rounding, so an inexact y only
///    discards fewer boxes.
///  - contraction: a box these tests keep without a point of the linearized zero set has all
///    its zeros in c + [lo, hi], the bounds on d_j that the null-space test leaves
///    (LinearizedSystem::solutionBox); where that sub-box is small (|h'|^2 below kContraction
///    |h|^2) the tests run once more on the sub-box's own linearisation, whose remainder is
///    smaller (docs/subdivision.md, "Contraction").
/// For an equation of total degree 2 without piecewise leaves the remainder is that of its
/// Taylor form, F_i(c + d) = F_i(c) + grad F_i(c) . d + d^T H_i d / 2 exactly, so
/// |F_i(c + d) - F_i(c) - J_c,i d| <= sum_j (rad grad_j F_i(c) + rad J_ij(X) / 2) h_j with
/// J_c,i the midpoint of the gradient enclosed at c (rad J_ij(X) >= sum_l |H_i,jl| h_l, the
/// radius of the gradient's range): half the mean-value form's remainder. Where H_i is proven
/// semidefinite (a sum of squares: spheres, ellipsoids, cylinders; quadraticCurvature), the
/// remainder d^T H_i d / 2 has one sign, so G_i is the one-sided [0, r_i] (up to the proof's
/// slack) instead of [-r_i, r_i]: half as wide again.
/// The identities hold for the matrices actually computed (P, J^+, N are just some matrices),
/// and every floating-point product is bounded with the standard error bound gamma_p of
/// p-term dot products (a relative margin of 8 (n + m + 8) eps on every bound), so rounding
/// never discards a box that holds a common zero. A rank-deficient J_c (a pivot below 1e-10
/// of the largest row) skips the test and keeps the box.
///
/// F(c) and J(X) come from the equations' tapes evaluated in midpoint-radius arithmetic
/// (MidRadEvaluator, framework/numeric/midrad.hpp) (rounding-to-nearest, every rounding error added
/// to the radius): as rigorous as outward-rounded intervals, without switching rounding modes per
/// operation. The test is only enabled when it can pay: m <= n and some two equations share a
/// variable (for equations in disjoint variables, like the Clifford torus, the per-equation tests
/// already decide the system, and `linearized` is `bernstein`). Scratch buffers make
/// mayContainZero allocation-free for double: use one instance per thread.
template <class S>
class LinearizedBounding final {
 public:
  /// The model's name, what it does and its parameters (defined in linearized.cpp, next to the
  /// model; the family's registry lists it in one line).
  static ModelSpec spec();

  /// Per-box state: the Bernstein state (box and patches), carried down by halving.
  using State = typename BernsteinBounding<S>::State;

  /// Converts the equations to Bernstein form on `domain` (as BernsteinBounding) and prepares
  /// their midpoint-radius evaluators for the linearized test.
  LinearizedBounding(const Problem& problem, const Box<S>& domain);

  /// Number of variables n.
  int dim() const { return bernstein_.dim(); }
  /// State of the whole domain.
  void root(State& state) const { bernstein_.root(state); }
  /// Children of `parent` at the midpoint of `axis` (Bernstein halving); a child that the
  /// parent's test showed to hold no common zero (State::emptyHalves) is marked so.
  /// A child that holds the parent's point of M (State::point, found by Newton's iteration
  /// from the parent's centre when the parent has none) takes it along.
  void halve(const State& parent, int axis, State& lower, State& upper) const {
    bernstein_.halve(parent, axis, lower, upper);
    lower.emptyByParent = axis < 32 && ((parent.emptyHalves >> (2 * axis)) & 1);
    upper.emptyByParent = axis < 32 && ((parent.emptyHalves >> (2 * axis + 1)) & 1);
    carryPoint(parent, lower, upper);
  }
  /// Alg. 1 step (1): false when a Bernstein hull excludes 0 or, for m >= 2, when the
  /// linearized system has no solution in the box (see the class comment). A box that holds a
  /// point of M (State::point) is kept without the tests, which could not discard it.
  bool mayContainZero(const State& state) const;

  /// The simultaneous test alone (for tests): true when the linearized system proves that
  /// `box` holds no common zero.
  bool linearizationExcludes(const Box<S>& box) const;
  /// The mean-value test of the equations without a patch alone (for tests): true when one of
  /// them proves that `box` holds no zero of it.
  bool meanValueExcludes(const Box<S>& box) const;

  /// Largest dense Bernstein form (coefficients, the product of (degree + 1) over the
  /// variables) an equation of total degree <= 2 is subdivided in; a larger one is enclosed by
  /// its mean-value form instead (see the class comment). 1024 keeps every quadratic up to
  /// n = 6 (3^6 = 729) in Bernstein form (affine equations never have one).
  static constexpr double kMaxDensePatch = 1024;
  /// Reweighted least-squares steps of the multiplier test (step 8) per box. On the rotated
  /// 2-sphere in R^7 the best y was found within 8 steps for 96% of the boxes the exact
  /// linear program discards (docs/subdivision.md).
  static constexpr int kMultiplierIterations = 8;
  /// Newton steps of newtonPoint, and the last step's size (relative to the box's largest
  /// width) below which the iteration counts as converged.
  static constexpr int kNewtonSteps = 6;
  static constexpr double kPointTolerance = 1e-10;
  /// contractedExcludes runs when the solutions' box has |h'|^2 below this share of |h|^2.
  static constexpr double kContraction = 0.5;
  /// True when `equation` is subdivided in Bernstein form (total degree above 2, or 2 with at
  /// most kMaxDensePatch coefficients, or a piecewise affine one).
  static bool hasPatch(const Expression& equation);

 private:
  /// Steps 3 to 8 on the linearisation of the box of `state` (hh = |h|_2^2); true when they
  /// discard it, else the halves they show empty go to state.emptyHalves.
  bool simultaneousExcludes(const S& hh, const State& state) const;
  /// After steps 3 to 8 kept `box` without a point: the same steps on the box of step 7's
  /// bounds on the solutions, when it is small enough (kContraction); true when they discard
  /// it.
  bool contractedExcludes(const Box<S>& box) const;
  /// `problem` with only the equations that have a patch.
  static Problem patchedEquations(const Problem& problem);
  /// Gives each child the point of M that the parent holds (or that Newton's iteration finds
  /// from the parent's centre) if the point lies in it by more than its error.
  void carryPoint(const State& parent, State& lower, State& upper) const;
  /// Newton's iteration (minimum-norm steps) from the state's start (or its box's centre) into
  /// newtonX_; true when it converged (the last step below kPointTolerance times the box's
  /// largest width), with `error` bounding the point's distance from a zero by four times the
  /// last step.
  bool newtonPoint(const State& state, S& error) const;
  /// The mean-value test of each equation without a patch, affine or not, after steps 1 and 2
  /// (for those rows); true when one excludes 0.
  bool meanValueExcludes(bool affine) const;
  // The steps of linearizationExcludes (numbered as in the class comment), on the scratch
  // buffers below.
  /// 1: centre c_ and half-widths (system_.h) of `box`; returns |h|_2^2 (rounded up).
  S centreAndHalfWidths(const Box<S>& box) const;
  /// 2: J_c, mid F(c) and the radii rho into system_; false when an enclosure is not finite.
  bool linearise() const;
  /// Step 2 for the affine rows only, or for the others only.
  bool lineariseRows(bool affine) const;
  /// For a semidefinite quadratic (`curvature`), the Taylor remainder [-r, r] made one-sided:
  /// `r` becomes its half-width and `shift` its centre.
  void oneSided(const Curvature& curvature, S& r, S& shift) const;
  BernsteinBounding<S> bernstein_;
  std::vector<MidRadEvaluator<S>> evaluators_;  // per equation
  std::vector<char> affine_;     // per equation: total degree <= 1, so the gradient is constant
  std::vector<char> evaluated_;  // per equation: no patch, enclosed by its mean-value form
  std::vector<char> quadratic_;  // per equation: total degree 2, no leaves (Taylor remainder)
  bool anyEvaluated_ = false;
  int n_ = 0, m_ = 0;
  bool enabled_ = false;  // some pair of equations shares a variable, and m <= n
  S tol_;                 // relative margin covering every rounding of the test
  S u_;                   // unit of the midpoint-radius arithmetic (>= 2 x unit round-off)
  std::vector<S> affineMid_, affineRad_;  // m x n: constant gradients (affine rows only)
  // Scratch of linearizationExcludes, sized once.
  mutable std::vector<S> c_, zero_;     // the box's centre; zero radii
  mutable std::vector<S> spread_;       // MidRadEvaluator::gradientSpread
  mutable LinearizedSystem<S> system_;  // steps 2 to 8
  mutable std::vector<S> dLo_, dHi_;    // contractedExcludes: the solutions' d
  mutable Box<S> contracted_;           // and their box
  // Scratch of newtonPoint.
  mutable MinimumNormSolver<S> newton_;
  System<S> newtonSystem_;
  mutable std::vector<S> newtonX_, newtonF_, newtonJ_, newtonStep_;
};

static_assert(BoundingStrategy<LinearizedBounding<double>>);
static_assert(BoundingStrategy<LinearizedBounding<Mpfr>>);
extern template class LinearizedBounding<double>;
extern template class LinearizedBounding<Mpfr>;

}  // namespace ndc
