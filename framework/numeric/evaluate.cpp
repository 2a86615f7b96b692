// The evaluators over a Tape: value, value and gradient (forward mode), each in plain and
// interval arithmetic, and the Bernstein form. Instantiated for double and Mpfr.
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "framework/numeric/form_rounding.hpp"
#include "framework/numeric/tape.hpp"

namespace ndc {

namespace {

using K = TapeOp::Kind;

// ---- Arithmetic of the evaluators: T is S or Interval<S> ---------------------------------------

template <class T>
struct Arith {
  static T number(const TapeConstant& c) { return c.as<T>(); }
  static T constant(int k) { return T(k); }
  static T power(const T& a, int n) {
    // Binary powering: exact for small integers, a few roundings otherwise.
    T result = 1, base = a;
    for (; n > 0; n >>= 1) {
      if (n & 1) result *= base;
      if (n > 1) base *= base;
    }
    return result;
  }
  static T divide(const T& a, const T& c) { return a / c; }
};

template <class S>
struct Arith<Interval<S>> {
  using T = Interval<S>;
  static T number(const TapeConstant& c) { return c.enclosure<S>(); }
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

/// Per-evaluation scratch: the stack (stride values per slot) and the values of the distinct
/// leaves (stride per leaf, computed on first use). Reused per thread for double and
/// Interval<double>, so the Newton loop and the interval tests do not allocate once warm.
template <class T>
struct Workspace {
  std::vector<T> stack;
  std::vector<T> leaves;
  std::vector<unsigned char> done;
  void reset(const Tape& tape, std::size_t stride) {
    const auto need = static_cast<std::size_t>(tape.stackDepth()) * stride;
    if (stack.size() < need) stack.resize(need, Arith<T>::constant(0));
    const auto leafCount = tape.leaves().size();
    if (leaves.size() < leafCount * stride)
      leaves.resize(leafCount * stride, Arith<T>::constant(0));
    done.assign(leafCount, 0);
  }
};

template <class T, class F>
decltype(auto) withWorkspace(F&& f) {
  // Per thread for double and Interval<double> (no evaluation re-enters another: leaves and
  // constants are not tapes); Mpfr values carry their precision, so they are made per call.
  if constexpr (std::is_same_v<T, double> || std::is_same_v<T, Interval<double>>) {
    thread_local Workspace<T> work;
    return f(work);
  } else {
    Workspace<T> work;
    return f(work);
  }
}

// ---- Value --------------------------------------------------------------------------------------

/// Runs the instructions [begin, end) (a program leaving one value) on the stack from slot 0.
template <class T>
T runValue(const Tape& tape, std::size_t begin, std::size_t end, std::span<const T> x,
           Workspace<T>& work) {
  const auto ops = tape.ops();
  T* stack = work.stack.data();
  std::size_t top = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const TapeOp& op = ops[i];
    const auto arg = static_cast<std::size_t>(op.arg);
    switch (op.kind) {
      case K::kConstant:
        stack[top++] = Arith<T>::number(tape.constants()[arg]);
        break;
      case K::kVariable:
        stack[top++] = x[arg];
        break;
      case K::kLeaf:
        if (!work.done[arg]) {
          work.leaves[arg] = leafValue<T>(*tape.leaves()[arg].polynomial, x);
          work.done[arg] = 1;
        }
        stack[top++] = work.leaves[arg];
        break;
      case K::kAdd:
        --top;
        stack[top - 1] += stack[top];
        break;
      case K::kSub:
        --top;
        stack[top - 1] -= stack[top];
        break;
      case K::kMul:
        --top;
        stack[top - 1] *= stack[top];
        break;
      case K::kDiv:
        --top;
        stack[top - 1] = Arith<T>::divide(stack[top - 1], stack[top]);
        break;
      case K::kPow:
        stack[top - 1] = Arith<T>::power(stack[top - 1], op.arg);
        break;
      case K::kNeg:
        stack[top - 1] = -stack[top - 1];
        break;
    }
  }
  return stack[0];
}

// ---- Value and gradient (forward mode)
// -----------------------------------------------------------

/// Each stack slot holds dim + 1 values: the value, then the gradient.
template <class T>
class GradientRun {
 public:
  GradientRun(const Tape& tape, std::span<const T> x, Workspace<T>& work)
      : tape_(tape), x_(x), stride_(x.size() + 1), work_(work) {
    work_.reset(tape, stride_);
  }

