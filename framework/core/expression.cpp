// Polynomial expressions: recursive-descent parser and the evaluators (plain, gradient,
// interval, interval gradient, Bernstein), instantiated for double and Mpfr.
//
// Exponent rule: the right operand of `^` is a non-negative integer literal written with digits
// only ("2", not "2.0" or "2e0"), optionally in parentheses, at most kMaxExponent; `^` is right
// associative and the exponent itself may be a power of such literals, folded at parse time
// (`x^2^3` = `x^(2^3)` = `x^8`). `^` binds tighter than unary minus: `-x^2` = `-(x^2)`.
// A divisor must be a constant subexpression (no variable) that is certified nonzero by
// interval arithmetic in double at parse time. Unary plus is accepted.
#include "framework/core/expression.hpp"

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace ndc {

namespace {

/// Largest exponent the parser accepts (a Bernstein degree beyond it is not a sane input).
constexpr long kMaxExponent = 10000;
/// Parentheses, signs and parenthesised exponents nest at most this deep: every evaluator
/// walks the tree recursively, so its height must stay far below what the stack holds.
constexpr int kMaxNesting = 200;
/// Sums and products of more terms than this are built as balanced trees (height log2 of the
/// count, so a sum of 100,000 terms is 17 levels); shorter ones keep the left-to-right order.
constexpr std::size_t kBalanceAbove = 16;

std::unique_ptr<ExprNode> makeNode(ExprNode::Kind kind) {
  auto node = std::make_unique<ExprNode>();
  node->kind = kind;
  return node;
}

std::unique_ptr<ExprNode> makeBinary(ExprNode::Kind kind, std::unique_ptr<ExprNode> left,
                                     std::unique_ptr<ExprNode> right) {
  auto node = makeNode(kind);
  node->left = std::move(left);
  node->right = std::move(right);
  return node;
}

/// Sets a number node's literal and its cached double value and double enclosure.
void setNumber(ExprNode& node, std::string literal) {
  const Interval<double> enclosure = Interval<double>::fromString(literal);
  node.value = std::strtod(literal.c_str(), nullptr);
  node.enclosureLo = enclosure.lower();
  node.enclosureHi = enclosure.upper();
  node.literal = std::move(literal);
}

std::unique_ptr<ExprNode> clone(const ExprNode& n) {
  auto node = makeNode(n.kind);
  node->literal = n.literal;
  node->value = n.value;
  node->enclosureLo = n.enclosureLo;
  node->enclosureHi = n.enclosureHi;
  node->variable = n.variable;
  node->exponent = n.exponent;
  if (n.left) node->left = clone(*n.left);
  if (n.right) node->right = clone(*n.right);
  node->polynomial = n.polynomial;
  node->partials = n.partials;
  node->leafIndex = n.leafIndex;
  return node;
}

int height(const ExprNode& n) {
  int h = 0;
  if (n.left) h = std::max(h, height(*n.left));
  if (n.right) h = std::max(h, height(*n.right) + 1);  // the right operand uses the next slot
  return h;
}

bool isIdentifierStart(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}
bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isIdentifierChar(char c) { return isIdentifierStart(c) || isDigit(c); }

// ---- Arithmetic of the evaluators: T is S or Interval<S> ---------------------------------------

template <class T>
struct Arith;

template <>
struct Arith<double> {
  static double number(const ExprNode& n) { return n.value; }  // rounded at parse time
  static double constant(int k) { return k; }
  static double power(const double& a, int n) {
    // Binary powering: exact for small integers, a few roundings otherwise.
    double result = 1, base = a;
    for (; n > 0; n >>= 1) {
      if (n & 1) result *= base;
      if (n > 1) base *= base;
    }
    return result;
  }
  static double divide(const double& a, const double& c) { return a / c; }
};

template <>
struct Arith<Mpfr> {
  static Mpfr number(const ExprNode& n) {
    if (n.literal.empty()) return Mpfr(n.value);  // an exact double
    Mpfr v;
    mpfr_set_str(v.backend().data(), n.literal.c_str(), 10, MPFR_RNDN);
    return v;
  }
  static Mpfr constant(int k) { return Mpfr(k); }
  static Mpfr power(const Mpfr& a, int n) {
    Mpfr result = 1, base = a;
    for (; n > 0; n >>= 1) {
      if (n & 1) result *= base;
      if (n > 1) base *= base;
    }
    return result;
  }
  static Mpfr divide(const Mpfr& a, const Mpfr& c) { return a / c; }
};

template <class S>
struct Arith<Interval<S>> {
  using T = Interval<S>;
  static T number(const ExprNode& n) {
    // Double intervals use the enclosure computed at parse time; others parse the literal.
    if constexpr (std::is_same_v<S, double>) {
      return T(n.enclosureLo, n.enclosureHi);
    } else {
      if (n.literal.empty()) return T(S(n.value));  // an exact double
      return T::fromString(n.literal);
    }
  }
  static T constant(int k) { return T(S(k)); }
  static T power(const T& a, int n) { return a.pow(n); }  // even-power rule: tight
  static T divide(const T& a, const T& c) {
    if (c.containsZero()) throw std::domain_error("Expression: divisor interval contains zero");
    S lo = c.lower(), hi = c.upper();
    if (lo == hi) return a.dividedBy(lo);
    // 1/t is monotonic on c, so the hull of the enclosures of 1/lo and 1/hi encloses 1/c.
    T reciprocal = T(S(1)).dividedBy(lo).hull(T(S(1)).dividedBy(hi));
    return a * reciprocal;
  }
};

// ---- Piecewise Bernstein leaves -----------------------------------------------------------------

template <class T>
struct IntervalScalar {
  using type = void;
};
template <class S>
struct IntervalScalar<Interval<S>> {
  using type = S;
};

/// Value (or enclosure, for intervals) of a leaf at the problem point x.
template <class T>
T leafValue(const PiecewiseBernstein& leaf, std::span<const T> x) {
  constexpr int kMax = 8;  // PiecewiseBernstein::validate allows at most 8 axes
  T local[kMax];
  for (int a = 0; a < leaf.dim(); ++a) local[a] = x[leaf.axes[a]];
  const std::span<const T> span(local, static_cast<std::size_t>(leaf.dim()));
  using S = typename IntervalScalar<T>::type;
  if constexpr (std::is_void_v<S>)
    return leaf.evaluate<T>(span);
  else
    return leaf.enclose<S>(span);
}

// ---- Evaluation of the value only ---------------------------------------------------------------

/// Values of the distinct piecewise leaves of a tree during one evaluation: built expressions
/// refer to the same few leaves many times (ExprNode::leafIndex numbers them).
template <class T>
struct LeafMemo {
  std::vector<T> values;  ///< evalValue: one per leaf; GradientEvaluator: dim + 1 per leaf
  std::vector<unsigned char> done;
  void reset(int leaves, std::size_t stride) {
    if (values.size() < static_cast<std::size_t>(leaves) * stride)
      values.resize(static_cast<std::size_t>(leaves) * stride, Arith<T>::constant(0));
    done.assign(static_cast<std::size_t>(leaves), 0);
  }
};

// Recursive evaluation on the tree; for double no heap allocation at all (once warm).
template <class T>
T evalValue(const ExprNode& n, std::span<const T> x, LeafMemo<T>* memo = nullptr) {
  using K = ExprNode::Kind;
  switch (n.kind) {
    case K::kNumber:
      return Arith<T>::number(n);
    case K::kVariable:
      return x[n.variable];
    case K::kAdd:
      return evalValue(*n.left, x, memo) + evalValue(*n.right, x, memo);
    case K::kSub:
      return evalValue(*n.left, x, memo) - evalValue(*n.right, x, memo);
    case K::kMul:
      return evalValue(*n.left, x, memo) * evalValue(*n.right, x, memo);
    case K::kDiv:
      return Arith<T>::divide(evalValue(*n.left, x, memo), evalValue(*n.right, x, memo));
    case K::kPow:
      return Arith<T>::power(evalValue(*n.left, x, memo), n.exponent);
    case K::kNeg:
      return -evalValue(*n.left, x, memo);
    case K::kPolynomial: {
      if (!memo || n.leafIndex < 0) return leafValue<T>(*n.polynomial, x);
      const auto i = static_cast<std::size_t>(n.leafIndex);
      if (!memo->done[i]) {
        memo->values[i] = leafValue<T>(*n.polynomial, x);
        memo->done[i] = 1;
      }
      return memo->values[i];
    }
  }
  throw std::logic_error("Expression: bad node kind");
}

// ---- Evaluation with gradient (forward mode) ---------------------------------------------------

// Each subtree is evaluated into a slot of dim + 1 values (value, then the gradient) of one
// workspace allocated per call; a binary node puts its right operand in the next slot.
template <class T>
class GradientEvaluator {
 public:
  /// `slots` is the tree's height + 1; `work` is scratch the evaluator may resize (a reused
  /// per-thread buffer for double, so the Newton loop does not allocate).
  GradientEvaluator(int slots, int leaves, std::span<const T> x, std::vector<T>& work,
                    LeafMemo<T>& memo)
      : x_(x), stride_(x.size() + 1), work_(work), memo_(memo) {
    work_.resize(std::size_t(slots) * stride_, Arith<T>::constant(0));
    memo_.reset(leaves, stride_);
  }

  /// Evaluates `root` into slot 0 and returns the value; the gradient is copied to `gradient`.
  T run(const ExprNode& root, std::span<T> gradient) {
    eval(root, 0);
    for (std::size_t j = 0; j + 1 < stride_; ++j) gradient[j] = work_[j + 1];
    return work_[0];
  }

 private:
  void eval(const ExprNode& n, std::size_t slot) {
    using K = ExprNode::Kind;
    T* out = &work_[slot * stride_];
    switch (n.kind) {
      case K::kNumber:
        out[0] = Arith<T>::number(n);
        setZeroGradient(out);
        return;
      case K::kVariable:
        out[0] = x_[n.variable];
        setZeroGradient(out);
        out[n.variable + 1] = Arith<T>::constant(1);
        return;
      case K::kAdd:
      case K::kSub: {
        eval(*n.left, slot);
        eval(*n.right, slot + 1);
        const T* r = out + stride_;
        for (std::size_t k = 0; k < stride_; ++k) {
          if (n.kind == K::kAdd)
            out[k] += r[k];
          else
            out[k] -= r[k];
        }
        return;
      }
      case K::kMul: {
        // Product rule: (ab)' = a'b + ab'.
        eval(*n.left, slot);
        eval(*n.right, slot + 1);
        const T* r = out + stride_;
        for (std::size_t k = 1; k < stride_; ++k) out[k] = out[k] * r[0] + out[0] * r[k];
        out[0] *= r[0];
        return;
      }
      case K::kDiv: {
        // The divisor is a constant: (a/c)' = a'/c.
        eval(*n.left, slot);
        T c = evalValue(*n.right, x_);
        for (std::size_t k = 0; k < stride_; ++k) out[k] = Arith<T>::divide(out[k], c);
        return;
      }
      case K::kPow: {
        // (a^p)' = p a^(p-1) a'; the value is a^p itself (tight for intervals).
        eval(*n.left, slot);
        int p = n.exponent;
        if (p == 0) {
          out[0] = Arith<T>::constant(1);
          setZeroGradient(out);
          return;
        }
        T factor = Arith<T>::constant(p) * Arith<T>::power(out[0], p - 1);
        out[0] = Arith<T>::power(out[0], p);
        for (std::size_t k = 1; k < stride_; ++k) out[k] = factor * out[k];
        return;
      }
      case K::kNeg:
        eval(*n.left, slot);
        for (std::size_t k = 0; k < stride_; ++k) out[k] = -out[k];
        return;
      case K::kPolynomial: {
        // The leaf's value, and its partials along its own axes (zero along the others),
        // computed once per distinct leaf and evaluation.
        T* block = &memo_.values[static_cast<std::size_t>(n.leafIndex) * stride_];
        if (!memo_.done[static_cast<std::size_t>(n.leafIndex)]) {
          block[0] = leafValue<T>(*n.polynomial, x_);
          for (std::size_t k = 1; k < stride_; ++k) block[k] = Arith<T>::constant(0);
          const auto& axes = n.polynomial->axes;
          for (std::size_t a = 0; a < axes.size(); ++a)
            block[axes[a] + 1] = leafValue<T>(*n.partials[a], x_);
          memo_.done[static_cast<std::size_t>(n.leafIndex)] = 1;
        }
        for (std::size_t k = 0; k < stride_; ++k) out[k] = block[k];
        return;
      }
    }
    throw std::logic_error("Expression: bad node kind");
  }

  void setZeroGradient(T* out) {
    for (std::size_t k = 1; k < stride_; ++k) out[k] = Arith<T>::constant(0);
  }

  std::span<const T> x_;
  std::size_t stride_;
  std::vector<T>& work_;
  LeafMemo<T>& memo_;
};

/// Numbers the distinct leaves of a tree (ExprNode::leafIndex); returns how many there are.
int indexLeaves(ExprNode& root) {
  std::vector<const PiecewiseBernstein*> seen;
  std::vector<ExprNode*> stack{&root};
  while (!stack.empty()) {
    ExprNode* n = stack.back();
    stack.pop_back();
    if (n->left) stack.push_back(n->left.get());
    if (n->right) stack.push_back(n->right.get());
    if (n->kind != ExprNode::Kind::kPolynomial) continue;
    const auto it = std::find(seen.begin(), seen.end(), n->polynomial.get());
    n->leafIndex = static_cast<int>(it - seen.begin());
    if (it == seen.end()) seen.push_back(n->polynomial.get());
  }
  return static_cast<int>(seen.size());
}

// ---- Bernstein form -------------------------------------------------------------------------

template <class S>
Bernstein<S> evalBernstein(const ExprNode& n, const Box<S>& domain) {
  using K = ExprNode::Kind;
  switch (n.kind) {
    case K::kNumber:
      return Bernstein<S>::constant(
          domain, n.literal.empty() ? S(n.value) : ScalarTraits<S>::fromString(n.literal));
    case K::kVariable:
      return Bernstein<S>::variable(domain, n.variable);
    case K::kAdd:
      return evalBernstein(*n.left, domain) + evalBernstein(*n.right, domain);
    case K::kSub:
      return evalBernstein(*n.left, domain) - evalBernstein(*n.right, domain);
    case K::kMul:
      return evalBernstein(*n.left, domain) * evalBernstein(*n.right, domain);
    case K::kDiv: {
      // The divisor is a constant: scale by its reciprocal.
      S c = evalValue<S>(*n.right, {});
      return evalBernstein(*n.left, domain) * (S(1) / c);
    }
    case K::kPow:
      return pow(evalBernstein(*n.left, domain), n.exponent);
    case K::kNeg:
      return -evalBernstein(*n.left, domain);
    case K::kPolynomial: {
      // The piece holding the domain's projection, restricted to it, embedded in n variables.
      const PiecewiseBernstein& leaf = *n.polynomial;
      Box<S> local;
      for (int axis : leaf.axes) {
        local.lo.push_back(domain.lo[axis]);
        local.hi.push_back(domain.hi[axis]);
      }
      return leaf.onBox<S>(local).embed(domain, leaf.axes);
    }
  }
  throw std::logic_error("Expression: bad node kind");
}

// ---- Degrees -----------------------------------------------------------------------------------

int saturatingAdd(int a, int b) { return a > INT_MAX - b ? INT_MAX : a + b; }
int saturatingMul(int a, int b) { return a != 0 && b > INT_MAX / a ? INT_MAX : a * b; }

void degreesOf(const ExprNode& n, std::vector<int>& out) {
  using K = ExprNode::Kind;
  std::fill(out.begin(), out.end(), 0);
  switch (n.kind) {
    case K::kNumber:
      return;
    case K::kVariable:
      out[n.variable] = 1;
      return;
    case K::kAdd:
    case K::kSub:
    case K::kMul: {
      std::vector<int> right(out.size());
      degreesOf(*n.left, out);
      degreesOf(*n.right, right);
      for (std::size_t j = 0; j < out.size(); ++j)
        out[j] = n.kind == K::kMul ? saturatingAdd(out[j], right[j]) : std::max(out[j], right[j]);
      return;
    }
    case K::kDiv:  // the divisor is a constant
    case K::kNeg:
      degreesOf(*n.left, out);
      return;
    case K::kPow:
      degreesOf(*n.left, out);
      for (int& d : out) d = saturatingMul(d, n.exponent);
      return;
    case K::kPolynomial:
      for (int a = 0; a < n.polynomial->dim(); ++a)
        out[n.polynomial->axes[a]] = n.polynomial->degree(a);
      return;
  }
}

// ---- Parser ------------------------------------------------------------------------------------

// Grammar (whitespace between tokens is ignored):
//   expression := term (('+' | '-') term)*
//   term       := unary (('*' | '/') unary)*
//   unary      := ('-' | '+') unary | power
//   power      := primary ('^' exponent)?
//   exponent   := (INTEGER | '(' exponent ')') ('^' exponent)?
//   primary    := NUMBER | VARIABLE | '(' expression ')'
class Parser {
 public:
  Parser(std::string_view text, std::span<const std::string> variables)
      : text_(text), variables_(variables) {}

  std::unique_ptr<ExprNode> parse() {
    skipSpace();
    if (atEnd()) fail(0, "empty expression");
    auto node = expression();
    skipSpace();
    if (!atEnd()) failUnexpected();
    return node;
  }

 private:
  [[noreturn]] void fail(std::size_t pos, const std::string& message) const {
    throw ExpressionError(static_cast<int>(pos) + 1, message);
  }

  // Diagnoses the token at pos_ where an operator, ')' or the end was expected.
  [[noreturn]] void failUnexpected() const {
    char c = text_[pos_];
    if (c == ')') fail(pos_, "unmatched ')'");
    if (isIdentifierStart(c) || isDigit(c) || c == '.' || c == '(')
      fail(pos_, std::string("missing operator before '") + c + "'");
    fail(pos_, std::string("unexpected character '") + c + "'");
  }

  bool atEnd() const { return pos_ >= text_.size(); }
  char peek() const { return atEnd() ? '\0' : text_[pos_]; }
  void skipSpace() {
    while (!atEnd() && (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\n' ||
                        text_[pos_] == '\r'))
      ++pos_;
  }

  /// Counts one level of nesting for its lifetime; past kMaxNesting the parse fails.
  class Nest {
   public:
    explicit Nest(Parser& p) : p_(p) {
      if (++p_.nesting_ > kMaxNesting)
        p_.fail(p_.pos_, "expression nested too deeply (more than " + std::to_string(kMaxNesting) +
                             " levels of parentheses, signs or exponents)");
    }
    ~Nest() { --p_.nesting_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;

   private:
    Parser& p_;
  };

  std::unique_ptr<ExprNode> expression() {
    // The terms and whether each is subtracted.
    std::vector<std::unique_ptr<ExprNode>> terms;
    std::vector<bool> minus;
    terms.push_back(term());
    minus.push_back(false);
    for (;;) {
      skipSpace();
      char c = peek();
      if (c != '+' && c != '-') break;
      ++pos_;
      terms.push_back(term());
      minus.push_back(c == '-');
    }
    if (terms.size() <= kBalanceAbove) {
      auto left = std::move(terms[0]);
      for (std::size_t i = 1; i < terms.size(); ++i)
        left = makeBinary(minus[i] ? ExprNode::Kind::kSub : ExprNode::Kind::kAdd, std::move(left),
                          std::move(terms[i]));
      return left;
    }
    return balancedSum(terms, minus, 0, terms.size());
  }

  /// sum_{lo <= i < hi} (s_i / s_lo) t_i with s_i = -1 for a subtracted term: the left half
  /// plus or minus the right half, each relative to its own first sign.
  static std::unique_ptr<ExprNode> balancedSum(std::vector<std::unique_ptr<ExprNode>>& terms,
                                               const std::vector<bool>& minus, std::size_t lo,
                                               std::size_t hi) {
    if (hi - lo == 1) return std::move(terms[lo]);
    const std::size_t mid = lo + (hi - lo) / 2;
    auto left = balancedSum(terms, minus, lo, mid);
    auto right = balancedSum(terms, minus, mid, hi);
    return makeBinary(minus[mid] == minus[lo] ? ExprNode::Kind::kAdd : ExprNode::Kind::kSub,
                      std::move(left), std::move(right));
  }

  std::unique_ptr<ExprNode> term() {
    // The operands, each a factor ('*') or a constant divisor ('/').
    std::vector<std::unique_ptr<ExprNode>> operands;
    std::vector<bool> divide;
    operands.push_back(unary());
    divide.push_back(false);
    for (;;) {
      skipSpace();
      char c = peek();
      if (c == '*') {
        ++pos_;
        operands.push_back(unary());
        divide.push_back(false);
      } else if (c == '/') {
        ++pos_;
        skipSpace();
        operands.push_back(divisor());
        divide.push_back(true);
      } else {
        break;
      }
    }
    if (operands.size() <= kBalanceAbove) {
      auto left = std::move(operands[0]);
      for (std::size_t i = 1; i < operands.size(); ++i)
        left = makeBinary(divide[i] ? ExprNode::Kind::kDiv : ExprNode::Kind::kMul, std::move(left),
                          std::move(operands[i]));
      return left;
    }
    // Long: each factor takes the divisors that follow it, then the factors are multiplied.
    std::vector<std::unique_ptr<ExprNode>> factors;
    for (std::size_t i = 0; i < operands.size(); ++i) {
      if (divide[i]) {
        factors.back() =
            makeBinary(ExprNode::Kind::kDiv, std::move(factors.back()), std::move(operands[i]));
      } else {
        factors.push_back(std::move(operands[i]));
      }
    }
    return balancedProduct(factors, 0, factors.size());
  }

  static std::unique_ptr<ExprNode> balancedProduct(std::vector<std::unique_ptr<ExprNode>>& factors,
                                                   std::size_t lo, std::size_t hi) {
    if (hi - lo == 1) return std::move(factors[lo]);
    const std::size_t mid = lo + (hi - lo) / 2;
    auto left = balancedProduct(factors, lo, mid);
    return makeBinary(ExprNode::Kind::kMul, std::move(left), balancedProduct(factors, mid, hi));
  }

  // The right operand of '/': a constant subexpression certified nonzero.
  std::unique_ptr<ExprNode> divisor() {
    std::size_t start = pos_;
    auto saved = std::exchange(firstVariable_, std::pair<std::size_t, int>{0, -1});
    auto node = unary();
    if (firstVariable_.second >= 0)
      fail(firstVariable_.first, "division by a non-constant: the divisor depends on '" +
                                     variables_[firstVariable_.second] +
                                     "' (only constant divisors are allowed)");
    firstVariable_ = saved;
    Interval<double> value = evalValue<Interval<double>>(*node, {});
    if (value.lower() == 0 && value.upper() == 0) fail(start, "division by zero");
    if (value.containsZero())
      fail(start, "division by a constant that is too close to zero to certify it is nonzero");
    return node;
  }

  std::unique_ptr<ExprNode> unary() {
    skipSpace();
    if (peek() == '-') {
      const Nest nest(*this);
      ++pos_;
      auto node = makeNode(ExprNode::Kind::kNeg);
      node->left = unary();
      return node;
    }
    if (peek() == '+') {
      const Nest nest(*this);
      ++pos_;
      return unary();
    }
    return power();
  }

  std::unique_ptr<ExprNode> power() {
    auto base = primary();
    skipSpace();
    if (peek() != '^') return base;
    ++pos_;
    const int p = static_cast<int>(exponent());
    // a^0 is the constant 1 (0^0 = 1 as in polynomial algebra). Folding it drops the base,
    // whose degree the expression's degrees no longer show: an evaluator would otherwise build
    // the Bernstein form of ((x^10000)^10000)^0, past every size limit (a fuzzing finding).
    if (p == 0) {
      auto one = makeNode(ExprNode::Kind::kNumber);
      setNumber(*one, "1");
      return one;
    }
    auto node = makeNode(ExprNode::Kind::kPow);
    node->left = std::move(base);
    node->exponent = p;
    return node;
  }

  long exponent() {
    skipSpace();
    std::size_t start = pos_;
    long value = 0;
    if (peek() == '(') {
      const Nest nest(*this);
      ++pos_;
      value = exponent();
      skipSpace();
      if (atEnd()) fail(pos_, "missing ')' to close '(' at column " + std::to_string(start + 1));
      if (peek() != ')') fail(pos_, "the exponent must be a non-negative integer literal");
      ++pos_;
    } else if (isDigit(peek()) || peek() == '.') {
      std::string_view token = numberToken();
      for (char c : token)
        if (!isDigit(c))
          fail(start, "the exponent must be a non-negative integer literal, got '" +
                          std::string(token) + "'");
      for (char c : token) {
        value = value * 10 + (c - '0');
        if (value > kMaxExponent)
          fail(start, "exponent too large (at most " + std::to_string(kMaxExponent) + ")");
      }
    } else if (peek() == '-') {
      fail(pos_,
           "the exponent must be a non-negative integer (negative powers are not polynomial)");
    } else if (atEnd()) {
      fail(pos_, "unexpected end of expression: expected an exponent after '^'");
    } else {
      fail(pos_, "the exponent must be a non-negative integer literal");
    }
    // Right associativity: a^b^c = a^(b^c), folded here.
    skipSpace();
    if (peek() == '^') {
      ++pos_;
      long outer = exponent();
      long folded = 1;
      for (long k = 0; k < outer; ++k) {
        folded *= value;
        if (folded > kMaxExponent)
          fail(start, "exponent too large (at most " + std::to_string(kMaxExponent) + ")");
        if (folded == 0 || folded == 1) break;
      }
      value = folded;
    }
    return value;
  }

  std::unique_ptr<ExprNode> primary() {
    skipSpace();
    if (atEnd()) fail(pos_, "unexpected end of expression: expected a number, variable or '('");
    char c = peek();
    if (isDigit(c) || c == '.') return number();
    if (isIdentifierStart(c)) return identifier();
    if (c == '(') {
      const Nest nest(*this);
      std::size_t open = pos_++;
      auto node = expression();
      skipSpace();
      if (atEnd()) fail(pos_, "missing ')' to close '(' at column " + std::to_string(open + 1));
      if (peek() != ')') failUnexpected();
      ++pos_;
      return node;
    }
    if (c == ')') fail(pos_, "unexpected ')': expected a number, variable or '('");
    if (c == '*' || c == '/' || c == '^')
      fail(pos_, std::string("unexpected '") + c + "': expected a number, variable or '('");
    fail(pos_, std::string("unexpected character '") + c + "'");
  }

  // Scans digits [. digits] [(e|E) [+|-] digits]; an 'e' not followed by an exponent is left.
  std::string_view numberToken() {
    std::size_t start = pos_;
    while (isDigit(peek())) ++pos_;
    if (peek() == '.') {
      ++pos_;
      while (isDigit(peek())) ++pos_;
    }
    if (peek() == 'e' || peek() == 'E') {
      std::size_t k = pos_ + 1;
      if (k < text_.size() && (text_[k] == '+' || text_[k] == '-')) ++k;
      if (k < text_.size() && isDigit(text_[k])) {
        pos_ = k;
        while (isDigit(peek())) ++pos_;
      }
    }
    return text_.substr(start, pos_ - start);
  }

  std::unique_ptr<ExprNode> number() {
    std::size_t start = pos_;
    std::string token(numberToken());
    // A mantissa without a digit ('.', '.e+5') is no number; strtod would read it as 0 and the
    // exact readers (Interval, Mpfr) refuse it with another exception.
    if (token.substr(0, token.find_first_of("eE")).find_first_of("0123456789") == std::string::npos)
      fail(start, "malformed number '" + token + "'");
    // The value must be a finite double (the same rule for every scalar type).
    double v = std::strtod(token.c_str(), nullptr);
    if (!std::isfinite(v)) fail(start, "number out of range (not finite): '" + token + "'");
    auto node = makeNode(ExprNode::Kind::kNumber);
    setNumber(*node, std::move(token));
    return node;
  }

  std::unique_ptr<ExprNode> identifier() {
    std::size_t start = pos_;
    while (isIdentifierChar(peek())) ++pos_;
    std::string name(text_.substr(start, pos_ - start));
    std::size_t after = pos_;
    skipSpace();
    if (peek() == '(') fail(start, "function calls are not allowed: '" + name + "'");
    pos_ = after;
    for (std::size_t j = 0; j < variables_.size(); ++j) {
      if (variables_[j] != name) continue;
      if (firstVariable_.second < 0) firstVariable_ = {start, static_cast<int>(j)};
      auto node = makeNode(ExprNode::Kind::kVariable);
      node->variable = static_cast<int>(j);
      return node;
    }
    std::string known;
    for (const auto& v : variables_) known += (known.empty() ? "" : ", ") + v;
    fail(start, "unknown variable '" + name + "' (variables: " + known + ")");
  }

  std::string_view text_;
  std::span<const std::string> variables_;
  std::size_t pos_ = 0;
  /// Column (0-based) and index of the first variable seen in the current divisor, or -1.
  std::pair<std::size_t, int> firstVariable_{0, -1};
  int nesting_ = 0;  ///< current depth of parentheses, signs and exponent parentheses
};

template <class X>
void checkSize(const Expression& e, std::span<X> x, const char* what) {
  if (static_cast<int>(x.size()) != e.dim())
    throw std::invalid_argument(std::string("Expression: ") + what + " has size " +
                                std::to_string(x.size()) + ", expected " + std::to_string(e.dim()));
}

}  // namespace

// ---- Expression --------------------------------------------------------------------------------

Expression::Expression() : root_(makeNode(ExprNode::Kind::kNumber)) {
  setNumber(*root_, "0");
  text_ = "0";
}
Expression::Expression(const Expression& o)
    : dim_(o.dim_),
      slots_(o.slots_),
      leaves_(o.leaves_),
      text_(o.text_),
      root_(o.root_ ? clone(*o.root_) : nullptr) {}
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(const Expression& o) {
  if (this != &o) *this = Expression(o);
  return *this;
}
Expression& Expression::operator=(Expression&&) noexcept = default;
Expression::~Expression() = default;

Expression Expression::parse(std::string_view text, std::span<const std::string> variables) {
  Expression e;
  e.root_ = Parser(text, variables).parse();
  e.dim_ = static_cast<int>(variables.size());
  e.text_ = std::string(text);
  e.slots_ = height(*e.root_) + 1;
  return e;
}

Expression Expression::constant(int dim, double value) {
  if (!std::isfinite(value)) throw std::invalid_argument("Expression::constant: not finite");
  Expression e;
  e.dim_ = dim;
  e.root_->value = value;
  e.root_->enclosureLo = e.root_->enclosureHi = value;
  e.root_->literal.clear();  // the double itself, exactly
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  e.text_ = text;
  return e;
}

Expression Expression::variable(int dim, int j, const std::string& name) {
  if (j < 0 || j >= dim) throw std::invalid_argument("Expression::variable: bad index");
  Expression e;
  e.dim_ = dim;
  e.root_ = makeNode(ExprNode::Kind::kVariable);
  e.root_->variable = j;
  e.text_ = name;
  return e;
}

Expression Expression::polynomial(int dim, std::shared_ptr<const PiecewiseBernstein> leaf) {
  leaf->validate();
  for (int axis : leaf->axes)
    if (axis < 0 || axis >= dim)
      throw std::invalid_argument(leaf->name + ": axis out of range for the problem variables");
  Expression e;
  e.dim_ = dim;
  e.root_ = makeNode(ExprNode::Kind::kPolynomial);
  for (int a = 0; a < leaf->dim(); ++a)
    e.root_->partials.push_back(std::make_shared<const PiecewiseBernstein>(leaf->derivative(a)));
  e.text_ = leaf->name;
  e.root_->polynomial = std::move(leaf);
  e.leaves_ = indexLeaves(*e.root_);
  return e;
}

Expression Expression::join(ExprNode::Kind kind, const char* op, const Expression& a,
                            const Expression* b) {
  if (b && a.dim_ != b->dim_)
    throw std::invalid_argument("Expression: operands in different numbers of variables");
  // Long operand texts are elided: built expressions can be large.
  const auto shown = [](const std::string& t) { return t.size() > 80 ? std::string("...") : t; };
  Expression e;
  e.dim_ = a.dim_;
  e.root_ = makeNode(kind);
  e.root_->left = clone(*a.root_);
  if (b) {
    e.root_->right = clone(*b->root_);
    e.text_ = "(" + shown(a.text_) + op + shown(b->text_) + ")";
  } else {
    e.text_ = std::string(op) + "(" + shown(a.text_) + ")";
  }
  e.slots_ = height(*e.root_) + 1;
  e.leaves_ = indexLeaves(*e.root_);
  return e;
}

Expression operator+(const Expression& a, const Expression& b) {
  return Expression::join(ExprNode::Kind::kAdd, " + ", a, &b);
}
Expression operator-(const Expression& a, const Expression& b) {
  return Expression::join(ExprNode::Kind::kSub, " - ", a, &b);
}
Expression operator*(const Expression& a, const Expression& b) {
  return Expression::join(ExprNode::Kind::kMul, " * ", a, &b);
}
Expression operator-(const Expression& a) {
  return Expression::join(ExprNode::Kind::kNeg, "-", a, nullptr);
}

std::vector<double> Expression::breaks(int j) const {
  std::vector<double> out;
  std::vector<const ExprNode*> stack{root_.get()};
  while (!stack.empty()) {
    const ExprNode* n = stack.back();
    stack.pop_back();
    if (n->left) stack.push_back(n->left.get());
    if (n->right) stack.push_back(n->right.get());
    if (n->kind != ExprNode::Kind::kPolynomial) continue;
    const auto& leaf = *n->polynomial;
    for (int a = 0; a < leaf.dim(); ++a)
      if (leaf.axes[a] == j) out.insert(out.end(), leaf.breaks[a].begin(), leaf.breaks[a].end());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<int> Expression::degrees() const {
  std::vector<int> out(dim_);
  degreesOf(*root_, out);
  return out;
}

template <class S>
S Expression::evaluate(std::span<const S> x) const {
  checkSize(*this, x, "point");
  if (leaves_ == 0) return evalValue<S>(*root_, x);
  if constexpr (std::is_same_v<S, double>) {
    thread_local LeafMemo<double> memo;
    memo.reset(leaves_, 1);
    return evalValue<S>(*root_, x, &memo);
  } else {
    LeafMemo<S> memo;
    memo.reset(leaves_, 1);
    return evalValue<S>(*root_, x, &memo);
  }
}

template <class S>
S Expression::evaluate(std::span<const S> x, std::span<S> gradient) const {
  checkSize(*this, x, "point");
  checkSize(*this, gradient, "gradient");
  if constexpr (std::is_same_v<S, double>) {
    thread_local std::vector<double> work;
    thread_local LeafMemo<double> memo;
    return GradientEvaluator<S>(slots_, leaves_, x, work, memo).run(*root_, gradient);
  } else {
    std::vector<S> work;
    LeafMemo<S> memo;
    return GradientEvaluator<S>(slots_, leaves_, x, work, memo).run(*root_, gradient);
  }
}

template <class S>
Interval<S> Expression::evaluate(std::span<const Interval<S>> x) const {
  checkSize(*this, x, "box");
  LeafMemo<Interval<S>> memo;
  memo.reset(leaves_, 1);
  return evalValue<Interval<S>>(*root_, x, &memo);
}

template <class S>
Interval<S> Expression::evaluate(std::span<const Interval<S>> x,
                                 std::span<Interval<S>> gradient) const {
  checkSize(*this, x, "box");
  checkSize(*this, gradient, "gradient");
  std::vector<Interval<S>> work;
  LeafMemo<Interval<S>> memo;
  return GradientEvaluator<Interval<S>>(slots_, leaves_, x, work, memo).run(*root_, gradient);
}

template <class S>
Bernstein<S> Expression::toBernstein(const Box<S>& domain) const {
  if (domain.dim() != dim_)
    throw std::invalid_argument("Expression::toBernstein: the domain has dimension " +
                                std::to_string(domain.dim()) + ", expected " +
                                std::to_string(dim_));
  return evalBernstein(*root_, domain);
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
