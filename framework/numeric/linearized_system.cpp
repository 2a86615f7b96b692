#include "framework/numeric/linearized_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ndc {

template <class S>
void LinearizedSystem<S>::resize(int n, int m) {
  n_ = n;
  m_ = m;
  // 8 (n + m + 8) eps >= 2 gamma_p for every dot product length p used below (eps = 2u).
  tol_ = S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  const auto nn = static_cast<std::size_t>(n), mm = static_cast<std::size_t>(m);
  const std::size_t k = nn >= mm ? nn - mm : 0;
  jac.assign(mm * nn, S(0));
  mu.assign(mm, S(0));
  rho.assign(mm, S(0));
  h.assign(nn, S(0));
  w_.resize(nn * mm);
  beta_.resize(mm);
  diag_.resize(mm);
  q_.resize(nn * nn);
  p_.resize(mm * mm);
  pj_.resize(mm * nn);
  pjAbs_.resize(mm * nn);
  mig_.resize(mm);
  pinv_.resize(nn * mm);
  a_.resize(nn);
  b_.resize(nn);
  tlo_.resize(k);
  thi_.resize(k);
  witness_.reserve(k);
  inside_.resize(nn);
  // The polygons of 7c and solvesInside: 4 corners, at most one vertex more per clip, up to
  // 4 n clips (clip swaps the buffers, so each gets the largest size).
  polygon_.reserve(2 * (4 + 4 * nn));
  clipped_.reserve(2 * (4 + 4 * nn));
  tight_.reserve(2 * (4 + 4 * nn));
}

template <class S>
bool LinearizedSystem<S>::excludes(const S& hh, int multiplierSteps) {
  kernelReady_ = false;
  insideFound_ = false;
  if (!factorTranspose()) return false;  // 3: J_c (nearly) rank-deficient
  invertLowerFactor();                   // 4
  S migSq = 0;
  if (rowTestExcludes(migSq)) return true;       // 5
  if (ballTestExcludes(migSq, hh)) return true;  // 6
  kernelBounds();                                // 7
  if (kernelPropagationExcludes()) return true;
  if (n_ - m_ == 2 && kernelPolygonExcludes()) return true;
  kernelReady_ = true;
  // 8, unless a d found by steps 7b and 7c solves the linearized system with mid G well inside
  // the box: then no multipliers exist (Farkas), and the boxes around M skip the search.
  return !solvesInside() && multiplierExcludes(multiplierSteps);
}

template <class S>
std::uint64_t LinearizedSystem<S>::emptyHalves() const {
  // Every solution has d_j within b_j - h_j of (N t)_j - a_j (step 7), t in what steps 7b and
  // 7c left: (N t)_j ranges over [lo, hi] there (the polygon's or the interval's end points,
  // the t box's interval product for k > 2). The half d_j >= 0 holds none when
  // hi - a_j + b_j - h_j < 0, with a slack for every rounding here (as facetsMet's).
  if (!kernelReady_ || n_ > 32) return 0;
  const S reach = kernelReach();
  std::uint64_t empty = 0;
  for (int j = 0; j < n_; ++j) {
    S lo, hi;
    const S slack = kernelRange(j, reach, lo, hi);
    const S edge = h[j] - b_[j] - slack;  // <= 0: b_j >= h_j
    if (hi - a_[j] < edge) empty |= std::uint64_t(1) << (2 * j + 1);
    if (a_[j] - lo < edge) empty |= std::uint64_t(1) << (2 * j);
  }
  return empty;
}

template <class S>
bool LinearizedSystem<S>::solutionBox(std::vector<S>& lo, std::vector<S>& hi) const {
  if (!kernelReady_) return false;
  const S reach = kernelReach();
  lo.resize(std::size_t(n_));
  hi.resize(std::size_t(n_));
  for (int j = 0; j < n_; ++j) {
    solutionRange(j, reach, lo[std::size_t(j)], hi[std::size_t(j)]);
    lo[std::size_t(j)] = std::max(lo[std::size_t(j)], -h[j]);
    hi[std::size_t(j)] = std::min(hi[std::size_t(j)], h[j]);
  }
  return true;
}

template <class S>
void LinearizedSystem<S>::solutionRange(int j, const S& reach, S& lo, S& hi) const {
  // As emptyHalves: d_j within b_j - h_j of (N t)_j - a_j, (N t)_j in [tLo, tHi].
  S tLo, tHi;
  const S slack = kernelRange(j, reach, tLo, tHi);
  const S spread = b_[j] - h[j] + slack;  // >= 0: b_j >= h_j
  lo = tLo - a_[j] - spread;
  hi = tHi - a_[j] + spread;
}

