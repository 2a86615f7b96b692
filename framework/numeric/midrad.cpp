// Midpoint-radius evaluation of a Tape (see midrad.hpp).
#include "framework/numeric/midrad.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ndc {

namespace {

using K = TapeOp::Kind;

// Midpoint-radius products and sums: z = x * y and z = x + s y (s = +-1), each with the
// rounding of its midpoint (u |z| bounds it, u >= 2 x unit round-off) and of its radius (the
// factor up = 1 + 8 u) absorbed in the radius.
template <class S>
void mulMidRad(const S& xm, const S& xr, const S& ym, const S& yr, const S& u, const S& up, S& zm,
               S& zr) {
  using std::abs;
  S m = xm * ym;
  S r = (abs(xm) * yr + xr * abs(ym) + xr * yr + u * abs(m)) * up;
  zm = std::move(m);
  zr = std::move(r);
}

template <class S>
void addMidRad(S& xm, S& xr, const S& ym, const S& yr, bool subtract, const S& u, const S& up) {
  using std::abs;
  if (subtract)
    xm -= ym;
  else
    xm += ym;
  xr = (xr + yr + u * abs(xm)) * up;
}

template <class S>
bool isZero(const S& m, const S& r) {
  return m == 0 && r == 0;
}

/// Midpoint and radius of an interval, the radius rounded up by the factor `up`.
template <class S>
void toMidRad(const Interval<S>& v, const S& up, S& mid, S& rad) {
  mid = v.midpoint();
  rad = std::max(v.upper() - mid, mid - v.lower()) * up;
}

}  // namespace

template <class S>
MidRadEvaluator<S>::MidRadEvaluator(std::shared_ptr<const Tape> tape, std::span<const S> origin)
    : tape_(std::move(tape)), u_(ScalarTraits<S>::epsilon()), up_(S(1) + 8 * u_) {
  for (const TapeConstant& c : tape_->constants()) {
    constMid_.emplace_back();
    constRad_.emplace_back();
    toMidRad(c.enclosure<S>(), up_, constMid_.back(), constRad_.back());
  }
  const auto stride = static_cast<std::size_t>(tape_->dim()) + 1;
  stackMid_.assign(static_cast<std::size_t>(tape_->stackDepth()) * stride, S(0));
  stackRad_ = stackMid_;
  leafMid_.assign(tape_->leaves().size() * stride, S(0));
  leafRad_ = leafMid_;
  leafDone_.assign(tape_->leaves().size(), 0);
  gradientAffine_ = tape_->leaves().empty() && tape_->totalDegree(3) <= 2;
  if (gradientAffine_ && !buildForm(origin)) form_.reset();
}