  T run(std::span<T> gradient) {
    for (const TapeOp& op : tape_.ops()) {
      if (op.kind == K::kConstant || op.kind == K::kVariable || op.kind == K::kLeaf)
        pushOperand(op, slot(top_++));
      else
        apply(op);
    }
    const T* out = slot(0);
    for (std::size_t j = 0; j + 1 < stride_; ++j) gradient[j] = out[j + 1];
    return out[0];
  }

 private:
  T* slot(std::size_t i) { return &work_.stack[i * stride_]; }

  void pushOperand(const TapeOp& op, T* out) {
    const auto arg = static_cast<std::size_t>(op.arg);
    if (op.kind == K::kLeaf) {
      const T* block = leafBlock(arg);
      for (std::size_t k = 0; k < stride_; ++k) out[k] = block[k];
      return;
    }
    out[0] = op.kind == K::kConstant ? Arith<T>::number(tape_.constants()[arg]) : x_[arg];
    for (std::size_t k = 1; k < stride_; ++k) out[k] = Arith<T>::constant(0);
    if (op.kind == K::kVariable) out[arg + 1] = Arith<T>::constant(1);
  }

  /// The leaf's value and its partials along its own axes (zero along the others), computed
  /// once per distinct leaf and evaluation.
  const T* leafBlock(std::size_t i) {
    T* block = &work_.leaves[i * stride_];
    if (work_.done[i]) return block;
    const TapeLeaf& leaf = tape_.leaves()[i];
    block[0] = leafValue<T>(*leaf.polynomial, x_);
    for (std::size_t k = 1; k < stride_; ++k) block[k] = Arith<T>::constant(0);
    const auto& axes = leaf.polynomial->axes;
    for (std::size_t a = 0; a < axes.size(); ++a)
      block[axes[a] + 1] = leafValue<T>(*leaf.partials[a], x_);
    work_.done[i] = 1;
    return block;
  }

  void apply(const TapeOp& op) {
    if (op.kind != K::kPow && op.kind != K::kNeg) --top_;
    T* out = slot(top_ - 1);
    const T* r = out + stride_;  // the right operand of a binary instruction
    switch (op.kind) {
      case K::kAdd:
        for (std::size_t k = 0; k < stride_; ++k) out[k] += r[k];
        break;
      case K::kSub:
        for (std::size_t k = 0; k < stride_; ++k) out[k] -= r[k];
        break;
      case K::kMul:
        // Product rule: (ab)' = a'b + ab'.
        for (std::size_t k = 1; k < stride_; ++k) out[k] = out[k] * r[0] + out[0] * r[k];
        out[0] *= r[0];
        break;
      case K::kDiv:
        // The divisor is a constant: (a/c)' = a'/c.
        for (std::size_t k = 0; k < stride_; ++k) out[k] = Arith<T>::divide(out[k], r[0]);
        break;
      case K::kPow:
        power(out, op.arg);
        break;
      case K::kNeg:
        for (std::size_t k = 0; k < stride_; ++k) out[k] = -out[k];
        break;
      default:
        break;
    }
  }

  /// (a^p)' = p a^(p-1) a'; the value is a^p itself (tight for intervals).
  void power(T* out, int p) {
    if (p == 0) {
      out[0] = Arith<T>::constant(1);
      for (std::size_t k = 1; k < stride_; ++k) out[k] = Arith<T>::constant(0);
      return;
    }
    T factor = Arith<T>::constant(p) * Arith<T>::power(out[0], p - 1);
    out[0] = Arith<T>::power(out[0], p);
    for (std::size_t k = 1; k < stride_; ++k) out[k] = factor * out[k];
  }

