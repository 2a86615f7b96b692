#include "strategies/bounding/bounding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
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

//! [bernstein-test]
template <class S>
bool BernsteinBounding<S>::mayContainZero(const State& state) const {
  // Alg. 1 step (1): discard the box if a Bernstein hull excludes 0.
  for (const Bernstein<S>& patch : state.patches)
    if (patch.excludesZero()) return false;
  return true;
}
//! [bernstein-test]

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

// --- LinearizedBounding --------------------------------------------------------------------------

template <class S>
bool LinearizedBounding<S>::hasPatch(const Expression& equation) {
  // Above total degree 2 the mean-value form loses too much against the hull; at most 2 it
  // is as tight up to O(h^2) (exact for an affine F_i), and cheaper once the dense form is large.
  if (equation.tape().totalDegree(3) > 2) return true;
  // An affine equation's range is exact from its constant gradient (no halving, no scan).
  if (equation.tape().totalDegree(2) <= 1 && equation.tape().leaves().empty()) return false;
  double coefficients = 1;
  for (int d : equation.degrees()) coefficients *= d + 1;
  return coefficients <= kMaxDensePatch;
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
      m_(static_cast<int>(problem.equations.size())) {
  const auto n = static_cast<std::size_t>(n_), m = static_cast<std::size_t>(m_);
  const auto k = n >= m ? n - m : 0;
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
  for (const Expression& e : problem.equations) evaluators_.emplace_back(e.sharedTape());
  c_.resize(n);
  h_.resize(n);
  zero_.assign(n, S(0));
  jac_.resize(m * n);
  mu_.resize(m);
  rho_.resize(m);
  w_.resize(n * m);
  beta_.resize(m);
  diag_.resize(m);
  q_.resize(n * n);
  p_.resize(m * m);
  pj_.resize(m * n);
  pjAbs_.resize(m * n);
  mig_.resize(m);
  pinv_.resize(n * m);
  a_.resize(n);
  b_.resize(n);
  tlo_.resize(k);
  thi_.resize(k);
  // 7c's polygons: 4 corners, at most one vertex more per clip, 2 n clips.
  polygon_.reserve(2 * (4 + 2 * std::size_t(n)));
  clipped_.reserve(2 * (4 + 2 * std::size_t(n)));
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
  // The per-equation hulls first: cheap, and they discard most boxes far from every F_i = 0.
  if (!bernstein_.mayContainZero(state)) return false;
  if (!anyEvaluated_) return !enabled_ || !linearizationExcludes(state.box);
  // Equations without a patch: their mean-value forms, then the simultaneous test on the same
  // linearisation.
  const S hh = centreAndHalfWidths(state.box);
  // The affine rows first: their exact ranges discard most boxes far from M for a tape run
  // each, before the curved rows' evaluations over the box.
  if (!lineariseRows(true)) return true;
  if (meanValueExcludes(true)) return false;
  if (!lineariseRows(false)) return true;
  if (meanValueExcludes(false)) return false;
  return !enabled_ || !linearisedSystemExcludes(hh);
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
    for (int j = 0; j < n_; ++j) reach += abs(jac_[rowMajor(i, j, n_)]) * h_[j];
    if (abs(mu_[i]) > (rho_[i] + reach * up) * up) return true;
  }
  return false;
}

template <class S>
bool LinearizedBounding<S>::linearizationExcludes(const Box<S>& box) const {
  if (!enabled_) return false;
  // The steps of the class comment; a step that cannot conclude keeps the box.
  const S hh = centreAndHalfWidths(box);  // 1
  if (!linearise()) return false;         // 2: an enclosure that is not finite
  return linearisedSystemExcludes(hh);
}

template <class S>
bool LinearizedBounding<S>::linearisedSystemExcludes(const S& hh) const {
  if (!factorTranspose()) return false;  // 3: J_c (nearly) rank-deficient
  invertLowerFactor();                   // 4
  S migSq = 0;
  if (rowTestExcludes(migSq)) return true;       // 5
  if (ballTestExcludes(migSq, hh)) return true;  // 6
  kernelBounds();                                // 7
  if (kernelPropagationExcludes()) return true;
  if (n_ - m_ == 2 && kernelPolygonExcludes()) return true;
  // 8, unless d = -J^+ mu solves the linearised system well inside the box: then no
  // multipliers exist (Farkas), and the boxes around M, where this holds, skip the search.
  return !centreSolvesInside() && multiplierExcludes();
}

