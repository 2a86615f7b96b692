/// \file tape.hpp
/// The compiled form of an expression: a flat postfix program over a stack, built once per
/// expression. Every evaluator (value, gradient, interval, Bernstein in expression.hpp,
/// midpoint-radius in midrad.hpp, the magnitude bound in magnitude.hpp) runs over it; the syntax
/// tree is private to the parser.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/piecewise.hpp"
#include "framework/numeric/scalar.hpp"

namespace ndc {

/// One instruction. Operands push one value; unary instructions replace the top value;
/// binary ones replace the two top values (the left operand below the right one) by one.
struct TapeOp {
  enum class Kind : std::uint8_t {
    kConstant,  ///< push constant `arg` (Tape::constants)
    kVariable,  ///< push variable `arg`
    kLeaf,      ///< push piecewise leaf `arg` (Tape::leaves)
    kAdd,
    kSub,
    kMul,
    kDiv,  ///< left / right; the right operand is constant: instructions [arg, this one)
    kPow,  ///< top ^ arg, arg >= 0
    kNeg,
  };
  Kind kind;
  int arg = 0;
};

/// A numeric literal: its decimal text (so Mpfr reads it exactly), its nearest double, and a
/// double interval holding it.
struct TapeConstant {
  std::string literal;  ///< empty when the number is exactly `value` (Expression::constant)
  double value = 0;
  double lower = 0, upper = 0;

  /// The constant of a decimal literal (digits [. digits] [(e|E) [+|-] digits], finite as a
  /// double): its text, nearest double and tightest double enclosure.
  static TapeConstant fromLiteral(std::string literal);

  /// The literal from its text (rounded to nearest in S; the cached double for double).
  template <class S>
  S as() const;
  /// An interval in S that holds the literal (outward rounded).
  template <class S>
  Interval<S> enclosure() const;
};

/// A piecewise Bernstein leaf and its partial derivatives along its own axes.
struct TapeLeaf {
  std::shared_ptr<const PiecewiseBernstein> polynomial;
  std::vector<std::shared_ptr<const PiecewiseBernstein>> partials;
};

/// A compiled expression in `dim` variables. Immutable once built; shared between copies of
/// an Expression. Distinct leaves appear once in `leaves()`, so evaluators compute each once
/// per evaluation even where a built expression refers to it many times.
class Tape {
 public:
  /// An empty program in `dim` variables (push instructions to fill it).
  explicit Tape(int dim = 0) : dim_(dim) {}

  /// Appends an instruction and keeps the stack depth; returns its index.
  std::size_t push(TapeOp op);
  /// Appends a constant and the instruction that pushes it.
  void pushConstant(TapeConstant constant);
  /// Appends a leaf (shared with an equal pointer already present) and the instruction.
  void pushLeaf(const TapeLeaf& leaf);
  /// Appends the instructions of `other` (same dim), remapping its constants and leaves.
  void append(const Tape& other);

  int dim() const { return dim_; }
  std::span<const TapeOp> ops() const { return ops_; }
  const std::vector<TapeConstant>& constants() const { return constants_; }
  const std::vector<TapeLeaf>& leaves() const { return leaves_; }
  /// Stack slots an evaluation needs.
  int stackDepth() const { return depth_; }

  /// Degree in each variable (an upper bound: cancellation is ignored), saturated at INT_MAX.
  std::vector<int> degrees() const;
  /// Total degree, saturated at `cap`.
  int totalDegree(int cap) const;
  /// The break values of the leaves along variable j, sorted and unique.
  std::vector<double> breaks(int j) const;

 private:
  int dim_ = 0;
  int depth_ = 0;
  int top_ = 0;  ///< stack height after the last instruction
  std::vector<TapeOp> ops_;
  std::vector<TapeConstant> constants_;
  std::vector<TapeLeaf> leaves_;
};

// ---- Evaluators (defined in evaluate.cpp for S = double, Mpfr)
// ----------------------------------- T is a scalar S (a point) or Interval<S> (a box: the natural
// interval extension, outward rounded). `x` has tape.dim() entries; each distinct leaf is computed
// once per evaluation.

/// Value of the program at `x`.
template <class T>
T evaluateTape(const Tape& tape, std::span<const T> x);
/// Value and gradient (forward mode; `gradient` has tape.dim() entries).
template <class T>
T evaluateTape(const Tape& tape, std::span<const T> x, std::span<T> gradient);
/// Value of the constant sub-program [begin, end) of `tape` (the divisor of a kDiv instruction).
template <class S>
S evaluateConstant(const Tape& tape, std::size_t begin, std::size_t end);
/// The exact Bernstein form on `domain`, built in Bernstein arithmetic (each variable is the
/// linear polynomial on its interval, each leaf the piece holding the domain's projection).
template <class S>
Bernstein<S> bernsteinOfTape(const Tape& tape, const Box<S>& domain);
/// bernsteinOfTape in double, with `roundingError` >= the largest error of a coefficient
/// against the exact form of the program (literals as written; form_rounding.hpp): infinity
/// for programs with leaves or divisions.
Bernstein<double> bernsteinOfTape(const Tape& tape, const Box<double>& domain,
                                  double& roundingError);

}  // namespace ndc