template <class S>
S LinearizedSystem<S>::kernelReach() const {
  using std::abs;
  S reach = 0;
  if (n_ - m_ == 2) {
    for (const S& v : polygon_) reach = std::max(reach, abs(v));
  } else {
    for (int p = 0; p < n_ - m_; ++p) reach = std::max({reach, abs(tlo_[p]), abs(thi_[p])});
  }
  return reach;
}

template <class S>
S LinearizedSystem<S>::kernelRange(int j, const S& reach, S& lo, S& hi) const {
  // (N t)_j over the polygon's vertices (a linear function takes its extremes there), else the
  // interval product over the t box.
  using std::abs;
  const int k = n_ - m_;
  S weight = 0;
  lo = hi = 0;
  if (k == 2) {
    lo = std::numeric_limits<S>::infinity(), hi = -lo;
    for (std::size_t v = 0; v < polygon_.size() / 2; ++v) {
      const S value = nul(j, 0) * polygon_[2 * v] + nul(j, 1) * polygon_[2 * v + 1];
      lo = std::min(lo, value);
      hi = std::max(hi, value);
    }
  } else {
    for (int p = 0; p < k; ++p) {
      const S& u = nul(j, p);
      lo += std::min(u * tlo_[p], u * thi_[p]);
      hi += std::max(u * tlo_[p], u * thi_[p]);
    }
  }
  for (int p = 0; p < k; ++p) weight += abs(nul(j, p));
  // Generous against every rounding here and in the caller's comparisons with h_j and b_j.
  return 8 * tol_ * (abs(a_[j]) + b_[j] + h[j] + weight * reach);
}

template <class S>
bool LinearizedSystem<S>::solvesInside() {
  // d = N t - a for t = 0 (d = -J^+ mid G), else for a point of the region of t whose d lies
  // in the box shrunk by the margin: the strips |(N t)_j - a_j| <= h_j (1 - 1e-6) cut out of
  // what steps 7b and 7c left (the centre of the interval for k = 1, the mean of the
  // polygon's vertices for k = 2, the centre of the t box for k > 2, untightened).
  using std::abs;
  const int n = n_, k = n_ - m_;
  const S inside = S(1) - S(1e-6);
  const auto insideAt = [&](const S* t) {
    for (int j = 0; j < n; ++j) {
      S d = -a_[j];
      for (int p = 0; p < k && t; ++p) d += nul(j, p) * t[p];
      if (!(abs(d) < h[j] * inside)) return false;
      inside_[std::size_t(j)] = d;
    }
    insideFound_ = true;
    return true;
  };
  if (insideAt(nullptr)) return true;
  if (k == 0) return false;
  witness_.assign(static_cast<std::size_t>(k), S(0));
  if (k == 1) {
    S lo = tlo_[0], hi = thi_[0];
    for (int j = 0; j < n && lo <= hi; ++j) {
      const S& u = nul(j, 0);
      if (u == 0) continue;
      const S a = (a_[j] - h[j] * inside) / u, b = (a_[j] + h[j] * inside) / u;
      lo = std::max(lo, std::min(a, b));
      hi = std::min(hi, std::max(a, b));
    }
    if (!(lo <= hi)) return false;
    witness_[0] = (lo + hi) / 2;
  } else if (k == 2) {
    // The mean of step 7c's vertices first (its strips are those shrunk, widened by the
    // linearisation's terms, and usually both hold it), then of the shrunk strips' polygon.
    const auto mean = [&](const std::vector<S>& polygon) {
      const std::size_t count = polygon.size() / 2;
      witness_[0] = witness_[1] = 0;
      for (std::size_t v = 0; v < count; ++v) {
        witness_[0] += polygon[2 * v];
        witness_[1] += polygon[2 * v + 1];
      }
      witness_[0] /= S(count);
      witness_[1] /= S(count);
    };
    if (polygon_.empty()) return false;
    mean(polygon_);
    if (insideAt(witness_.data())) return true;
    tight_ = polygon_;
    for (int j = 0; j < n; ++j) {
      const S& u0 = nul(j, 0);
      const S& u1 = nul(j, 1);
      if (u0 == 0 && u1 == 0) continue;
      if (!clipStrip(tight_, u0, u1, a_[j] + h[j] * inside, h[j] * inside - a_[j])) return false;
    }
    mean(tight_);
  } else {
    for (int p = 0; p < k; ++p) witness_[std::size_t(p)] = (tlo_[p] + thi_[p]) / 2;
  }
  return insideAt(witness_.data());
}