template <class S>
bool MidRadEvaluator<S>::buildForm(std::span<const S> origin) {
  // f_o = F(o) and g_o = grad F(o); column l of H = (grad F(o + delta e_l) - g_o) / delta (the
  // gradient is affine), delta = (o_l + 1) - o_l as rounded, whose exact value lies within
  // u |delta| / 2 of it: differences at o, where the program's terms are at the scale of F's
  // variation, not at 0, where they cancel for a domain far from it.
  using std::abs;
  const auto n = static_cast<std::size_t>(tape_->dim());
  std::vector<S> zero(n, S(0));
  QuadraticForm f;
  f.origin.assign(n, S(0));
  if (origin.size() == n) std::copy(origin.begin(), origin.end(), f.origin.begin());
  if (!runProgram(f.origin, zero, true)) return false;
  f.f0m = stackMid_[0], f.f0r = stackRad_[0];
  f.g0m.assign(stackMid_.begin() + 1, stackMid_.begin() + 1 + long(n));
  f.g0r.assign(stackRad_.begin() + 1, stackRad_.begin() + 1 + long(n));
  std::vector<S> x = f.origin, hm(n * n), hr(n * n);
  for (std::size_t l = 0; l < n; ++l) {
    x[l] = f.origin[l] + 1;
    const S delta = x[l] - f.origin[l];
    if (!runProgram(x, zero, true)) return false;
    x[l] = f.origin[l];
    for (std::size_t j = 0; j < n; ++j) {
      const S diff = stackMid_[j + 1] - f.g0m[j];
      const S diffRad = stackRad_[j + 1] + f.g0r[j] + u_ * abs(diff);
      const S h = diff / delta;
      hm[j * n + l] = h;
      hr[j * n + l] = ((diffRad + u_ * abs(diff)) / (abs(delta) * (1 - u_)) + u_ * abs(h)) * up_;
    }
  }
  // H is symmetric: its midpoint, with |H_jl - mid| <= hr_jl + |hm_jl - mid|, kept once per
  // pair (j <= l; the loops over it add an entry off the diagonal to both rows); exact zeros (a
  // variable in no product) are left out.
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t l = j; l < n; ++l) {
      const S& a = hm[j * n + l];
      const S& b = hm[l * n + j];
      if (a == 0 && b == 0 && hr[j * n + l] == 0 && hr[l * n + j] == 0) continue;
      const S mid = (a + b) / 2;
      const S rad = (std::max(hr[j * n + l], hr[l * n + j]) + abs(a - mid) + u_ * abs(mid)) * up_;
      f.row.push_back(static_cast<std::uint32_t>(j));
      f.column.push_back(static_cast<std::uint32_t>(l));
      f.hm.push_back(mid);
      f.hr.push_back(rad);
      f.habs.push_back((abs(mid) + rad) * up_);
    }
  form_ = std::move(f);
  formG_.resize(n);
  formMagnitude_.resize(n);
  formD_.resize(n);
  formR_.resize(n);
  formP_.resize(n);
  formSpread_.resize(n);
  return true;
}

template <class S>
bool MidRadEvaluator<S>::run(std::span<const S> centre, std::span<const S> radius,
                             bool gradient) const {
  return form_ ? runForm(centre, radius, gradient) : runProgram(centre, radius, gradient);
}

template <class S>
bool MidRadEvaluator<S>::runForm(std::span<const S> centre, std::span<const S> radius,
                                 bool gradient) const {
  using std::abs;
  using std::isfinite;
  const QuadraticForm& f = *form_;
  const std::size_t n = f.g0m.size(), nonzeros = f.hm.size();
  stride_ = gradient ? n + 1 : 1;
  // Sums of up to n + 2 terms: gamma_(n+2) <= (n + 2) u (u >= 2 x unit round-off) of their
  // magnitudes, and the radii's own sums rounded up by `up`.
  const S gamma = S(n + 2) * u_, up = S(1) + S(n + 8) * u_;
  // d = c - o, rounded: the exact c lies within u |d_j| of o + d, which widens the box.
  std::vector<S>& d = formD_;
  std::vector<S>& wr = formR_;
  for (std::size_t j = 0; j < n; ++j) {
    d[j] = centre[j] - f.origin[j];
    wr[j] = f.origin[j] == 0 ? radius[j] : (radius[j] + u_ * abs(d[j])) * up_;
  }
  // G(c) = g_o + H d into the gradient slots (midpoints) and formG_ (radii); the magnitudes of
  // its terms go to the rounding bound.
  S* gm = &stackMid_[1];
  std::vector<S>& gr = formG_;
  std::vector<S>& mag = formMagnitude_;
  for (std::size_t j = 0; j < n; ++j) {
    gm[j] = f.g0m[j];
    gr[j] = f.g0r[j];
    mag[j] = abs(f.g0m[j]);
  }
  for (std::size_t t = 0; t < nonzeros; ++t) {
    const std::uint32_t j = f.row[t], l = f.column[t];
    const S term = f.hm[t] * d[l];
    gm[j] += term;
    gr[j] += f.hr[t] * abs(d[l]);
    mag[j] += abs(term);
    if (j == l) continue;
    const S mirror = f.hm[t] * d[j];  // H_lj = H_jl
    gm[l] += mirror;
    gr[l] += f.hr[t] * abs(d[j]);
    mag[l] += abs(mirror);
  }
  for (std::size_t j = 0; j < n; ++j) gr[j] = (gr[j] + gamma * mag[j]) * up;
  // F(c) = f_o + sum_j d_j (g_o,j + G_j) / 2.
  S fm = f.f0m, fr = f.f0r, fmag = abs(f.f0m);
  for (std::size_t j = 0; j < n; ++j) {
    const S w = (f.g0m[j] + gm[j]) / 2;
    const S wr_j = (f.g0r[j] + gr[j]) / 2 + u_ * abs(w);
    const S term = d[j] * w;
    fm += term;
    fr += abs(d[j]) * wr_j;
    fmag += abs(term);
  }
  fr = (fr + gamma * fmag) * up;
  // The value at the centre alone, as a run with radius 0 gives it: the box of d's rounding.
  if (recordCentre_) {
    std::vector<S>& wp = formP_;
    for (std::size_t j = 0; j < n; ++j) wp[j] = f.origin[j] == 0 ? S(0) : (u_ * abs(d[j])) * up_;
    centreMid_ = fm;
    centreRad_ = fr;
    widen(centreRad_, wp, formSpread_.data(), up);
  }
  // Over the box, where the gradient's radii grow by the spread too.
  S* spread = &stackRad_[1];
  if (widen(fr, wr, spread, up))
    for (std::size_t j = 0; j < n; ++j) gr[j] = (gr[j] + spread[j]) * up;
  stackMid_[0] = fm;
  stackRad_[0] = fr;
  for (std::size_t j = 0; gradient && j < n; ++j) stackRad_[j + 1] = gr[j];
  return isfinite(fm) && isfinite(fr);
}

