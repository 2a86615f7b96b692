/// \file expression.hpp
/// Polynomial expressions (docs/contracts.md 4.1): parsed and compiled once to a Tape, and
/// evaluated over it in plain, interval and Bernstein arithmetic, with or without gradients.
#pragma once

#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/piecewise.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/numeric/tape.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

/// A parsed polynomial expression in the variables `x_0..x_{n-1}`.
///
/// Grammar: numbers (decimal, scientific), variables, `+ - * /` (division by a constant
/// only), `^` with a non-negative integer exponent, parentheses, unary minus. Anything else
/// (function calls, unknown identifiers, non-integer exponents, division by a non-constant)
/// is an ExpressionError.
class Expression {
 public:
  /// The constant 0 in zero variables.
  Expression();

  /// Parses `text` with the given variable names; throws ExpressionError.
  static Expression parse(std::string_view text, std::span<const std::string> variables);

  /// The constant `value` (exactly this double) in `dim` variables.
  static Expression constant(int dim, double value);
  /// The variable `x_j` of `dim` variables, written `name` in the text.
  static Expression variable(int dim, int j, const std::string& name);
  /// A piecewise Bernstein polynomial leaf in `dim` variables (its axes are variables of
  /// these). Application problems are built from such leaves with `+ - *`, so their Bernstein
  /// forms come from Bernstein arithmetic on the input control points (no power basis).
  /// Throws std::invalid_argument when the leaf is invalid or uses a variable >= dim.
  static Expression polynomial(int dim, std::shared_ptr<const PiecewiseBernstein> leaf);
  /// Sum, difference and product (same dim), and negation.
  friend Expression operator+(const Expression& a, const Expression& b);
  friend Expression operator-(const Expression& a, const Expression& b);
  friend Expression operator*(const Expression& a, const Expression& b);
  friend Expression operator-(const Expression& a);
  /// Replaces the text (e.g. a name for a long built expression).
  void setText(std::string text) { text_ = std::move(text); }
  /// The break values of the piecewise leaves along variable j, sorted and unique (empty
  /// when no leaf is cut along j).
  std::vector<double> breaks(int j) const;

  /// Number of variables n.
  int dim() const { return dim_; }
  /// The source text.
  const std::string& text() const { return text_; }
  /// The compiled program (shared by copies; midrad.hpp and magnitude.hpp evaluate it too).
  const Tape& tape() const { return *tape_; }
  const std::shared_ptr<const Tape>& sharedTape() const { return tape_; }
  /// Degree in each variable (an upper bound from the program: cancellation is ignored).
  std::vector<int> degrees() const;
  /// Instructions of the program as the text was written; tape().ops().size() is smaller when
  /// parse() kept the canonical program (like terms collected, canonical.hpp).
  std::size_t writtenInstructions() const { return written_ ? written_ : tape_->ops().size(); }

  /// Value at a point.
  template <class S>
  S evaluate(std::span<const S> x) const;
  /// Value and gradient at a point (`gradient.size() == dim()`).
  template <class S>
  S evaluate(std::span<const S> x, std::span<S> gradient) const;
  /// Natural interval extension over a box of intervals.
  template <class S>
  Interval<S> evaluate(std::span<const Interval<S>> x) const;
  /// Interval value and interval gradient (for the mean-value form).
  template <class S>
  Interval<S> evaluate(std::span<const Interval<S>> x, std::span<Interval<S>> gradient) const;
  /// The exact Bernstein form on `domain`, built in Bernstein arithmetic (each variable is the
  /// linear polynomial on its interval; no power-basis conversion).
  template <class S>
  Bernstein<S> toBernstein(const Box<S>& domain) const;
  /// toBernstein in double, with `roundingError` >= the largest error of a coefficient against
  /// the exact form (the literals as written), proven along the way (form_rounding.hpp);
  /// infinity for expressions with B-spline leaves or divisions.
  Bernstein<double> toBernstein(const Box<double>& domain, double& roundingError) const;

 private:
  /// The program of `a`, then of `*b` (for binary kinds), then `kind`.
  static Expression join(TapeOp::Kind kind, const char* op, const Expression& a,
                         const Expression* b);
  int dim_ = 0;
  std::size_t written_ = 0;  ///< instructions as written (0: those of tape_)
  std::string text_;
  std::shared_ptr<const Tape> tape_;
};

}  // namespace ndc