template <class S>
bool LinearizedBounding<S>::centreSolvesInside() const {
  using std::abs;
  const S inside = S(1) - S(1e-6);
  for (int j = 0; j < n_; ++j)
    if (!(abs(a_[j]) < h_[j] * inside)) return false;
  return true;
}

template <class S>
S LinearizedBounding<S>::centreAndHalfWidths(const Box<S>& box) const {
  // 1. Centre c and half-widths h >= |x - c| on the box (rounded up); returns |h|_2^2.
  const S up = S(1) + tol_;
  S hh = 0;
  for (int j = 0; j < n_; ++j) {
    c_[j] = (box.lo[j] + box.hi[j]) / 2;
    h_[j] = std::max(box.hi[j] - c_[j], c_[j] - box.lo[j]) * up;
    hh += h_[j] * h_[j];
  }
  return hh * up;
}

template <class S>
bool LinearizedBounding<S>::linearise() const {
  return lineariseRows(true) && lineariseRows(false);
}

template <class S>
bool LinearizedBounding<S>::lineariseRows(bool affine) const {
  // 2. The linearised system J_c d = -g, g in G = mu_i +- rho_i: F(c) enclosed at the point,
  // J_c = mid J(X), r_i = sum_j mag(J_ij(X) - J_c,ij) h_j = sum_j rad J_ij(X) h_j (mean value
  // theorem); for a quadratic J_c = mid grad F(c) and the Taylor remainder (class comment).
  using std::abs;
  using std::isfinite;
  const int n = n_;
  const S up = S(1) + tol_;
  for (int i = 0; i < m_; ++i) {
    if (bool(affine_[i]) != affine) continue;
    S* jac = &jac_[rowMajor(i, 0, n)];
    const MidRadEvaluator<S>& evaluator = evaluators_[i];
    S r = 0, shift = 0;  // rho's term of the linearisation; mu's shift (one-sided remainder)
    if (affine) {
      for (int j = 0; j < n; ++j) {
        jac[j] = affineMid_[rowMajor(i, j, n)];
        r += affineRad_[rowMajor(i, j, n)] * h_[j];
      }
    } else {
      if (!evaluator.run(c_, h_, true)) return false;
      for (int j = 0; j < n; ++j) r += evaluator.rad(j + 1) * h_[j];
      if (quadratic_[i]) {
        // d^T H d / 2 in [-r/2, r/2] from the gradient's radius over X (one-sided for a
        // semidefinite H), the gradient itself at c.
        r /= 2;
        oneSided(evaluator.curvature(), r, shift);
        if (!evaluator.run(c_, zero_, true)) return false;
        for (int j = 0; j < n; ++j) {
          jac[j] = evaluator.mid(j + 1);
          r += evaluator.rad(j + 1) * h_[j];
        }
      } else {
        for (int j = 0; j < n; ++j) jac[j] = evaluator.mid(j + 1);
      }
    }
    if (!quadratic_[i] && !evaluator.run(c_, zero_, false)) return false;
    mu_[i] = evaluator.mid(0) + shift;  // rounded: u |mu| joins rho
    rho_[i] = (evaluator.rad(0) + r * up + u_ * abs(mu_[i])) * up;
    if (!isfinite(rho_[i])) return false;
  }
  return true;
}

template <class S>
void LinearizedBounding<S>::oneSided(const Curvature& curvature, S& r, S& shift) const {
  // With sign +1, d^T H d / 2 lies in [-e, r] (e = slack max_j h_j^2) instead of [-r, r]: the
  // centre moves by (r - e) / 2 and the radius becomes (r + e) / 2 (sign -1: mirrored).
  if (curvature.sign == 0) return;
  S hMax = 0;
  for (int j = 0; j < n_; ++j) hMax = std::max(hMax, h_[j]);
  const S up = S(1) + tol_;
  S radius;
  taylorRemainder(curvature, r, hMax, up, shift, radius);
  r = radius * up;
}