template <class S>
bool MidRadEvaluator<S>::widen(S& fr, std::span<const S> w, S* spread, const S& up) const {
  // F(c + d) = F(c) + G(c) . d + d^T H d / 2 with |d_j| <= w_j: the value's radius grows by
  // sum_j (|G_j| + (|H| w)_j / 2) w_j, G(c) in the gradient slots (midpoints) and formG_.
  using std::abs;
  const QuadraticForm& f = *form_;
  const std::size_t n = f.g0m.size();
  bool wide = false;
  for (std::size_t j = 0; j < n && !wide; ++j) wide = w[j] != 0;
  if (!wide) return false;
  for (std::size_t j = 0; j < n; ++j) spread[j] = 0;
  addAbsH(w.data(), spread);
  const S* gm = &stackMid_[1];
  S reach = 0;
  for (std::size_t j = 0; j < n; ++j) {
    spread[j] *= up;
    reach += (abs(gm[j]) + formG_[j] + spread[j] / 2) * w[j];
  }
  fr = (fr + reach * up) * up;
  return true;
}

template <class S>
bool MidRadEvaluator<S>::runWithCentre(std::span<const S> centre, std::span<const S> radius) const {
  if (form_) {
    recordCentre_ = true;
    const bool ok = runForm(centre, radius, true);
    recordCentre_ = false;
    using std::isfinite;
    return ok && isfinite(centreMid_) && isfinite(centreRad_);
  }
  // A program: the pass at the centre first, then the one over the box.
  zero_.assign(centre.size(), S(0));
  if (!runProgram(centre, std::span<const S>(zero_), false)) return false;
  centreMid_ = stackMid_[0];
  centreRad_ = stackRad_[0];
  return runProgram(centre, radius, true);
}

template <class S>
void MidRadEvaluator<S>::addAbsH(const S* w, S* spread) const {
  const QuadraticForm& f = *form_;
  for (std::size_t t = 0; t < f.hm.size(); ++t) {
    const std::uint32_t j = f.row[t], l = f.column[t];
    spread[j] += f.habs[t] * w[l];
    if (j != l) spread[l] += f.habs[t] * w[j];
  }
}

