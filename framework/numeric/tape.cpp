// The compiled expression: building the postfix program, and the analyses that need no scalar
// (degrees, total degree, breaks).
#include "framework/numeric/tape.hpp"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <stdexcept>
#include <utility>

namespace ndc {

namespace {

int saturatingAdd(int a, int b) { return a > INT_MAX - b ? INT_MAX : a + b; }
int saturatingMul(int a, int b) { return a != 0 && b > INT_MAX / a ? INT_MAX : a * b; }

/// Operands an instruction pops (0, 1 or 2); it then pushes one value.
int pops(TapeOp::Kind kind) {
  using K = TapeOp::Kind;
  switch (kind) {
    case K::kConstant:
    case K::kVariable:
    case K::kLeaf:
      return 0;
    case K::kPow:
    case K::kNeg:
      return 1;
    default:
      return 2;
  }
}

}  // namespace

// ---- Building ----------------------------------------------------------------------------------

TapeConstant TapeConstant::fromLiteral(std::string literal) {
  const Interval<double> enclosure = Interval<double>::fromString(literal);
  const double value = std::strtod(literal.c_str(), nullptr);
  return {std::move(literal), value, enclosure.lower(), enclosure.upper()};
}

template <>
double TapeConstant::as<double>() const {
  return value;  // rounded to nearest when it was read
}

template <>
Mpfr TapeConstant::as<Mpfr>() const {
  if (literal.empty()) return Mpfr(value);  // an exact double
  Mpfr v;
  mpfr_set_str(v.backend().data(), literal.c_str(), 10, MPFR_RNDN);
  return v;
}

template <>
Interval<double> TapeConstant::enclosure<double>() const {
  return Interval<double>(lower, upper);  // computed when the literal was read
}

template <>
Interval<Mpfr> TapeConstant::enclosure<Mpfr>() const {
  if (literal.empty()) return Interval<Mpfr>(Mpfr(value));
  return Interval<Mpfr>::fromString(literal);
}

std::size_t Tape::push(TapeOp op) {
  const int popped = pops(op.kind);
  if (top_ < popped) throw std::logic_error("Tape: an instruction without its operands");
  top_ += 1 - popped;
  depth_ = std::max(depth_, top_);
  ops_.push_back(op);
  return ops_.size() - 1;
}

void Tape::pushConstant(TapeConstant constant) {
  constants_.push_back(std::move(constant));
  push({TapeOp::Kind::kConstant, static_cast<int>(constants_.size()) - 1});
}

void Tape::pushLeaf(const TapeLeaf& leaf) {
  const auto it = std::find_if(leaves_.begin(), leaves_.end(),
                               [&](const TapeLeaf& l) { return l.polynomial == leaf.polynomial; });
  const auto index = static_cast<int>(it - leaves_.begin());
  if (it == leaves_.end()) leaves_.push_back(leaf);
  push({TapeOp::Kind::kLeaf, index});
}

void Tape::append(const Tape& other) {
  if (other.dim_ != dim_)
    throw std::invalid_argument("Expression: operands in different numbers of variables");
  // The other program runs on top of the current stack (push keeps the depth).
  const auto offset = static_cast<int>(ops_.size());
  for (const TapeOp& op : other.ops_) {
    switch (op.kind) {
      case TapeOp::Kind::kConstant:
        pushConstant(other.constants_[static_cast<std::size_t>(op.arg)]);
        break;
      case TapeOp::Kind::kLeaf:
        pushLeaf(other.leaves_[static_cast<std::size_t>(op.arg)]);
        break;
      case TapeOp::Kind::kDiv:
        push({op.kind, op.arg + offset});
        break;
      default:
        push(op);
    }
  }
}

// ---- Analyses ----------------------------------------------------------------------------------

std::vector<int> Tape::degrees() const {
  using K = TapeOp::Kind;
  const auto n = static_cast<std::size_t>(dim_);
  std::vector<std::vector<int>> stack;
  for (const TapeOp& op : ops_) {
    if (pops(op.kind) == 0) stack.emplace_back(n, 0);
    std::vector<int>& out = stack[stack.size() - 1 - (pops(op.kind) == 2 ? 1 : 0)];
    switch (op.kind) {
      case K::kVariable:
        out[static_cast<std::size_t>(op.arg)] = 1;
        break;
      case K::kLeaf: {
        const PiecewiseBernstein& leaf = *leaves_[static_cast<std::size_t>(op.arg)].polynomial;
        for (int a = 0; a < leaf.dim(); ++a)
          out[static_cast<std::size_t>(leaf.axes[a])] = leaf.degree(a);
        break;
      }
      case K::kAdd:
      case K::kSub:
      case K::kMul:
        for (std::size_t j = 0; j < n; ++j)
          out[j] = op.kind == K::kMul ? saturatingAdd(out[j], stack.back()[j])
                                      : std::max(out[j], stack.back()[j]);
        break;
      case K::kPow:
        for (int& d : out) d = saturatingMul(d, op.arg);
        break;
      default:  // constants, negation, division by a constant
        break;
    }
    if (pops(op.kind) == 2) stack.pop_back();
  }
  return stack.empty() ? std::vector<int>(n, 0) : stack.back();
}

int Tape::totalDegree(int cap) const {
  using K = TapeOp::Kind;
  std::vector<int> stack;
  for (const TapeOp& op : ops_) {
    int right = 0;
    if (pops(op.kind) == 2) {
      right = stack.back();
      stack.pop_back();
    }
    switch (op.kind) {
      case K::kConstant:
        stack.push_back(0);
        break;
      case K::kVariable:
        stack.push_back(std::min(1, cap));
        break;
      case K::kLeaf: {
        const PiecewiseBernstein& leaf = *leaves_[static_cast<std::size_t>(op.arg)].polynomial;
        int d = 0;
        for (int a = 0; a < leaf.dim(); ++a) d = std::min(cap, saturatingAdd(d, leaf.degree(a)));
        stack.push_back(d);
        break;
      }
      case K::kAdd:
      case K::kSub:
        stack.back() = std::max(stack.back(), right);
        break;
      case K::kMul:
        stack.back() = std::min(cap, saturatingAdd(stack.back(), right));
        break;
      case K::kPow:
        stack.back() = std::min(cap, saturatingMul(stack.back(), op.arg));
        break;
      case K::kDiv:  // by a constant
      case K::kNeg:
        break;
    }
  }
  return stack.empty() ? 0 : stack.back();
}

std::vector<double> Tape::breaks(int j) const {
  std::vector<double> out;
  for (const TapeLeaf& l : leaves_) {
    const PiecewiseBernstein& leaf = *l.polynomial;
    for (int a = 0; a < leaf.dim(); ++a)
      if (leaf.axes[a] == j) out.insert(out.end(), leaf.breaks[a].begin(), leaf.breaks[a].end());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace ndc
