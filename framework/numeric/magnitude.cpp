// The magnitude bound of a Tape (see magnitude.hpp).
#include "framework/numeric/magnitude.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ndc {

template <class S>
MagnitudeBound<S>::MagnitudeBound(std::shared_ptr<const Tape> tape) : tape_(std::move(tape)) {
  using std::abs;
  using K = TapeOp::Kind;
  const auto ops = tape_->ops();
  operand_.assign(ops.size(), S(0));
  // Per stack entry: the total degree and the operations that round. A divisor's own
  // operations are not counted: it is rounded once, as a constant.
  std::vector<std::pair<int, int>> stack;
  for (std::size_t i = 0; i < ops.size(); ++i) {
    const TapeOp& op = ops[i];
    const auto arg = static_cast<std::size_t>(op.arg);
    std::pair<int, int> right{0, 0};
    if (op.kind >= K::kAdd && op.kind <= K::kDiv) {
      right = stack.back();
      stack.pop_back();
    }
    switch (op.kind) {
      case K::kConstant:
        // A decimal literal is rounded once when it is read.
        operand_[i] = abs(tape_->constants()[arg].as<S>());
        stack.emplace_back(0, 1);
        break;
      case K::kVariable:
        stack.emplace_back(1, 0);
        break;
      case K::kLeaf: {
        // |leaf| <= its largest |coefficient| near its pieces; de Casteljau rounds once per step.
        const PiecewiseBernstein& leaf = *tape_->leaves()[arg].polynomial;
        int steps = 0;
        for (int a = 0; a < leaf.dim(); ++a) steps += leaf.degree(a) * (leaf.degree(a) + 1);
        operand_[i] = S(leaf.maxAbsCoefficient());
        stack.emplace_back(0, steps);
        break;
      }
      case K::kAdd:
      case K::kSub:
        stack.back() = {std::max(stack.back().first, right.first),
                        stack.back().second + right.second + 1};
        break;
      case K::kMul:
        stack.back() = {stack.back().first + right.first, stack.back().second + right.second + 1};
        break;
      case K::kDiv:
        // Divide by the divisor's actual magnitude, not its bound.
        operand_[i] = abs(evaluateConstant<S>(*tape_, arg, i));
        stack.back().second += 2;
        break;
      case K::kPow:
        // A naive product of p factors: p - 1 roundings at most.
        stack.back() = {stack.back().first * op.arg, stack.back().second + std::max(op.arg - 1, 0)};
        break;
      case K::kNeg:  // exact, and magnitudes do not change
        break;
    }
  }
  if (!stack.empty()) count_ = stack.back().first + stack.back().second;
  depth_ = static_cast<std::size_t>(std::max(tape_->stackDepth(), 1));
}

template <class S>
S MagnitudeBound<S>::operator()(std::span<const S> absX, std::vector<S>& stack) const {
  using K = TapeOp::Kind;
  const auto ops = tape_->ops();
  // A stack of the program's depth, sized once (Newton calls this every iteration).
  if (stack.size() < depth_) stack.resize(depth_);
  S* top = stack.data() - 1;
  for (std::size_t i = 0; i < ops.size(); ++i) {
    const TapeOp& op = ops[i];
    switch (op.kind) {
      case K::kConstant:
      case K::kLeaf:
        *++top = operand_[i];
        break;
      case K::kVariable:
        *++top = absX[static_cast<std::size_t>(op.arg)];
        break;
      case K::kNeg:
        break;
      case K::kPow: {
        S base = *top, result = 1;
        for (int e = 0; e < op.arg; ++e) result *= base;
        *top = result;
        break;
      }
      case K::kMul:
        // Binary: |ab| = |a||b|, |a +- b| <= |a| + |b|, |a / c| with c the divisor.
        top[-1] *= *top;
        --top;
        break;
      case K::kDiv:
        top[-1] /= operand_[i];
        --top;
        break;
      default:
        top[-1] += *top;
        --top;
    }
  }
  return *top;
}

template class MagnitudeBound<double>;
template class MagnitudeBound<Mpfr>;

}  // namespace ndc
