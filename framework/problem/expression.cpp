// Polynomial expressions: a parsed or built expression is compiled once to a Tape (parser.cpp,
// tape.cpp); the evaluators run over it (evaluate.cpp).
#include "framework/problem/expression.hpp"

#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "framework/numeric/canonical.hpp"
#include "framework/problem/parser.hpp"

namespace ndc {

namespace {

template <class X>
void checkSize(const Expression& e, std::span<X> x, const char* what) {
  if (static_cast<int>(x.size()) != e.dim())
    throw std::invalid_argument(std::string("Expression: ") + what + " has size " +
                                std::to_string(x.size()) + ", expected " + std::to_string(e.dim()));
}

void checkDomain(const Expression& e, int dim) {
  if (dim != e.dim())
    throw std::invalid_argument("Expression::toBernstein: the domain has dimension " +
                                std::to_string(dim) + ", expected " + std::to_string(e.dim()));
}

/// Programs of at most this many instructions are kept as written: a hand-written equation.
constexpr std::size_t kCanonicalAbove = 64;

/// A program of one operand instruction.
std::shared_ptr<const Tape> single(int dim, const TapeOp& op) {
  auto tape = std::make_shared<Tape>(dim);
  tape->push(op);
  return tape;
}

}  // namespace

Expression::Expression() : text_("0") {
  auto tape = std::make_shared<Tape>(0);
  tape->pushConstant({"0", 0, 0, 0});
  tape_ = std::move(tape);
}

Expression Expression::parse(std::string_view text, std::span<const std::string> variables) {
  Expression e;
  Tape tape = parseExpression(text, variables);
  // Compiled once: the canonical program (like terms collected) when it is at most half as
  // long, so a generated equation costs its coefficients, not its text (canonical.hpp). A
  // short hand-written program stays as written, with its natural interval extension.
  const std::size_t ops = tape.ops().size();
  e.written_ = ops;
  if (ops > kCanonicalAbove)
    if (std::optional<Tape> canonical = canonicalTape(tape, canonicalLimitsFor(ops));
        canonical && 2 * canonical->ops().size() <= ops)
      tape = std::move(*canonical);
  e.tape_ = std::make_shared<const Tape>(std::move(tape));
  e.dim_ = static_cast<int>(variables.size());
  e.text_ = std::string(text);
  return e;
}

Expression Expression::constant(int dim, double value) {
  if (!std::isfinite(value)) throw std::invalid_argument("Expression::constant: not finite");
  Expression e;
  e.dim_ = dim;
  auto tape = std::make_shared<Tape>(dim);
  tape->pushConstant({"", value, value, value});  // the double itself, exactly
  e.tape_ = std::move(tape);
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  e.text_ = text;
  return e;
}

Expression Expression::variable(int dim, int j, const std::string& name) {
  if (j < 0 || j >= dim) throw std::invalid_argument("Expression::variable: bad index");
  Expression e;
  e.dim_ = dim;
  e.tape_ = single(dim, {TapeOp::Kind::kVariable, j});
  e.text_ = name;
  return e;
}

Expression Expression::polynomial(int dim, std::shared_ptr<const PiecewiseBernstein> leaf) {
  leaf->validate();
  for (int axis : leaf->axes)
    if (axis < 0 || axis >= dim)
      throw std::invalid_argument(leaf->name + ": axis out of range for the problem variables");
  TapeLeaf compiled;
  for (int a = 0; a < leaf->dim(); ++a)
    compiled.partials.push_back(std::make_shared<const PiecewiseBernstein>(leaf->derivative(a)));
  Expression e;
  e.dim_ = dim;
  e.text_ = leaf->name;
  compiled.polynomial = std::move(leaf);
  auto tape = std::make_shared<Tape>(dim);
  tape->pushLeaf(compiled);
  e.tape_ = std::move(tape);
  return e;
}

Expression Expression::join(TapeOp::Kind kind, const char* op, const Expression& a,
                            const Expression* b) {
  if (b && a.dim_ != b->dim_)
    throw std::invalid_argument("Expression: operands in different numbers of variables");
  // Long operand texts are elided: built expressions can be large.
  const auto shown = [](const std::string& t) { return t.size() > 80 ? std::string("...") : t; };
  Expression e;
  e.dim_ = a.dim_;
  auto tape = std::make_shared<Tape>(a.dim_);
  tape->append(*a.tape_);
  if (b) {
    tape->append(*b->tape_);
    e.text_ = '(' + shown(a.text_);
    e.text_ += op;
    e.text_ += shown(b->text_);
    e.text_ += ')';
  } else {
    e.text_ = std::string(op) + '(' + shown(a.text_) + ')';
  }
  tape->push({kind, 0});
  e.tape_ = std::move(tape);
  return e;
}

Expression operator+(const Expression& a, const Expression& b) {
  return Expression::join(TapeOp::Kind::kAdd, " + ", a, &b);
}
Expression operator-(const Expression& a, const Expression& b) {
  return Expression::join(TapeOp::Kind::kSub, " - ", a, &b);
}
Expression operator*(const Expression& a, const Expression& b) {
  return Expression::join(TapeOp::Kind::kMul, " * ", a, &b);
}
Expression operator-(const Expression& a) {
  return Expression::join(TapeOp::Kind::kNeg, "-", a, nullptr);
}

std::vector<double> Expression::breaks(int j) const { return tape_->breaks(j); }

std::vector<int> Expression::degrees() const { return tape_->degrees(); }

template <class S>
S Expression::evaluate(std::span<const S> x) const {
  checkSize(*this, x, "point");
  return evaluateTape<S>(*tape_, x);
}

template <class S>
S Expression::evaluate(std::span<const S> x, std::span<S> gradient) const {
  checkSize(*this, x, "point");
  checkSize(*this, gradient, "gradient");
  return evaluateTape<S>(*tape_, x, gradient);
}

template <class S>
Interval<S> Expression::evaluate(std::span<const Interval<S>> x) const {
  checkSize(*this, x, "box");
  return evaluateTape<Interval<S>>(*tape_, x);
}

template <class S>
Interval<S> Expression::evaluate(std::span<const Interval<S>> x,
                                 std::span<Interval<S>> gradient) const {
  checkSize(*this, x, "box");
  checkSize(*this, gradient, "gradient");
  return evaluateTape<Interval<S>>(*tape_, x, gradient);
}

template <class S>
Bernstein<S> Expression::toBernstein(const Box<S>& domain) const {
  checkDomain(*this, domain.dim());
  return bernsteinOfTape(*tape_, domain);
}

Bernstein<double> Expression::toBernstein(const Box<double>& domain, double& roundingError) const {
  checkDomain(*this, domain.dim());
  return bernsteinOfTape(*tape_, domain, roundingError);
}

// ---- Explicit instantiation --------------------------------------------------------------------

#define NDC_INSTANTIATE_EXPRESSION(S)                                               \
  template S Expression::evaluate<S>(std::span<const S>) const;                     \
  template S Expression::evaluate<S>(std::span<const S>, std::span<S>) const;       \
  template Interval<S> Expression::evaluate<S>(std::span<const Interval<S>>) const; \
  template Interval<S> Expression::evaluate<S>(std::span<const Interval<S>>,        \
                                               std::span<Interval<S>>) const;       \
  template Bernstein<S> Expression::toBernstein<S>(const Box<S>&) const;

NDC_INSTANTIATE_EXPRESSION(double)
NDC_INSTANTIATE_EXPRESSION(Mpfr)
#undef NDC_INSTANTIATE_EXPRESSION

}  // namespace ndc
