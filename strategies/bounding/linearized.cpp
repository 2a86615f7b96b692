// LinearizedBounding (strategies/bounding/linearized.hpp).
#include "strategies/bounding/linearized.hpp"

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
ModelSpec LinearizedBounding<S>::spec() {
  return {"linearized",
          "The Bernstein hull (the mean-value form for a quadratic whose dense form is large), "
          "then a linearization of all equations together that discards boxes no single "
          "equation can (docs/subdivision.md).",
          {}};
}

template <class S>
bool LinearizedBounding<S>::hasPatch(const Expression& equation) {
  // Above total degree 2 the mean-value form loses too much against the hull; at most 2 it
  // is as tight up to O(h^2) (exact for an affine F_i), and cheaper once the dense form is large.
  if (equation.tape().totalDegree(3) > 2) return true;
  // An affine equation's range is exact from its constant gradient (no halving, no scan).
  if (equation.tape().totalDegree(2) <= 1 && equation.tape().leaves().empty()) return false;
  return denseCoefficients(equation) <= kMaxDensePatch;
}

template <class S>
Problem LinearizedBounding<S>::patchedEquations(const Problem& problem) {
  Problem patched = problem;
  patched.equations.clear();
  for (const Expression& e : problem.equations)
    if (hasPatch(e)) patched.equations.push_back(e);
  return patched;
}

template <class S>
LinearizedBounding<S>::LinearizedBounding(const Problem& problem, const Box<S>& domain)
    : bernstein_(patchedEquations(problem), domain),
      n_(problem.n()),
      m_(static_cast<int>(problem.equations.size())),
      newtonSystem_(problem) {
  const auto n = static_cast<std::size_t>(n_), m = static_cast<std::size_t>(m_);
  // Enabled when the equations are coupled: for equations in disjoint variables a box holds a
  // common zero iff each F_i vanishes on its own factor of the box, which the per-equation
  // hulls already test. More equations than variables: J_c^T has no full column rank.
  std::vector<int> users(n, 0);  // equations using each variable
  for (const Expression& e : problem.equations) {
    const std::vector<int> degrees = e.degrees();
    for (std::size_t j = 0; j < n; ++j) users[j] += degrees[j] > 0;
  }
  enabled_ =
      m_ >= 2 && m_ <= n_ && std::any_of(users.begin(), users.end(), [](int c) { return c >= 2; });
  // 8 (n + m + 8) eps >= 2 gamma_p for every dot product length p used below (eps = 2u).
  u_ = ScalarTraits<S>::epsilon();
  tol_ = S(8 * (n_ + m_ + 8)) * u_;
  c_.resize(n);
  for (int j = 0; j < n_; ++j) c_[j] = (domain.lo[j] + domain.hi[j]) / 2;
  for (const Expression& e : problem.equations)
    evaluators_.emplace_back(e.sharedTape(), std::span<const S>(c_));
  spread_.resize(n);
  zero_.assign(n, S(0));
  system_.resize(n_, m_);
  // Affine equations have a constant gradient: enclose it once, by the outward-rounded interval
  // gradient over the domain (the constant up to the rounding of the literals).
  affine_.assign(m, 0);
  affineMid_.assign(m * n, S(0));
  affineRad_.assign(m * n, S(0));
  std::vector<Interval<S>> box(n), gradient(n);
  for (std::size_t j = 0; j < n; ++j) box[j] = Interval<S>(domain.lo[j], domain.hi[j]);
  evaluated_.assign(m, 0);
  quadratic_.assign(m, 0);
  for (std::size_t i = 0; i < m; ++i) {
    const Tape& tape = problem.equations[i].tape();
    evaluated_[i] = !hasPatch(problem.equations[i]);
    anyEvaluated_ = anyEvaluated_ || evaluated_[i];
    if (tape.totalDegree(2) > 1) {
      quadratic_[i] = evaluators_[i].gradientAffine();
      continue;
    }
    affine_[i] = 1;
    problem.equations[i].evaluate<S>(std::span<const Interval<S>>(box),
                                     std::span<Interval<S>>(gradient));
    for (std::size_t j = 0; j < n; ++j) {
      const S mid = gradient[j].midpoint();
      affineMid_[i * n + j] = mid;
      affineRad_[i * n + j] =
          std::max(gradient[j].upper() - mid, mid - gradient[j].lower()) * (S(1) + tol_);
    }
  }
}