template <class S>
bool LinearizedSystem<S>::factorTranspose() {
  // 3. Householder QR of J_c^T (n x m, column i = row i of J_c): J_c^T = Q [R; 0]. A pivot
  // below 1e-10 of the largest row norm means J_c is (nearly) rank-deficient: keep the box.
  using std::isfinite;
  using std::sqrt;
  const int n = n_, m = m_;
  std::copy(jac.begin(), jac.end(), w_.begin());
  S scale = 0;
  for (int i = 0; i < m; ++i) {
    S s = 0;
    for (int j = 0; j < n; ++j) s += jac[rowMajor(i, j, n)] * jac[rowMajor(i, j, n)];
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
void LinearizedSystem<S>::reflect(int i, S* x) const {
  // x <- (I - beta_i v_i v_i^T) x on rows i..n-1, v_i the i-th reflector (column i of w_).
  const S* v = &w_[rowMajor(i, 0, n_)];
  S s = 0;
  for (int r = i; r < n_; ++r) s += v[r] * x[r];
  s *= beta_[i];
  for (int r = i; r < n_; ++r) x[r] -= s * v[r];
}

template <class S>
void LinearizedSystem<S>::invertLowerFactor() {
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
bool LinearizedSystem<S>::rowTestExcludes(S& migSq) {
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
        s += p_[rowMajor(i, t, m)] * jac[rowMajor(t, j, n)];
        sa += abs(p_[rowMajor(i, t, m)]) * abs(jac[rowMajor(t, j, n)]);
      }
      pj_[rowMajor(i, j, n)] = s;
      pjAbs_[rowMajor(i, j, n)] = sa;
    }
  for (int i = 0; i < m; ++i) {
    S v = 0, va = 0, vr = 0;  // (P mu)_i, (|P| |mu|)_i, (|P| rho)_i
    for (int t = 0; t <= i; ++t) {
      v += p_[rowMajor(i, t, m)] * mu[t];
      va += abs(p_[rowMajor(i, t, m)]) * abs(mu[t]);
      vr += abs(p_[rowMajor(i, t, m)]) * rho[t];
    }
    // A lower bound of |(P g)_i| over g in G (the last term covers the roundings here).
    const S absV = abs(v);
    S mig = absV - tol * va - vr - tol * (absV + va + vr);
    if (!(mig > 0)) mig = 0;
    mig_[i] = mig;
    S reach = 0;  // upper bound of sum_j |(P J_c)_ij| h_j
    for (int j = 0; j < n; ++j)
      reach += (abs(pj_[rowMajor(i, j, n)]) + tol * pjAbs_[rowMajor(i, j, n)]) * h[j];
    if (mig > reach * up) return true;
    migSq += mig * mig;
  }
  return false;
}

template <class S>
bool LinearizedSystem<S>::ballTestExcludes(const S& migSq, const S& hh) const {
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
void LinearizedSystem<S>::kernelBounds() {
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
      a += pv * mu[t];
      aa += abs(pv) * abs(mu[t]);
      ar += abs(pv) * rho[t];
    }
    S dh = 0;  // (|D| h)_j with D's rounding error bound
    for (int l = 0; l < n; ++l) {
      S d = j == l ? S(1) : S(0), da = d;
      for (int t = 0; t < m; ++t) {
        d -= pinv_[rowMajor(j, t, m)] * jac[rowMajor(t, l, n)];
        da += abs(pinv_[rowMajor(j, t, m)]) * abs(jac[rowMajor(t, l, n)]);
      }
      for (int p = 0; p < k; ++p) {
        d -= nul(j, p) * nul(l, p);
        da += abs(nul(j, p)) * abs(nul(l, p));
      }
      dh += (abs(d) + tol * da) * h[l];
    }
    a_[j] = a;
    b_[j] = (h[j] + ar + dh + tol * (2 * aa + ar + dh)) * up;
  }
}