template <class S>
bool MidRadEvaluator<S>::gradientSpread(std::span<const S> radius, std::span<S> spread) const {
  if (!form_) return false;
  const QuadraticForm& f = *form_;
  const S up = S(1) + S(f.g0m.size() + 8) * u_;
  for (std::size_t j = 0; j < spread.size(); ++j) spread[j] = 0;
  addAbsH(radius.data(), spread.data());
  for (std::size_t j = 0; j < spread.size(); ++j) spread[j] *= up;
  return true;
}

template <class S>
bool MidRadEvaluator<S>::runProgram(std::span<const S> centre, std::span<const S> radius,
                                    bool gradient) const {
  using std::isfinite;
  stride_ = gradient ? static_cast<std::size_t>(tape_->dim()) + 1 : 1;
  centre_ = centre;
  radius_ = radius;
  std::fill(leafDone_.begin(), leafDone_.end(), 0);
  std::size_t top = 0;  // number of occupied slots
  for (const TapeOp& op : tape_->ops()) {
    if (op.kind == K::kConstant || op.kind == K::kVariable || op.kind == K::kLeaf) {
      pushOperand(op, &stackMid_[top * stride_], &stackRad_[top * stride_]);
      ++top;
      continue;
    }
    // Unary instructions act on the top slot, binary ones on the two top slots (x below y).
    if (op.kind != K::kPow && op.kind != K::kNeg) --top;
    S* xm = &stackMid_[(top - 1) * stride_];
    S* xr = &stackRad_[(top - 1) * stride_];
    if (!apply(op, xm, xr, xm + stride_, xr + stride_)) return false;
  }
  return isfinite(stackMid_[0]) && isfinite(stackRad_[0]);
}

template <class S>
void MidRadEvaluator<S>::pushOperand(const TapeOp& op, S* m, S* r) const {
  const auto arg = static_cast<std::size_t>(op.arg);
  for (std::size_t q = 1; q < stride_; ++q) m[q] = r[q] = 0;
  switch (op.kind) {
    case K::kLeaf:
      leafEnclosure(arg, m, r);
      break;
    case K::kConstant:
      m[0] = constMid_[arg];
      r[0] = constRad_[arg];
      break;
    default:  // a variable
      m[0] = centre_[arg];
      r[0] = radius_[arg];
      if (stride_ > 1) m[arg + 1] = 1;
  }
}

template <class S>
void MidRadEvaluator<S>::leafEnclosure(std::size_t i, S* m, S* r) const {
  // Interval enclosures of the leaf and its partials over the box, as midpoint-radius, once
  // per distinct leaf and run.
  S* memoMid = &leafMid_[i * stride_];
  S* memoRad = &leafRad_[i * stride_];
  if (!leafDone_[i]) {
    const TapeLeaf& leaf = tape_->leaves()[i];
    const PiecewiseBernstein& p = *leaf.polynomial;
    Interval<S> local[8];  // PiecewiseBernstein::validate allows at most 8 axes
    for (int a = 0; a < p.dim(); ++a) {
      const auto j = static_cast<std::size_t>(p.axes[a]);
      local[a] = Interval<S>(centre_[j] - radius_[j], centre_[j] + radius_[j]);
    }
    const std::span<const Interval<S>> span(local, static_cast<std::size_t>(p.dim()));
    toMidRad(p.enclose<S>(span), up_, m[0], r[0]);
    if (stride_ > 1)
      for (int a = 0; a < p.dim(); ++a)
        toMidRad(leaf.partials[a]->template enclose<S>(span), up_, m[p.axes[a] + 1],
                 r[p.axes[a] + 1]);
    for (std::size_t q = 0; q < stride_; ++q) memoMid[q] = m[q], memoRad[q] = r[q];
    leafDone_[i] = 1;
    return;
  }
  for (std::size_t q = 0; q < stride_; ++q) m[q] = memoMid[q], r[q] = memoRad[q];
}