template <class S>
bool LinearizedBounding<S>::mayContainZero(const State& state) const {
  // A half that the parent's test showed empty; else the box's own halves, found below.
  if (state.emptyByParent) return false;
  state.emptyHalves = 0;
  state.hasStart = false;
  // A box that holds a point of M holds a zero: no test could discard it.
  if (state.hasPoint) return true;
  // The per-equation hulls first: cheap, and they discard most boxes far from every F_i = 0.
  if (!bernstein_.mayContainZero(state)) return false;
  if (!anyEvaluated_) {
    if (!enabled_) return true;
    const S hh = centreAndHalfWidths(state.box);
    return !linearise() || !simultaneousExcludes(hh, state);
  }
  // Equations without a patch: their mean-value forms, then the simultaneous test on the same
  // linearisation.
  const S hh = centreAndHalfWidths(state.box);
  // The affine rows first: their exact ranges discard most boxes far from M for a tape run
  // each, before the curved rows' evaluations over the box.
  if (!lineariseRows(true)) return true;
  if (meanValueExcludes(true)) return false;
  if (!lineariseRows(false)) return true;
  if (meanValueExcludes(false)) return false;
  return !enabled_ || !simultaneousExcludes(hh, state);
}

template <class S>
void LinearizedBounding<S>::carryPoint(const State& parent, State& lower, State& upper) const {
  lower.hasPoint = upper.hasPoint = false;
  lower.hasStart = upper.hasStart = false;
  if (!enabled_) return;
  const std::vector<S>* x = &parent.point;
  S error = parent.pointError;
  if (!parent.hasPoint) {
    // Without a point of the linearized zero set in the box (its test ran the multiplier
    // search instead), M rarely meets the box where Newton's iteration from the centre ends.
    if (!parent.hasStart || !newtonPoint(parent, error)) return;
    x = &newtonX_;
  }
  // The zero within `error` of x lies in the closed child when x does by `error` on every
  // axis; a point on the halving plane goes to neither child.
  const auto holds = [&](const Box<S>& box) {
    for (int j = 0; j < n_; ++j) {
      if (!((*x)[j] - error >= box.lo[j] && (*x)[j] + error <= box.hi[j])) return false;
    }
    return true;
  };
  for (State* child : {&lower, &upper}) {
    if (child->emptyByParent || !holds(child->box)) continue;
    child->point.assign(x->begin(), x->end());
    child->pointError = error;
    child->hasPoint = true;
    break;
  }
}

template <class S>
bool LinearizedBounding<S>::newtonPoint(const State& state, S& error) const {
  using std::abs;
  const Box<S>& box = state.box;
  const auto n = static_cast<std::size_t>(n_), m = static_cast<std::size_t>(m_);
  newtonX_.resize(n);
  newtonF_.resize(m);
  newtonJ_.resize(m * n);
  newtonStep_.resize(n);
  S width = 0;
  for (std::size_t j = 0; j < n; ++j) {
    newtonX_[j] = state.hasStart ? state.start[j] : (box.lo[j] + box.hi[j]) / 2;
    width = std::max<S>(width, box.hi[j] - box.lo[j]);
  }
  const S tolerance = S(kPointTolerance) * width;
  for (int step = 0; step < kNewtonSteps; ++step) {
    newtonSystem_.evaluate(std::span<const S>(newtonX_), std::span<S>(newtonF_),
                           std::span<S>(newtonJ_));
    if (!newton_.factor(newtonJ_.data(), m_, n_, S(1e-10))) return false;
    newton_.solve(newtonF_.data(), newtonStep_.data());
    S size = 0, outside = 0;
    for (std::size_t j = 0; j < n; ++j) {
      newtonX_[j] -= newtonStep_[j];
      size = std::max<S>(size, abs(newtonStep_[j]));
      outside = std::max<S>({outside, box.lo[j] - newtonX_[j], newtonX_[j] - box.hi[j]});
    }
    // Outside the box by more than the last step: the rest of a converging iteration moves
    // less than that, so its point would not be the box's.
    if (!isFinite(size) || outside > size) return false;
    if (size <= tolerance) {
      // Quadratic convergence leaves an error far below the last step; four steps and the
      // coordinates' rounding bound it.
      S magnitude = 0;
      for (const S& v : newtonX_) magnitude = std::max<S>(magnitude, abs(v));
      error = 4 * size + 4 * ScalarTraits<S>::epsilon() * magnitude;
      return true;
    }
  }
  return false;
}

