/// \file expression.hpp
/// Polynomial expressions (docs/contracts.md 4.1): parsing to a syntax tree and evaluation in
/// plain, interval and Bernstein arithmetic, with or without gradients.
#pragma once

#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "framework/core/bernstein.hpp"
#include "framework/core/box.hpp"
#include "framework/core/errors.hpp"
#include "framework/core/interval.hpp"
#include "framework/core/piecewise.hpp"
#include "framework/core/scalar.hpp"

namespace ndc {

/// A node of the syntax tree.
struct ExprNode {
  enum class Kind { kNumber, kVariable, kAdd, kSub, kMul, kDiv, kPow, kNeg, kPolynomial };
  Kind kind;
  /// kNumber: the decimal text, kept so Mpfr parses it exactly; empty when the number is the
  /// double `value` exactly (numbers built by Expression::constant)
  std::string literal;
  double value = 0;  ///< kNumber: the literal rounded to the nearest double (cached)
  double enclosureLo = 0, enclosureHi = 0;  ///< kNumber: a double interval holding the literal
  int variable = -1;                        ///< kVariable: index into the variable list
  int exponent = 0;                         ///< kPow: the non-negative integer exponent
  std::unique_ptr<ExprNode> left, right;    ///< operands (kNeg and kPow use left only)
  /// kPolynomial: the piecewise Bernstein leaf, and its partial derivative along each local
  /// axis (for gradients)
  std::shared_ptr<const PiecewiseBernstein> polynomial;
  std::vector<std::shared_ptr<const PiecewiseBernstein>> partials;
  /// kPolynomial: number of the leaf among the tree's distinct leaves (evaluations compute
  /// each distinct leaf once)
  int leafIndex = -1;
};

/// A parsed polynomial expression in the variables `x_0..x_{n-1}`.
///
/// Grammar: numbers (decimal, scientific), variables, `+ - * /` (division by a constant
/// only), `^` with a non-negative integer exponent, parentheses, unary minus. Anything else
/// (function calls, unknown identifiers, non-integer exponents, division by a non-constant)
/// is an ExpressionError.
class Expression {
 public:
  Expression();
  Expression(const Expression&);
  Expression(Expression&&) noexcept;
  Expression& operator=(const Expression&);
  Expression& operator=(Expression&&) noexcept;
  ~Expression();

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
  const ExprNode& root() const { return *root_; }
  /// Degree in each variable (an upper bound from the syntax tree: cancellation is ignored).
  std::vector<int> degrees() const;

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

 private:
  /// A node of `kind` over copies of `a` and (for binary kinds) `*b`.
  static Expression join(ExprNode::Kind kind, const char* op, const Expression& a,
                         const Expression* b);
  int dim_ = 0;
  int slots_ = 1;   ///< evaluation slots the gradient evaluator needs: tree height + 1
  int leaves_ = 0;  ///< distinct piecewise leaves in the tree
  std::string text_;
  std::unique_ptr<ExprNode> root_;
};

}  // namespace ndc
