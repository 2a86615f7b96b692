// BernsteinBounding (strategies/bounding/bernstein.hpp).
#include "strategies/bounding/bernstein.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>

#include "strategies/bounding/bounding_detail.hpp"

namespace ndc {

using bounding_detail::checkDomain;
using bounding_detail::halveBox;

template <class S>
ModelSpec BernsteinBounding<S>::spec() {
  return {"bernstein",
          "The convex hull of the Bernstein coefficients (Sec. 4): a box is discarded when one "
          "equation's coefficients all have one sign.",
          {}};
}

template <class S>
BernsteinBounding<S>::BernsteinBounding(const Problem& problem, const Box<S>& domain)
    : domain_(domain) {
  checkDomain(problem, domain);
  // Sec. 4: the constraints in Bernstein form on the domain, built once; every box's patches
  // are derived from these by halving.
  patches_.reserve(problem.equations.size());
  for (std::size_t i = 0; i < problem.equations.size(); ++i) {
    // The loader lets a quadratic equation exceed the dense forms' cap (densityFree).
    const double coefficients = denseCoefficients(problem.equations[i]);
    if (coefficients > kMaxCoefficients) {
      std::ostringstream message;
      message << "bounding 'bernstein' needs the dense Bernstein form of equation " << i + 1 << " ("
              << coefficients << " coefficients; at most " << kMaxCoefficients
              << " are supported): use the default bounding 'linearized', which encloses it "
                 "by its quadratic form";
      throw InputError(message.str());
    }
    patches_.push_back(problem.equations[i].toBernstein<S>(domain));
  }
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
  lower.emptyHalves = upper.emptyHalves = 0;
  lower.emptyByParent = upper.emptyByParent = false;
  // Only the first use of a per-level state sizes it; afterwards Bernstein::halve overwrites
  // the children's coefficients in place.
  const std::size_t m = parent.patches.size();
  if (lower.patches.size() != m) lower.patches.resize(m);
  if (upper.patches.size() != m) upper.patches.resize(m);
  for (std::size_t i = 0; i < m; ++i)
    parent.patches[i].halve(axis, lower.patches[i], upper.patches[i]);
}

//! [bernstein-test]
template <class S>
bool BernsteinBounding<S>::mayContainZero(const State& state) const {
  // Alg. 1 step (1): discard the box if a Bernstein hull excludes 0.
  for (const Bernstein<S>& patch : state.patches)
    if (patch.excludesZero()) return false;
  return true;
}
//! [bernstein-test]

template class BernsteinBounding<double>;
template class BernsteinBounding<Mpfr>;

}  // namespace ndc