template <class S>
bool LinearizedBounding<S>::factorTranspose() const {
  // 3. Householder QR of J_c^T (n x m, column i = row i of J_c): J_c^T = Q [R; 0]. A pivot
  // below 1e-10 of the largest row norm means J_c is (nearly) rank-deficient: keep the box.
  using std::isfinite;
  using std::sqrt;
  const int n = n_, m = m_;
  std::copy(jac_.begin(), jac_.end(), w_.begin());
  S scale = 0;
  for (int i = 0; i < m; ++i) {
    S s = 0;
    for (int j = 0; j < n; ++j) s += jac_[rowMajor(i, j, n)] * jac_[rowMajor(i, j, n)];
    scale = std::max(scale, s);
  }
  if (!(scale > 0) || !isfinite(scale)) return false;
  const S pivotFloor = sqrt(scale) * S(1e-10);
  for (int i = 0; i < m; ++i) {
    S* v = &w_[rowMajor(i, 0, n)];
    S norm2 = 0;
    for (int r = i; r < n; ++r) norm2 += v[r] * v[r];
    const S norm = sqrt(norm2);
    if (!(norm > pivotFloor)) return false;
    // Reflector I - beta v v^T mapping the column to alpha e_i; alpha has the opposite sign of
    // v_i, so v_i - alpha does not cancel.
    const S alpha = v[i] > 0 ? S(-norm) : norm;
    const S vv = 2 * (norm2 - alpha * v[i]);
    v[i] -= alpha;
    beta_[i] = 2 / vv;
    diag_[i] = alpha;
    for (int col = i + 1; col < m; ++col) reflect(i, &w_[rowMajor(col, 0, n)]);
  }
  // Q = H_0 ... H_{m-1}, accumulated backwards (H_i only touches columns >= i of the partial
  // product). Columns 0..m-1 are Q1 (the row space of J_c), m..n-1 are N = Q2 (its kernel).
  std::fill(q_.begin(), q_.end(), S(0));
  for (int j = 0; j < n; ++j) q_[rowMajor(j, j, n)] = 1;
  for (int i = m - 1; i >= 0; --i)
    for (int col = i; col < n; ++col) reflect(i, &q_[rowMajor(col, 0, n)]);
  return true;
}

template <class S>
void LinearizedBounding<S>::reflect(int i, S* x) const {
  // x <- (I - beta_i v_i v_i^T) x on rows i..n-1, v_i the i-th reflector (column i of w_).
  const S* v = &w_[rowMajor(i, 0, n_)];
  S s = 0;
  for (int r = i; r < n_; ++r) s += v[r] * x[r];
  s *= beta_[i];
  for (int r = i; r < n_; ++r) x[r] -= s * v[r];
}

template <class S>
void LinearizedBounding<S>::invertLowerFactor() const {
  // 4. P = L^{-1} with L = R^T (L L^T = J_c J_c^T): L(i,i) = diag_i, L(i,t) = R(t,i) = w_[i][t].
  const int n = n_, m = m_;
  for (int col = 0; col < m; ++col) {
    for (int i = 0; i < m; ++i) {
      if (i < col) {
        p_[rowMajor(i, col, m)] = 0;
        continue;
      }
      S s = i == col ? S(1) : S(0);
      for (int t = col; t < i; ++t) s -= w_[rowMajor(i, t, n)] * p_[rowMajor(t, col, m)];
      p_[rowMajor(i, col, m)] = s / diag_[i];
    }
  }
}

