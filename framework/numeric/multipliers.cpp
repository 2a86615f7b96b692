#include "framework/numeric/multipliers.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace ndc {

template <class S>
bool MultiplierTest<S>::excludes(int m, int n, const S* jac, const S* mu, const S* rho, const S* h,
                                 const S& tol, int iterations) {
  // Each step minimises y^T W y = sum_i rho_i y_i^2 / |y'_i| + sum_j h_j (J^T y)_j^2 /
  // |(J^T y')_j| over y . mu = 1 (y' the previous step's y), whose minimiser is W^{-1} mu up to
  // its scale; the weights make y^T W y equal the test's right side at y = y'.
  using std::abs;
  gram_.resize(std::size_t(m) * std::size_t(m));
  y_.resize(std::size_t(m));
  z_.resize(std::size_t(n));
  yWeight_.assign(std::size_t(m), S(1));
  zWeight_.assign(std::size_t(n), S(1));
  S best = std::numeric_limits<double>::infinity();
  for (int step = 0; step < iterations; ++step) {
    for (int i = 0; i < m; ++i)
      for (int t = 0; t <= i; ++t) {
        S s = i == t ? rho[i] / yWeight_[i] : S(0);
        for (int j = 0; j < n; ++j)
          s += jac[rowMajor(i, j, n)] * jac[rowMajor(t, j, n)] * h[j] / zWeight_[j];
        gram_[rowMajor(i, t, m)] = s;
      }
    if (!solveGram(m, mu)) return false;
    S ratio;
    if (check(m, n, jac, mu, rho, h, tol, ratio)) return true;
    // Stop when a step gains under 1%: the least-squares steps have converged.
    if (!(ratio < best * S(0.99))) return false;
    best = ratio;
    S yMax = 0, zMax = 0;
    for (int i = 0; i < m; ++i) yMax = std::max(yMax, S(abs(y_[i])));
    for (int j = 0; j < n; ++j) zMax = std::max(zMax, S(abs(z_[j])));
    if (!(yMax > 0) || !(zMax > 0)) return false;
    const S floor = S(1e-8);
    for (int i = 0; i < m; ++i) yWeight_[i] = std::max(S(abs(y_[i])), yMax * floor);
    for (int j = 0; j < n; ++j) zWeight_[j] = std::max(S(abs(z_[j])), zMax * floor);
  }
  return false;
}

template <class S>
bool MultiplierTest<S>::solveGram(int m, const S* mu) {
  using std::sqrt;
  for (int i = 0; i < m; ++i) {
    for (int t = 0; t <= i; ++t) {
      S s = gram_[rowMajor(i, t, m)];
      for (int l = 0; l < t; ++l) s -= gram_[rowMajor(i, l, m)] * gram_[rowMajor(t, l, m)];
      if (i == t) {
        if (!(s > 0)) return false;
        gram_[rowMajor(i, i, m)] = sqrt(s);
      } else {
        gram_[rowMajor(i, t, m)] = s / gram_[rowMajor(t, t, m)];
      }
    }
  }
  for (int i = 0; i < m; ++i) {  // L v = mu
    S s = mu[i];
    for (int l = 0; l < i; ++l) s -= gram_[rowMajor(i, l, m)] * y_[l];
    y_[i] = s / gram_[rowMajor(i, i, m)];
  }
  for (int i = m - 1; i >= 0; --i) {  // L^T y = v
    S s = y_[i];
    for (int l = i + 1; l < m; ++l) s -= gram_[rowMajor(l, i, m)] * y_[l];
    y_[i] = s / gram_[rowMajor(i, i, m)];
  }
  return true;
}

template <class S>
bool MultiplierTest<S>::check(int m, int n, const S* jac, const S* mu, const S* rho, const S* h,
                              const S& tol, S& ratio) {
  // A lower bound of |y . g| over g in mu +- rho against an upper bound of
  // sum_j |(J^T y)_j| h_j, each dot product's rounding bounded by tol times its magnitude.
  using std::abs;
  const S up = S(1) + tol;
  S v = 0, va = 0, vr = 0;  // y . mu, |y| . |mu|, |y| . rho
  for (int i = 0; i < m; ++i) {
    v += y_[i] * mu[i];
    va += abs(y_[i]) * abs(mu[i]);
    vr += abs(y_[i]) * rho[i];
  }
  S reach = 0;
  for (int j = 0; j < n; ++j) {
    S z = 0, za = 0;
    for (int i = 0; i < m; ++i) {
      z += y_[i] * jac[rowMajor(i, j, n)];
      za += abs(y_[i]) * abs(jac[rowMajor(i, j, n)]);
    }
    z_[j] = z;
    reach += (abs(z) + tol * za) * h[j];
  }
  const S absV = abs(v);
  const S mig = absV - tol * va - vr - tol * (absV + va + vr);
  ratio = absV > 0 ? S((vr + reach) / absV) : S(std::numeric_limits<double>::infinity());
  return mig > reach * up;
}

template class MultiplierTest<double>;
template class MultiplierTest<Mpfr>;

}  // namespace ndc
