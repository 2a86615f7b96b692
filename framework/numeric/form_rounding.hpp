/// \file form_rounding.hpp
/// A rigorous bound on the rounding error of a Bernstein form built in double arithmetic
/// (bernsteinOfTape), carried through the same operations as the form.
#pragma once

#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/tape.hpp"

namespace ndc {

/// Bounds E >= max_K |computed_K - exact_K| for every form on bernsteinOfTape's stack, where
/// `exact` is the form of the program with its literals as written, in exact arithmetic.
/// Standard model of floating-point arithmetic: every operation on doubles rounds with relative
/// error at most u = 2^-53, and a product or quotient that underflows adds at most 2^-1074;
/// gamma_k = k u / (1 - k u) bounds k successive roundings. The rules follow the operations of
/// bernstein.inl one by one:
/// - a literal: its distance to the outward-rounded enclosure read with it; a variable: 0 (the
///   coefficients are the box's bounds);
/// - degree elevation along an axis of degree d >= 1: weights C(d,i) C(e-d,k-i) / C(e,k) (one
///   rounding, and they sum to 1) in sums of at most d + 1 products: gamma_(d+2) max |b|;
///   from degree 0 every weight is exactly 1;
/// - a sum: both operands elevated, then one rounding of each coefficient;
/// - a product: each coefficient is sum_{I+J=K} w_IJ a_I b_J with weights
///   C(d,I) C(e,J) / C(d+e,K) that sum to 1 (Vandermonde), computed as scalings by binomials
///   (exact for rows of degree at most 2, one rounding per axis otherwise), N products and
///   N - 1 additions (N = prod_j (min(d_j, e_j) + 1)) and divisions: gamma_r max|a| max|b| with
///   r the number of roundings, plus |a| E_b + |b| E_a + E_a E_b for the operands' errors.
/// A leaf (a B-spline patch) or a division has no bound here (infinity): the caller measures
/// those forms instead. Every bound is rounded up.
class FormRounding {
 public:
  /// A literal's form: the distance from its double to the literal.
  void constant(const TapeConstant& c);
  /// A variable's form: exact.
  void variable() { errors_.push_back(0); }
  /// A form without a bound (a leaf).
  void unbounded();
  /// `a` op `b` for + and -, given before the operation: pops two bounds, pushes one.
  void sum(const Bernstein<double>& a, const Bernstein<double>& b);
  /// `a` * `b`: pops two bounds, pushes one.
  void product(const Bernstein<double>& a, const Bernstein<double>& b);
  /// A division by a constant sub-program: pops two bounds, pushes infinity.
  void divide();
  /// a^exponent by the repeated squaring of pow() (the same products, so the same form),
  /// with its bound in place of a's.
  Bernstein<double> power(const Bernstein<double>& a, int exponent);

  /// The bound of the form on top of the stack.
  double top() const { return errors_.back(); }

  /// E relative to the largest exact coefficient of `form` (at least max |form| - E): infinity
  /// when E is not finite or not below max |form|, 0 for an exact zero form.
  static double relative(const Bernstein<double>& form, double error);

 private:
  /// The bound of a * b from the operands' bounds.
  static double productBound(const Bernstein<double>& a, double ea, const Bernstein<double>& b,
                             double eb);
  double pop();

  std::vector<double> errors_;
};

}  // namespace ndc