template <class S>
bool LinearizedBounding<S>::rowTestExcludes(S& migSq) const {
  // 5. Row test. P J_c d = -P g, and P J_c = Q1^T up to rounding; its computed value carries
  // the error bound tol |P| |J_c| (gamma_m of an m-term dot product).
  using std::abs;
  const int n = n_, m = m_;
  const S& tol = tol_;
  const S up = S(1) + tol;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) {
      S s = 0, sa = 0;
      for (int t = 0; t <= i; ++t) {
        s += p_[rowMajor(i, t, m)] * jac_[rowMajor(t, j, n)];
        sa += abs(p_[rowMajor(i, t, m)]) * abs(jac_[rowMajor(t, j, n)]);
      }
      pj_[rowMajor(i, j, n)] = s;
      pjAbs_[rowMajor(i, j, n)] = sa;
    }
  for (int i = 0; i < m; ++i) {
    S v = 0, va = 0, vr = 0;  // (P mu)_i, (|P| |mu|)_i, (|P| rho)_i
    for (int t = 0; t <= i; ++t) {
      v += p_[rowMajor(i, t, m)] * mu_[t];
      va += abs(p_[rowMajor(i, t, m)]) * abs(mu_[t]);
      vr += abs(p_[rowMajor(i, t, m)]) * rho_[t];
    }
    // A lower bound of |(P g)_i| over g in G (the last term covers the roundings here).
    const S absV = abs(v);
    S mig = absV - tol * va - vr - tol * (absV + va + vr);
    if (!(mig > 0)) mig = 0;
    mig_[i] = mig;
    S reach = 0;  // upper bound of sum_j |(P J_c)_ij| h_j
    for (int j = 0; j < n; ++j)
      reach += (abs(pj_[rowMajor(i, j, n)]) + tol * pjAbs_[rowMajor(i, j, n)]) * h_[j];
    if (mig > reach * up) return true;
    migSq += mig * mig;
  }
  return false;
}

template <class S>
bool LinearizedBounding<S>::ballTestExcludes(const S& migSq, const S& hh) const {
  // 6. Ball test: |P J_c d|_2 <= |P J_c|_2 |d|_2 <= |P J_c|_2 |h|_2, with
  // |P J_c|_2 <= sqrt(|M M^T|_inf) + |E|_F for the computed M and its error bound E.
  using std::abs;
  using std::sqrt;
  const int n = n_, m = m_;
  const S& tol = tol_;
  const S up = S(1) + tol;
  S gram = 0, errF = 0;
  for (int i = 0; i < m; ++i) {
    S row = 0;
    for (int t = 0; t < m; ++t) {
      S g = 0, ga = 0;
      for (int j = 0; j < n; ++j) {
        g += pj_[rowMajor(i, j, n)] * pj_[rowMajor(t, j, n)];
        ga += abs(pj_[rowMajor(i, j, n)]) * abs(pj_[rowMajor(t, j, n)]);
      }
      row += abs(g) + tol * ga;
    }
    gram = std::max(gram, row);
    for (int j = 0; j < n; ++j)
      errF += (tol * pjAbs_[rowMajor(i, j, n)]) * (tol * pjAbs_[rowMajor(i, j, n)]);
  }
  const S normBound = (sqrt(gram * up) + sqrt(errF * up)) * up;
  return migSq * (S(1) - tol) > normBound * normBound * hh * up;
}

template <class S>
void LinearizedBounding<S>::kernelBounds() const {
  // 7. Null-space test. With J^+ = Q1 P (n x m) and D = I - J^+ J_c - N N^T, every solution
  // is d = -J^+ g + N t + D d with t = N^T d, so for every axis j
  // |(N t)_j - (J^+ mu)_j| <= h_j + (|J^+| rho)_j + (|D| h)_j =: b_j.
  using std::abs;
  const int n = n_, m = m_, k = n_ - m_;
  const S& tol = tol_;
  const S up = S(1) + tol;
  for (int j = 0; j < n; ++j)
    for (int t = 0; t < m; ++t) {
      S s = 0;
      for (int i = t; i < m; ++i) s += q1(j, i) * p_[rowMajor(i, t, m)];
      pinv_[rowMajor(j, t, m)] = s;
    }
  for (int j = 0; j < n; ++j) {
    S a = 0, aa = 0, ar = 0;  // (J^+ mu)_j, (|J^+| |mu|)_j, (|J^+| rho)_j
    for (int t = 0; t < m; ++t) {
      const S& pv = pinv_[rowMajor(j, t, m)];
      a += pv * mu_[t];
      aa += abs(pv) * abs(mu_[t]);
      ar += abs(pv) * rho_[t];
    }
    S dh = 0;  // (|D| h)_j with D's rounding error bound
    for (int l = 0; l < n; ++l) {
      S d = j == l ? S(1) : S(0), da = d;
      for (int t = 0; t < m; ++t) {
        d -= pinv_[rowMajor(j, t, m)] * jac_[rowMajor(t, l, n)];
        da += abs(pinv_[rowMajor(j, t, m)]) * abs(jac_[rowMajor(t, l, n)]);
      }
      for (int p = 0; p < k; ++p) {
        d -= nul(j, p) * nul(l, p);
        da += abs(nul(j, p)) * abs(nul(l, p));
      }
      dh += (abs(d) + tol * da) * h_[l];
    }
    a_[j] = a;
    b_[j] = (h_[j] + ar + dh + tol * (2 * aa + ar + dh)) * up;
  }
}