template <class S>
bool LinearizedBounding<S>::simultaneousExcludes(const S& hh, const State& state) const {
  if (system_.excludes(hh, kMultiplierIterations)) return true;
  state.emptyHalves = system_.emptyHalves();
  if (const S* d = system_.insideStep()) {
    state.start.resize(std::size_t(n_));
    for (int j = 0; j < n_; ++j) state.start[std::size_t(j)] = c_[std::size_t(j)] + d[j];
    state.hasStart = true;
    return false;
  }
  return contractedExcludes(state.box);
}

template <class S>
bool LinearizedBounding<S>::contractedExcludes(const Box<S>& box) const {
  // Every zero in the box lies in c + [lo, hi] (step 7's bounds); where that box is much
  // smaller, the linearisation over it has a smaller remainder.
  if (!system_.solutionBox(dLo_, dHi_)) return false;
  S before = 0, after = 0;
  for (int j = 0; j < n_; ++j) {
    if (dLo_[j] > dHi_[j]) return true;  // no solution reaches the box along axis j
    const S half = (dHi_[j] - dLo_[j]) / 2;
    before += system_.h[j] * system_.h[j];
    after += half * half;
  }
  if (!(after < S(kContraction) * before)) return false;
  contracted_.lo.resize(std::size_t(n_));
  contracted_.hi.resize(std::size_t(n_));
  using std::abs;
  for (int j = 0; j < n_; ++j) {
    // c + lo rounded down and c + hi up (by the test's margin), within the box.
    const S lo = c_[j] + dLo_[j], hi = c_[j] + dHi_[j];
    contracted_.lo[j] = std::max<S>(box.lo[j], lo - tol_ * (abs(c_[j]) + abs(dLo_[j])));
    contracted_.hi[j] = std::min<S>(box.hi[j], hi + tol_ * (abs(c_[j]) + abs(dHi_[j])));
  }
  const S hh = centreAndHalfWidths(contracted_);
  return linearise() && system_.excludes(hh, kMultiplierIterations);
}

template <class S>
bool LinearizedBounding<S>::meanValueExcludes(const Box<S>& box) const {
  if (!anyEvaluated_) return false;
  centreAndHalfWidths(box);
  return linearise() && (meanValueExcludes(true) || meanValueExcludes(false));
}

template <class S>
bool LinearizedBounding<S>::meanValueExcludes(bool affine) const {
  // F_i(x) = F_i(c) + J_i(xi) (x - c) with J_i(xi) in jac_i +- rad, so F_i(X) lies in
  // mu_i +- (rho_i + sum_j |jac_ij| h_j): the range itself for an affine F_i.
  using std::abs;
  const S up = S(1) + tol_;
  for (int i = 0; i < m_; ++i) {
    if (!evaluated_[i] || bool(affine_[i]) != affine) continue;
    S reach = 0;
    for (int j = 0; j < n_; ++j) reach += abs(system_.jac[rowMajor(i, j, n_)]) * system_.h[j];
    if (abs(system_.mu[i]) > (system_.rho[i] + reach * up) * up) return true;
  }
  return false;
}

template <class S>
bool LinearizedBounding<S>::linearizationExcludes(const Box<S>& box) const {
  if (!enabled_) return false;
  // The steps of the class comment; a step that cannot conclude keeps the box.
  const S hh = centreAndHalfWidths(box);  // 1
  if (!linearise()) return false;         // 2: an enclosure that is not finite
  return system_.excludes(hh, kMultiplierIterations);
}

