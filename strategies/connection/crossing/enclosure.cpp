#include "strategies/connection/crossing/enclosure.hpp"

#include <cmath>
#include <limits>
#include <memory>

namespace ndc::crossing_detail {

template <class S>
std::vector<MidRadEvaluator<S>>& threadEvaluators(const System<S>& system) {
  thread_local std::vector<std::shared_ptr<const Tape>> tapes;
  thread_local unsigned bits = 0;
  thread_local std::vector<MidRadEvaluator<S>> evaluators;
  thread_local std::vector<S> origin;
  const auto& equations = system.equations();
  bool same = tapes.size() == equations.size() && bits == ScalarTraits<S>::precisionBits() &&
              origin == system.origin();
  for (std::size_t i = 0; same && i < equations.size(); ++i)
    same = tapes[i].get() == equations[i].sharedTape().get();
  if (!same) {
    tapes.clear();
    evaluators.clear();
    origin = system.origin();
    for (const Expression& e : equations) {
      tapes.push_back(e.sharedTape());
      evaluators.emplace_back(e.sharedTape(), std::span<const S>(origin));
    }
    bits = ScalarTraits<S>::precisionBits();
  }
  return evaluators;
}

template <class S>
Interval<S> enclosingInterval(const S& mid, const S& rad) {
  using std::abs;
  const S eps = 2 * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  const S lo = mid - rad, hi = mid + rad;
  return Interval<S>(lo - (abs(lo) * eps + tiny), hi + (abs(hi) * eps + tiny));
}

template <class S>
bool encloseSystem(std::vector<MidRadEvaluator<S>>& evaluators, std::span<const S> centre,
                   std::span<const S> radius, std::span<const S> level,
                   std::span<const int> columns, std::vector<Interval<S>>& jacobian,
                   std::vector<Interval<S>>& fy, bool& excluded, bool stopWhenExcluded) {
  using I = Interval<S>;
  using std::abs;
  const std::size_t m = evaluators.size(), width = columns.size();
  const S up = S(1) + S(8 * (centre.size() + m + 8)) * ScalarTraits<S>::epsilon();
  jacobian.resize(m * width);
  fy.resize(m);
  excluded = false;
  for (std::size_t i = 0; i < m; ++i) {
    MidRadEvaluator<S>& e = evaluators[i];
    const I c(level[i]);
    // Over the box with the gradient: the value and J(X); and the value at the centre.
    if (!e.runWithCentre(centre, radius)) return false;
    const bool natural = !(enclosingInterval(e.mid(0), e.rad(0)) - c).containsZero();
    S spread = 0;  // sum_j mag J_ij(X) radius_j
    for (std::size_t j = 0; j < width; ++j) {
      const int q = columns[j] + 1;
      jacobian[i * width + j] = enclosingInterval(e.mid(q), e.rad(q));
      spread += (abs(e.mid(q)) + e.rad(q)) * radius[columns[j]];
    }
    fy[i] = enclosingInterval(e.centreMid(), e.centreRad()) - c;
    const I meanValue = fy[i] + I(-spread * up, spread * up);
    excluded = excluded || natural || !meanValue.containsZero();
    if (excluded && stopWhenExcluded) return true;
  }
  return true;
}

template std::vector<MidRadEvaluator<double>>& threadEvaluators(const System<double>&);
template std::vector<MidRadEvaluator<Mpfr>>& threadEvaluators(const System<Mpfr>&);
template Interval<double> enclosingInterval(const double&, const double&);
template Interval<Mpfr> enclosingInterval(const Mpfr&, const Mpfr&);
template bool encloseSystem(std::vector<MidRadEvaluator<double>>&, std::span<const double>,
                            std::span<const double>, std::span<const double>, std::span<const int>,
                            std::vector<Interval<double>>&, std::vector<Interval<double>>&, bool&,
                            bool);
template bool encloseSystem(std::vector<MidRadEvaluator<Mpfr>>&, std::span<const Mpfr>,
                            std::span<const Mpfr>, std::span<const Mpfr>, std::span<const int>,
                            std::vector<Interval<Mpfr>>&, std::vector<Interval<Mpfr>>&, bool&,
                            bool);

}  // namespace ndc::crossing_detail
