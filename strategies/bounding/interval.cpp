// IntervalBounding (strategies/bounding/interval.hpp).
#include "strategies/bounding/interval.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>

#include "strategies/bounding/bounding_detail.hpp"

namespace ndc {

using bounding_detail::checkDomain;
using bounding_detail::halveBox;

template <class S>
ModelSpec IntervalBounding<S>::spec() {
  return {"interval",
          "Interval arithmetic on the expression, with a mean-value form: cheap per box, looser "
          "than the Bernstein hull.",
          {}};
}

template <class S>
IntervalBounding<S>::IntervalBounding(const Problem& problem, const Box<S>& domain)
    : domain_(domain), equations_(problem.equations) {
  checkDomain(problem, domain);
  const auto n = static_cast<std::size_t>(problem.n());
  x_.resize(n);
  mid_.resize(n);
  gradient_.resize(n);
}

template <class S>
void IntervalBounding<S>::root(State& state) const {
  state.box = domain_;
}

template <class S>
void IntervalBounding<S>::halve(const State& parent, int axis, State& lower, State& upper) const {
  halveBox(parent.box, axis, lower.box, upper.box);
}

template <class S>
bool IntervalBounding<S>::mayContainZero(const State& state) const {
  const Box<S>& box = state.box;
  const int n = box.dim();
  for (int j = 0; j < n; ++j) {
    x_[j] = Interval<S>(box.lo[j], box.hi[j]);
    mid_[j] = Interval<S>((box.lo[j] + box.hi[j]) / 2);
  }
  const std::span<const Interval<S>> x(x_), mid(mid_);
  // Natural extensions first: one cheap pass per equation, and they exclude most boxes far
  // from M, before any gradient is computed.
  for (const Expression& e : equations_)
    if (!e.evaluate<S>(x).containsZero()) return false;
  // Mean-value forms F(m) + sum_j G_j (X_j - m_j), G the interval gradient over the box. The
  // intersection with the natural extension contains 0 iff both do, so only the mean-value
  // enclosure remains to be tested.
  for (const Expression& e : equations_) {
    e.evaluate<S>(x, std::span<Interval<S>>(gradient_));
    Interval<S> meanValue = e.evaluate<S>(mid);
    for (int j = 0; j < n; ++j) meanValue += gradient_[j] * (x_[j] - mid_[j]);
    if (!meanValue.containsZero()) return false;
  }
  return true;
}

template class IntervalBounding<double>;
template class IntervalBounding<Mpfr>;

}  // namespace ndc