template <class S>
bool LinearizedBounding<S>::kernelPropagationExcludes() const {
  // Propagate the constraints on t over the box |t_p| <= sum_j |N_jp| h_j; for k = 1 a single
  // sweep intersects n intervals and is exact.
  using std::abs;
  const int n = n_, k = n_ - m_;
  const S& tol = tol_;
  for (int p = 0; p < k; ++p) {
    S tau = 0;
    for (int j = 0; j < n; ++j) tau += abs(nul(j, p)) * h_[j];
    thi_[p] = tau * (S(1) + tol);
    tlo_[p] = -thi_[p];
  }
  const int sweeps = k <= 1 ? 1 : 3;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    for (int j = 0; j < n; ++j) {
      bool free = true;  // no t enters axis j: the constraint is |a_j| <= b_j
      for (int p = 0; p < k; ++p) {
        if (nul(j, p) == 0) continue;
        free = false;
        if (narrowKernelBox(j, p)) return true;
      }
      if (free && abs(a_[j]) - b_[j] > tol * (abs(a_[j]) + b_[j])) return true;
    }
  }
  return false;
}

template <class S>
bool LinearizedBounding<S>::narrowKernelBox(int j, int p) const {
  // N_jp t_p lies in a_j +- b_j minus the other terms (interval product over the t box);
  // true when the t box becomes empty.
  using std::abs;
  const int k = n_ - m_;
  const S& tol = tol_;
  const S& nv = nul(j, p);
  S restLo = 0, restHi = 0, restMag = 0;
  for (int o = 0; o < k; ++o) {
    if (o == p) continue;
    const S& no = nul(j, o);
    if (no >= 0) {
      restLo += no * tlo_[o];
      restHi += no * thi_[o];
    } else {
      restLo += no * thi_[o];
      restHi += no * tlo_[o];
    }
    restMag += abs(no) * std::max(abs(tlo_[o]), abs(thi_[o]));
  }
  const S slack = tol * (abs(a_[j]) + b_[j] + restMag);
  const S lo = a_[j] - b_[j] - restHi - slack, hi = a_[j] + b_[j] - restLo + slack;
  S tl = (nv > 0 ? lo : hi) / nv, th = (nv > 0 ? hi : lo) / nv;
  tl -= tol * abs(tl);
  th += tol * abs(th);
  if (tl > tlo_[p]) tlo_[p] = tl;
  if (th < thi_[p]) thi_[p] = th;
  return tlo_[p] > thi_[p];
}

