#include "strategies/bounding/bounding.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace ndc {

namespace {

// Both children of a box at the midpoint of `axis`. The vector assignments reuse the
// children's storage, and both children get the same midpoint value, so siblings share their
// face exactly (no gap where a zero could hide).
template <class S>
void halveBox(const Box<S>& parent, int axis, Box<S>& lower, Box<S>& upper) {
  lower.lo = parent.lo;
  lower.hi = parent.hi;
  upper.lo = parent.lo;
  upper.hi = parent.hi;
  lower.hi[axis] = (parent.lo[axis] + parent.hi[axis]) / 2;
  upper.lo[axis] = lower.hi[axis];
}

template <class S>
void checkDomain(const Problem& problem, const Box<S>& domain) {
  if (domain.dim() != problem.n() || static_cast<int>(domain.hi.size()) != problem.n())
    throw std::invalid_argument("bounding: the domain has " + std::to_string(domain.dim()) +
                                " axes, the problem " + std::to_string(problem.n()) + " variables");
}

}  // namespace

// --- BernsteinBounding ---------------------------------------------------------------------------

template <class S>
BernsteinBounding<S>::BernsteinBounding(const Problem& problem, const Box<S>& domain)
    : domain_(domain) {
  checkDomain(problem, domain);
  // Sec. 4: the constraints in Bernstein form on the domain, built once; every box's patches
  // are derived from these by halving.
  patches_.reserve(problem.equations.size());
  for (const Expression& e : problem.equations) patches_.push_back(e.toBernstein<S>(domain));
  // Test the smallest patches first: they are the cheapest to scan and, for a typical system
  // (a curved hypersurface cut by hyperplanes), the linear ones exclude most boxes.
  std::stable_sort(
      patches_.begin(), patches_.end(),
      [](const Bernstein<S>& a, const Bernstein<S>& b) { return a.size() < b.size(); });
}

template <class S>
void BernsteinBounding<S>::root(State& state) const {
  state.box = domain_;
  state.patches = patches_;
}

template <class S>
void BernsteinBounding<S>::halve(const State& parent, int axis, State& lower, State& upper) const {
  halveBox(parent.box, axis, lower.box, upper.box);
  // Only the first use of a per-level state sizes it; afterwards Bernstein::halve overwrites
  // the children's coefficients in place.
  const std::size_t m = parent.patches.size();
  if (lower.patches.size() != m) lower.patches.resize(m);
  if (upper.patches.size() != m) upper.patches.resize(m);
  for (std::size_t i = 0; i < m; ++i)
    parent.patches[i].halve(axis, lower.patches[i], upper.patches[i]);
}

template <class S>
bool BernsteinBounding<S>::mayContainZero(const State& state) const {
  // Alg. 1 step (1): discard the box if a Bernstein hull excludes 0.
  for (const Bernstein<S>& patch : state.patches)
    if (patch.excludesZero()) return false;
  return true;
}

// --- IntervalBounding ----------------------------------------------------------------------------

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

// --- Factory -------------------------------------------------------------------------------------

template <class S>
Bounding<S> createBounding(std::string_view name, const Problem& problem, const Box<S>& domain) {
  if (name == kBoundingNames[0]) return Bounding<S>(std::in_place_index<0>, problem, domain);
  if (name == kBoundingNames[1]) return Bounding<S>(std::in_place_index<1>, problem, domain);
  throw InputError("unknown bounding '" + std::string(name) + "' (expected bernstein or interval)");
}

template class BernsteinBounding<double>;
template class BernsteinBounding<Mpfr>;
template class IntervalBounding<double>;
template class IntervalBounding<Mpfr>;
template Bounding<double> createBounding<double>(std::string_view, const Problem&,
                                                 const Box<double>&);
template Bounding<Mpfr> createBounding<Mpfr>(std::string_view, const Problem&, const Box<Mpfr>&);

}  // namespace ndc