template <class S>
bool MidRadEvaluator<S>::apply(const TapeOp& op, S* xm, S* xr, const S* ym, const S* yr) const {
  using std::abs;
  const S& u = u_;
  const S& up = up_;
  S& sm = sm_;
  S& sr = sr_;
  switch (op.kind) {
    case K::kAdd:
    case K::kSub:
      for (std::size_t q = 0; q < stride_; ++q)
        if (!isZero(ym[q], yr[q])) addMidRad(xm[q], xr[q], ym[q], yr[q], op.kind == K::kSub, u, up);
      break;
    case K::kMul:
      // Product rule (xy)' = x' y + x y', then the value.
      for (std::size_t q = 1; q < stride_; ++q) {
        const bool zx = isZero(xm[q], xr[q]), zy = isZero(ym[q], yr[q]);
        if (zx && zy) continue;
        mulMidRad(xm[0], xr[0], ym[q], yr[q], u, up, sm, sr);
        if (zx) {
          xm[q] = sm;
          xr[q] = sr;
          continue;
        }
        mulMidRad(xm[q], xr[q], ym[0], yr[0], u, up, xm[q], xr[q]);
        if (!zy) addMidRad(xm[q], xr[q], sm, sr, false, u, up);
      }
      mulMidRad(xm[0], xr[0], ym[0], yr[0], u, up, xm[0], xr[0]);
      break;
    case K::kDiv: {
      // The divisor is a constant: multiply by an enclosure of its reciprocal.
      const S mag = abs(ym[0]);
      const S gap = mag - yr[0];
      if (!(gap > 2 * u * mag)) return false;
      S& fm = fm_;
      S& fr = fr_;
      fm = S(1) / ym[0];
      fr = (yr[0] / (mag * gap) + u * abs(fm)) * up;
      for (std::size_t q = 0; q < stride_; ++q)
        if (!isZero(xm[q], xr[q])) mulMidRad(xm[q], xr[q], fm, fr, u, up, xm[q], xr[q]);
      break;
    }
    case K::kPow:
      power(op.arg, xm, xr);
      break;
    case K::kNeg:
      for (std::size_t q = 0; q < stride_; ++q) xm[q] = -xm[q];
      break;
    default:
      break;
  }
  return true;
}

template <class S>
void MidRadEvaluator<S>::power(int p, S* xm, S* xr) const {
  // x^p = x^(p-1) x by binary powering, and (x^p)' = p x^(p-1) x'.
  const S& u = u_;
  const S& up = up_;
  if (p == 0) {
    xm[0] = 1;
    xr[0] = 0;
    for (std::size_t q = 1; q < stride_; ++q) xm[q] = xr[q] = 0;
    return;
  }
  S &tm = tm_, &tr = tr_, &sm = sm_, &sr = sr_, &fm = fm_, &fr = fr_;
  tm = 1;
  tr = 0;
  sm = xm[0];
  sr = xr[0];
  for (int e = p - 1; e > 0; e >>= 1) {
    if (e & 1) mulMidRad(tm, tr, sm, sr, u, up, tm, tr);
    if (e > 1) mulMidRad(sm, sr, sm, sr, u, up, sm, sr);
  }
  mulMidRad(S(p), S(0), tm, tr, u, up, fm, fr);
  for (std::size_t q = 1; q < stride_; ++q)
    if (!isZero(xm[q], xr[q])) mulMidRad(fm, fr, xm[q], xr[q], u, up, xm[q], xr[q]);
  mulMidRad(tm, tr, xm[0], xr[0], u, up, xm[0], xr[0]);
}

