// The expression parser (recursive descent) and its compilation to a Tape. The syntax tree
// (ExprNode) is private to this file.
//
// Exponent rule: the right operand of `^` is a non-negative integer literal written with digits
// only ("2", not "2.0" or "2e0"), optionally in parentheses, at most kMaxExponent; `^` is right
// associative and the exponent itself may be a power of such literals, folded at parse time
// (`x^2^3` = `x^(2^3)` = `x^8`). `^` binds tighter than unary minus: `-x^2` = `-(x^2)`.
// A divisor must be a constant subexpression (no variable) that is certified nonzero by
// interval arithmetic in double at parse time. Unary plus is accepted.
#include "framework/problem/parser.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "framework/util/errors.hpp"

namespace ndc {

namespace {

/// A node of the syntax tree.
struct ExprNode {
  enum class Kind { kNumber, kVariable, kAdd, kSub, kMul, kDiv, kPow, kNeg };
  Kind kind;
  std::string literal;                    ///< kNumber: the decimal text
  int variable = -1;                      ///< kVariable: index into the variable list
  int exponent = 0;                       ///< kPow: the non-negative integer exponent
  std::unique_ptr<ExprNode> left, right;  ///< operands (kNeg and kPow use left only)
};

/// Largest exponent the parser accepts (a Bernstein degree beyond it is not a sane input).
constexpr long kMaxExponent = 10000;
/// Parentheses, signs and parenthesised exponents nest at most this deep: the parser and the
/// compilation recurse, so the tree's height must stay far below what the stack holds.
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

bool isIdentifierStart(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}
bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isIdentifierChar(char c) { return isIdentifierStart(c) || isDigit(c); }

/// Appends the postfix program of `node` to `tape`.
void compile(const ExprNode& node, Tape& tape) {
  using K = ExprNode::Kind;
  using Op = TapeOp::Kind;
  switch (node.kind) {
    case K::kNumber:
      tape.pushConstant(TapeConstant::fromLiteral(node.literal));
      return;
    case K::kVariable:
      tape.push({Op::kVariable, node.variable});
      return;
    case K::kPow:
      compile(*node.left, tape);
      tape.push({Op::kPow, node.exponent});
      return;
    case K::kNeg:
      compile(*node.left, tape);
      tape.push({Op::kNeg, 0});
      return;
    default:
      break;
  }
  compile(*node.left, tape);
  const auto rightBegin = static_cast<int>(tape.ops().size());
  compile(*node.right, tape);
  const Op op = node.kind == K::kAdd   ? Op::kAdd
                : node.kind == K::kSub ? Op::kSub
                : node.kind == K::kMul ? Op::kMul
                                       : Op::kDiv;
  tape.push({op, op == Op::kDiv ? rightBegin : 0});
}

// ---- Parser ------------------------------------------------------------------------------------

// Grammar (whitespace between tokens is ignored):
//   expression := term (('+' | '-') term)*
//   term       := unary (('*' | '/') unary)*
//   unary      := ('-' | '+') unary | power
//   power      := primary ('^' exponent)?
//   exponent   := atom ('^' atom)*       (right associative, folded)
//   atom       := INTEGER | '(' exponent ')'
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
    Tape program(0);
    compile(*node, program);
    const Interval<double> value = evaluateTape<Interval<double>>(program, {});
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
      one->literal = "1";
      return one;
    }
    auto node = makeNode(ExprNode::Kind::kPow);
    node->left = std::move(base);
    node->exponent = p;
    return node;
  }

  /// exponent := atom ('^' atom)*, folded from the right (a^b^c = a^(b^c)) without recursion:
  /// a chain of 50,000 carets is input, not a reason to overflow the stack.
  long exponent() {
    const std::size_t start = pos_;
    std::vector<long> chain{exponentAtom()};
    for (;;) {
      skipSpace();
      if (peek() != '^') break;
      ++pos_;
      chain.push_back(exponentAtom());
    }
    long value = chain.back();
    for (std::size_t i = chain.size() - 1; i-- > 0;) value = foldPower(chain[i], value, start);
    return value;
  }

  /// base^power for the exponent's fold, failing past kMaxExponent.
  long foldPower(long base, long power, std::size_t start) const {
    long folded = 1;
    for (long k = 0; k < power; ++k) {
      folded *= base;
      if (folded > kMaxExponent)
        fail(start, "exponent too large (at most " + std::to_string(kMaxExponent) + ")");
      if (folded == 0 || folded == 1) break;
    }
    return folded;
  }

  /// INTEGER | '(' exponent ')'
  long exponentAtom() {
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
    node->literal = std::move(token);
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

}  // namespace

Tape parseExpression(std::string_view text, std::span<const std::string> variables) {
  Tape tape(static_cast<int>(variables.size()));
  compile(*Parser(text, variables).parse(), tape);
  return tape;
}

}  // namespace ndc