template <class S>
bool LinearizedBounding<S>::kernelPolygonExcludes() const {
  // For k = 2 the solutions t form the intersection of n strips |N_j t - a_j| <= b_j, a convex
  // polygon that propagation over boxes only bounds (it misses a corner the strips cut off
  // together). Clip the propagated box by each strip's two half-planes (Sutherland-Hodgman);
  // every half-plane is relaxed by 4 times narrowKernelBox's slack, so the relaxed polygon
  // holds a disc of radius about that slack around each true solution, which the clipping's
  // rounding (each new vertex a convex combination of two old ones) cannot lose.
  using std::abs;
  const int n = n_;
  const S& tol = tol_;
  const S reach = std::max({abs(tlo_[0]), abs(thi_[0]), abs(tlo_[1]), abs(thi_[1])});
  polygon_ = {tlo_[0], tlo_[1], thi_[0], tlo_[1], thi_[0], thi_[1], tlo_[0], thi_[1]};
  // Keeps the part of the polygon where u . t <= bound.
  const auto clip = [&](const S& u0, const S& u1, const S& bound) {
    clipped_.clear();
    const std::size_t count = polygon_.size() / 2;
    for (std::size_t v = 0; v < count; ++v) {
      const std::size_t w = (v + 1) % count;
      const S& x0 = polygon_[2 * v];
      const S& y0 = polygon_[2 * v + 1];
      const S& x1 = polygon_[2 * w];
      const S& y1 = polygon_[2 * w + 1];
      const S s0 = u0 * x0 + u1 * y0 - bound, s1 = u0 * x1 + u1 * y1 - bound;
      if (s0 <= 0) clipped_.insert(clipped_.end(), {x0, y0});
      if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
        const S f = s0 / (s0 - s1);
        clipped_.insert(clipped_.end(), {x0 + f * (x1 - x0), y0 + f * (y1 - y0)});
      }
    }
    polygon_.swap(clipped_);
    return !polygon_.empty();
  };
  for (int j = 0; j < n; ++j) {
    const S& u0 = nul(j, 0);
    const S& u1 = nul(j, 1);
    if (u0 == 0 && u1 == 0) continue;  // decided by the propagation
    const S slack = 4 * tol * (abs(a_[j]) + b_[j] + (abs(u0) + abs(u1)) * reach);
    if (!clip(u0, u1, a_[j] + b_[j] + slack) || !clip(-u0, -u1, b_[j] - a_[j] + slack)) return true;
  }
  return false;
}

template <class S>
bool LinearizedBounding<S>::multiplierExcludes() const {
  // 8. The multiplier test on the linearised system (framework/core/multipliers.hpp).
  return multipliers_.excludes(m_, n_, jac_.data(), mu_.data(), rho_.data(), h_.data(), tol_,
                               kMultiplierIterations);
}

// --- Factory -------------------------------------------------------------------------------------

//! [bounding-registry]
Registry<BoundingFactory>& boundingRegistry() {
  static Registry<BoundingFactory> registry(
      "bounding",
      {{{"bernstein",
         "The convex hull of the Bernstein coefficients (Sec. 4): a box is discarded when one "
         "equation's coefficients all have one sign.",
         {}},
        boundingFactory<BernsteinBounding>()},
       {{"interval",
         "Interval arithmetic on the expression, with a mean-value form: cheap per box, looser "
         "than the Bernstein hull.",
         {}},
        boundingFactory<IntervalBounding>()},
       {{"linearized",
         "The Bernstein hull (the mean-value form for a quadratic whose dense form is large), "
         "then a linearization of all equations together that discards boxes no single "
         "equation can (docs/subdivision.md).",
         {}},
        boundingFactory<LinearizedBounding>()}});
  return registry;
}
//! [bounding-registry]

template <class S>
Bounding<S> createBounding(const StrategyChoice& choice, const Problem& problem,
                           const Box<S>& domain) {
  const BoundingFactory& factory = boundingRegistry().find(choice.name).create;
  if constexpr (std::is_same_v<S, double>)
    return factory.inDouble(problem, domain, choice.parameters);
  else
    return factory.inMpfr(problem, domain, choice.parameters);
}

template <class S>
Bounding<S> createBounding(std::string_view spec, const Problem& problem, const Box<S>& domain) {
  return createBounding<S>(boundingRegistry().parse(spec), problem, domain);
}

template class BernsteinBounding<double>;
template class BernsteinBounding<Mpfr>;
template class IntervalBounding<double>;
template class IntervalBounding<Mpfr>;
template class LinearizedBounding<double>;
template class LinearizedBounding<Mpfr>;
template Bounding<double> createBounding<double>(const StrategyChoice&, const Problem&,
                                                 const Box<double>&);
template Bounding<Mpfr> createBounding<Mpfr>(const StrategyChoice&, const Problem&,
                                             const Box<Mpfr>&);
template Bounding<double> createBounding<double>(std::string_view, const Problem&,
                                                 const Box<double>&);
template Bounding<Mpfr> createBounding<Mpfr>(std::string_view, const Problem&, const Box<Mpfr>&);

}  // namespace ndc