  const Tape& tape_;
  std::span<const T> x_;
  std::size_t stride_;
  Workspace<T>& work_;
  std::size_t top_ = 0;
};

// ---- Bernstein form -----------------------------------------------------------------------------

template <class S>
Bernstein<S> leafOnDomain(const PiecewiseBernstein& leaf, const Box<S>& domain) {
  // The piece holding the domain's projection, restricted to it, embedded in n variables.
  Box<S> local;
  for (int axis : leaf.axes) {
    local.lo.push_back(domain.lo[axis]);
    local.hi.push_back(domain.hi[axis]);
  }
  return leaf.onBox<S>(local).embed(domain, leaf.axes);
}

}  // namespace

template <class T>
T evaluateTape(const Tape& tape, std::span<const T> x) {
  return withWorkspace<T>([&](Workspace<T>& work) {
    work.reset(tape, 1);
    return runValue<T>(tape, 0, tape.ops().size(), x, work);
  });
}

template <class T>
T evaluateTape(const Tape& tape, std::span<const T> x, std::span<T> gradient) {
  return withWorkspace<T>(
      [&](Workspace<T>& work) { return GradientRun<T>(tape, x, work).run(gradient); });
}

template <class S>
S evaluateConstant(const Tape& tape, std::size_t begin, std::size_t end) {
  Workspace<S> work;
  work.reset(tape, 1);
  return runValue<S>(tape, begin, end, {}, work);
}

namespace {

/// bernsteinOfTape's hooks where no rounding bound is kept.
template <class S>
struct Untracked {
  void constant(const TapeConstant&) {}
  void variable() {}
  void unbounded() {}
  void sum(const Bernstein<S>&, const Bernstein<S>&) {}
  void product(const Bernstein<S>&, const Bernstein<S>&) {}
  void divide() {}
  Bernstein<S> power(const Bernstein<S>& a, int exponent) { return pow(a, exponent); }
};

/// The Bernstein form of the program, with `track` told of every operation before it is done
/// (Untracked, or FormRounding for double).
template <class S, class Track>
Bernstein<S> runBernstein(const Tape& tape, const Box<S>& domain, Track& track) {
  std::vector<Bernstein<S>> stack;
  std::vector<std::optional<Bernstein<S>>> leaves(tape.leaves().size());
  const auto ops = tape.ops();
  for (std::size_t i = 0; i < ops.size(); ++i) {
    const TapeOp& op = ops[i];
    const auto arg = static_cast<std::size_t>(op.arg);
    Bernstein<S> right;
    if (op.kind >= K::kAdd && op.kind <= K::kDiv) {
      right = std::move(stack.back());
      stack.pop_back();
    }
    switch (op.kind) {
      case K::kConstant:
        track.constant(tape.constants()[arg]);
        stack.push_back(Bernstein<S>::constant(domain, tape.constants()[arg].as<S>()));
        break;
      case K::kVariable:
        track.variable();
        stack.push_back(Bernstein<S>::variable(domain, op.arg));
        break;
      case K::kLeaf:
        track.unbounded();
        if (!leaves[arg]) leaves[arg] = leafOnDomain(*tape.leaves()[arg].polynomial, domain);
        stack.push_back(*leaves[arg]);
        break;
      case K::kAdd:
        track.sum(stack.back(), right);
        stack.back() = stack.back() + right;
        break;
      case K::kSub:
        track.sum(stack.back(), right);
        stack.back() = stack.back() - right;
        break;
      case K::kMul:
        track.product(stack.back(), right);
        stack.back() = stack.back() * right;
        break;
      case K::kDiv: {
        // The divisor is a constant: scale by its reciprocal, computed in S.
        track.divide();
        stack.back() = stack.back() * (S(1) / evaluateConstant<S>(tape, arg, i));
        break;
      }
      case K::kPow:
        stack.back() = track.power(stack.back(), op.arg);
        break;
      case K::kNeg:
        stack.back() = -stack.back();
        break;
    }
  }
  return std::move(stack.back());
}

}  // namespace

template <class S>
Bernstein<S> bernsteinOfTape(const Tape& tape, const Box<S>& domain) {
  Untracked<S> track;
  return runBernstein<S>(tape, domain, track);
}

Bernstein<double> bernsteinOfTape(const Tape& tape, const Box<double>& domain,
                                  double& roundingError) {
  FormRounding track;
  Bernstein<double> form = runBernstein<double>(tape, domain, track);
  roundingError = track.top();
  return form;
}

// ---- Explicit instantiation --------------------------------------------------------------------

#define NDC_INSTANTIATE_TAPE(S)                                                              \
  template S evaluateTape<S>(const Tape&, std::span<const S>);                               \
  template S evaluateTape<S>(const Tape&, std::span<const S>, std::span<S>);                 \
  template Interval<S> evaluateTape<Interval<S>>(const Tape&, std::span<const Interval<S>>); \
  template Interval<S> evaluateTape<Interval<S>>(const Tape&, std::span<const Interval<S>>,  \
                                                 std::span<Interval<S>>);                    \
  template S evaluateConstant<S>(const Tape&, std::size_t, std::size_t);                     \
  template Bernstein<S> bernsteinOfTape<S>(const Tape&, const Box<S>&);

NDC_INSTANTIATE_TAPE(double)
NDC_INSTANTIATE_TAPE(Mpfr)
#undef NDC_INSTANTIATE_TAPE

}  // namespace ndc