namespace {

/// Whether +-M is positive semidefinite up to a proven slack (quadraticCurvature's
/// factorisation and bound); `radius` bounds |H - M| entrywise.
bool semidefiniteSlack(int n, const std::vector<double>& m, const std::vector<double>& radius,
                       double& slack) {
  using std::abs;
  const double eps = ScalarTraits<double>::epsilon();
  const double gamma = double(2 * n + 16) * eps;
  const auto at = [n](int j, int k) { return std::size_t(j) * std::size_t(n) + std::size_t(k); };
  // Pivoted L D L^T of m, largest remaining diagonal first; l holds the columns found.
  std::vector<double> work = m, l, d;
  std::vector<char> done(std::size_t(n), 0);
  double scale = 0, total = 0;
  for (int j = 0; j < n; ++j) scale = std::max(scale, abs(m[at(j, j)]));
  for (double v : m) total += abs(v);
  for (int step = 0; step < n; ++step) {
    int p = -1;
    for (int j = 0; j < n; ++j)
      if (!done[j] && (p < 0 || work[at(j, j)] > work[at(p, p)])) p = j;
    if (p < 0 || !(work[at(p, p)] > 1e-12 * scale)) break;
    const double pivot = work[at(p, p)];
    done[p] = 1;
    const std::size_t column = l.size();
    l.resize(column + std::size_t(n), 0.0);
    for (int j = 0; j < n; ++j) l[column + j] = done[j] && j != p ? 0.0 : work[at(j, p)] / pivot;
    l[column + p] = 1;
    d.push_back(pivot);
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) work[at(j, k)] -= l[column + j] * pivot * l[column + k];
  }
  // B_jk >= |H_jk - (L D L^T)_jk|: the computed residual, its rounding and the radius.
  double sum = 0;
  const std::size_t rank = d.size();
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < n; ++k) {
      double product = 0, magnitude = 0;
      for (std::size_t t = 0; t < rank; ++t) {
        const double v = l[t * n + j] * d[t] * l[t * n + k];
        product += v;
        magnitude += abs(v);
      }
      const double residual = m[at(j, k)] - product;
      sum +=
          (abs(residual) + gamma * (abs(m[at(j, k)]) + magnitude) + radius[at(j, k)]) * (1 + gamma);
    }
  slack = sum / 2 * (1 + gamma);
  return std::isfinite(slack) && slack <= 1e-8 * total + std::numeric_limits<double>::min();
}

}  // namespace

Curvature quadraticCurvature(const std::shared_ptr<const Tape>& tape) {
  using std::abs;
  if (!tape->leaves().empty() || tape->totalDegree(3) != 2) return {};
  const int n = tape->dim();
  const double eps = ScalarTraits<double>::epsilon();
  MidRadEvaluator<double> e(tape);
  const auto size = static_cast<std::size_t>(n);
  std::vector<double> x(size, 0.0), zero(size, 0.0);
  std::vector<double> g0m(size), g0r(size);
  if (!e.run(x, zero, true)) return {};
  for (int j = 0; j < n; ++j) g0m[j] = e.mid(j + 1), g0r[j] = e.rad(j + 1);
  // Column k of H: grad F(e_k) - grad F(0) (the gradient is affine), with its radius.
  std::vector<double> hm(size * size), hr(size * size);
  for (int k = 0; k < n; ++k) {
    x[k] = 1;
    if (!e.run(x, zero, true)) return {};
    x[k] = 0;
    for (int j = 0; j < n; ++j) {
      const double diff = e.mid(j + 1) - g0m[j];
      hm[std::size_t(j) * n + k] = diff;
      hr[std::size_t(j) * n + k] = (e.rad(j + 1) + g0r[j] + eps * abs(diff)) * (1 + 4 * eps);
    }
  }
  // H is symmetric: its midpoint M, and |H_jk - M_jk| <= hr_jk + |hm_jk - M_jk|.
  std::vector<double> m(hm.size()), radius(hm.size());
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < n; ++k) {
      const std::size_t jk = std::size_t(j) * n + k, kj = std::size_t(k) * n + j;
      m[jk] = (hm[jk] + hm[kj]) / 2;
      radius[jk] = (hr[jk] + abs(hm[jk] - m[jk]) + eps * abs(m[jk])) * (1 + 4 * eps);
    }
  for (int sign : {1, -1}) {
    std::vector<double> signed_ = m;
    for (double& v : signed_) v *= sign;
    double slack = 0;
    if (semidefiniteSlack(n, signed_, radius, slack)) return {sign, slack};
  }
  return {};
}

template class MidRadEvaluator<double>;
template class MidRadEvaluator<Mpfr>;

}  // namespace ndc