template <class S>
bool LinearizedSystem<S>::kernelPropagationExcludes() {
  // Propagate the constraints on t over the box |t_p| <= sum_j |N_jp| h_j; for k = 1 a single
  // sweep intersects n intervals and is exact.
  using std::abs;
  const int n = n_, k = n_ - m_;
  const S& tol = tol_;
  for (int p = 0; p < k; ++p) {
    S tau = 0;
    for (int j = 0; j < n; ++j) tau += abs(nul(j, p)) * h[j];
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
bool LinearizedSystem<S>::narrowKernelBox(int j, int p) {
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
bool LinearizedSystem<S>::kernelPolygonExcludes() {
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
  for (int j = 0; j < n; ++j) {
    const S& u0 = nul(j, 0);
    const S& u1 = nul(j, 1);
    if (u0 == 0 && u1 == 0) continue;  // decided by the propagation
    const S slack = 4 * tol * (abs(a_[j]) + b_[j] + (abs(u0) + abs(u1)) * reach);
    if (!clipStrip(polygon_, u0, u1, a_[j] + b_[j] + slack, b_[j] - a_[j] + slack)) return true;
  }
  return false;
}

template <class S>
bool LinearizedSystem<S>::clipStrip(std::vector<S>& polygon, const S& u0, const S& u1,
                                    const S& upper, const S& lower) {
  // Most strips hold the whole polygon: one pass shows it (with clip's own expressions, so a
  // strip it keeps whole is one clip would keep whole), else the two clips.
  const S v0 = -u0, v1 = -u1;
  const std::size_t count = polygon.size() / 2;
  bool whole = true;
  for (std::size_t v = 0; v < count && whole; ++v) {
    const S& x = polygon[2 * v];
    const S& y = polygon[2 * v + 1];
    whole = u0 * x + u1 * y - upper <= 0 && v0 * x + v1 * y - lower <= 0;
  }
  if (whole) return count > 0;
  return clip(polygon, u0, u1, upper) && clip(polygon, v0, v1, lower);
}

template <class S>
bool LinearizedSystem<S>::clip(std::vector<S>& polygon, const S& u0, const S& u1, const S& bound) {
  // Sutherland-Hodgman against one half-plane, through clipped_.
  clipped_.clear();
  const std::size_t count = polygon.size() / 2;
  for (std::size_t v = 0; v < count; ++v) {
    const std::size_t w = (v + 1) % count;
    const S& x0 = polygon[2 * v];
    const S& y0 = polygon[2 * v + 1];
    const S& x1 = polygon[2 * w];
    const S& y1 = polygon[2 * w + 1];
    const S s0 = u0 * x0 + u1 * y0 - bound, s1 = u0 * x1 + u1 * y1 - bound;
    if (s0 <= 0) {
      clipped_.push_back(x0);
      clipped_.push_back(y0);
    }
    if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
      const S f = s0 / (s0 - s1);
      clipped_.push_back(x0 + f * (x1 - x0));
      clipped_.push_back(y0 + f * (y1 - y0));
    }
  }
  polygon.swap(clipped_);
  return !polygon.empty();
}

template <class S>
bool LinearizedSystem<S>::multiplierExcludes(int steps) {
  // 8. The multiplier test on the linearized system (framework/numeric/multipliers.hpp).
  return multipliers_.excludes(m_, n_, jac.data(), mu.data(), rho.data(), h.data(), tol_, steps);
}

template <class S>
bool LinearizedSystem<S>::facetsMet(std::vector<char>& met) {
  // Steps 3, 4 and 7; on facet d_j = +h_j every solution has (N t)_j - a_j within
  // b_j - h_j of h_j (step 7's bound with |d_j| = h_j exactly), so the facet needs a t in the
  // polygon with (N t)_j - a_j >= 2 h_j - b_j (mirrored for -h_j). The polygon is relaxed
  // around every solution (kernelPolygonExcludes), so the largest value of (N t)_j over its
  // vertices, plus its rounding, bounds that of every solution.
  met.assign(2 * static_cast<std::size_t>(n_), 1);
  if (n_ - m_ != 2 || !factorTranspose()) return false;
  invertLowerFactor();
  kernelBounds();
  if (kernelPropagationExcludes() || kernelPolygonExcludes()) {
    std::fill(met.begin(), met.end(), 0);
    return true;
  }
  const S reach = kernelReach();
  for (int j = 0; j < n_; ++j) {
    S lo, hi;
    const S edge = 2 * h[j] - b_[j] - kernelRange(j, reach, lo, hi);
    met[2 * std::size_t(j) + 1] = hi - a_[j] >= edge;
    met[2 * std::size_t(j)] = a_[j] - lo >= edge;
  }
  return false;
}

template class LinearizedSystem<double>;
template class LinearizedSystem<Mpfr>;

}  // namespace ndc