template <class S>
S LinearizedBounding<S>::centreAndHalfWidths(const Box<S>& box) const {
  // 1. Centre c and half-widths h >= |x - c| on the box (rounded up); returns |h|_2^2.
  const S up = S(1) + tol_;
  S hh = 0;
  for (int j = 0; j < n_; ++j) {
    c_[j] = (box.lo[j] + box.hi[j]) / 2;
    system_.h[j] = std::max(box.hi[j] - c_[j], c_[j] - box.lo[j]) * up;
    hh += system_.h[j] * system_.h[j];
  }
  return hh * up;
}

template <class S>
bool LinearizedBounding<S>::linearise() const {
  return lineariseRows(true) && lineariseRows(false);
}

template <class S>
bool LinearizedBounding<S>::lineariseRows(bool affine) const {
  // 2. The linearized system J_c d = -g, g in G = mu_i +- rho_i: F(c) enclosed at the point,
  // J_c = mid J(X), r_i = sum_j mag(J_ij(X) - J_c,ij) h_j = sum_j rad J_ij(X) h_j (mean value
  // theorem); for a quadratic J_c = mid grad F(c) and the Taylor remainder (class comment).
  using std::abs;
  using std::isfinite;
  const int n = n_;
  const S up = S(1) + tol_;
  for (int i = 0; i < m_; ++i) {
    if (bool(affine_[i]) != affine) continue;
    S* jac = &system_.jac[rowMajor(i, 0, n)];
    const MidRadEvaluator<S>& evaluator = evaluators_[i];
    S r = 0, shift = 0;  // rho's term of the linearisation; mu's shift (one-sided remainder)
    if (affine) {
      for (int j = 0; j < n; ++j) {
        jac[j] = affineMid_[rowMajor(i, j, n)];
        r += affineRad_[rowMajor(i, j, n)] * system_.h[j];
      }
    } else {
      // The gradient's range over X: for a quadratic, sum_j (|H| h)_j h_j bounds what it adds
      // (its centre comes from the run at c below); otherwise a run over X.
      if (quadratic_[i] && evaluator.gradientSpread(system_.h, spread_)) {
        for (int j = 0; j < n; ++j) r += spread_[j] * system_.h[j];
      } else {
        if (!evaluator.run(c_, system_.h, true)) return false;
        for (int j = 0; j < n; ++j) r += evaluator.rad(j + 1) * system_.h[j];
      }
      if (quadratic_[i]) {
        // d^T H d / 2 in [-r/2, r/2] from the gradient's radius over X (one-sided for a
        // semidefinite H), the gradient itself at c.
        r /= 2;
        oneSided(evaluator.curvature(), r, shift);
        if (!evaluator.run(c_, zero_, true)) return false;
        for (int j = 0; j < n; ++j) {
          jac[j] = evaluator.mid(j + 1);
          r += evaluator.rad(j + 1) * system_.h[j];
        }
      } else {
        for (int j = 0; j < n; ++j) jac[j] = evaluator.mid(j + 1);
      }
    }
    if (!quadratic_[i] && !evaluator.run(c_, zero_, false)) return false;
    system_.mu[i] = evaluator.mid(0) + shift;  // rounded: u |mu| joins rho
    system_.rho[i] = (evaluator.rad(0) + r * up + u_ * abs(system_.mu[i])) * up;
    if (!isfinite(system_.rho[i])) return false;
  }
  return true;
}

template <class S>
void LinearizedBounding<S>::oneSided(const Curvature& curvature, S& r, S& shift) const {
  // With sign +1, d^T H d / 2 lies in [-e, r] (e = slack max_j h_j^2) instead of [-r, r]: the
  // centre moves by (r - e) / 2 and the radius becomes (r + e) / 2 (sign -1: mirrored).
  if (curvature.sign == 0) return;
  S hMax = 0;
  for (int j = 0; j < n_; ++j) hMax = std::max(hMax, system_.h[j]);
  const S up = S(1) + tol_;
  S radius;
  taylorRemainder(curvature, r, hMax, up, shift, radius);
  r = radius * up;
}

template class LinearizedBounding<double>;
template class LinearizedBounding<Mpfr>;

}  // namespace ndc
