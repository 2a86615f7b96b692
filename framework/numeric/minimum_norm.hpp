/// \file minimum_norm.hpp
/// The minimum-norm solution of an underdetermined linear system J s = f (m <= n), for the
/// Newton steps of the projection: a Householder QR with pivoting of J^T in working storage
/// that is sized once, so a step allocates nothing (Eigen's decompositions of dynamic size
/// allocate and, for the 5 x 7 systems of a surface in R^7, cost several times the arithmetic).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "framework/numeric/iteration.hpp"

namespace ndc {

/// `s = J^+ f` for an m x n matrix J of full row rank m <= n. factor() takes J^T P = Q R
/// (Householder, P choosing at each step the row of J with the largest remaining norm), and
/// declines when a pivot |R_ii| is at most `threshold` times the first one (the rank test of
/// a column-pivoted QR); solve() then gives the minimum-norm solution from R and J.
template <class S>
class MinimumNormSolver {
 public:
  /// Factors J (m x n, row-major); false when its rank is below m by the test above or a norm
  /// is not finite.
  bool factor(const S* jac, int m, int n, const S& threshold) {
    using std::sqrt;
    m_ = m;
    n_ = n;
    const auto size = static_cast<std::size_t>(m) * static_cast<std::size_t>(n);
    a_.assign(jac, jac + size);  // row i of J = column i of J^T
    jac_.assign(jac, jac + size);
    z_.resize(std::size_t(m));
    order_.resize(std::size_t(m));
    beta_.resize(std::size_t(m));
    diag_.resize(std::size_t(m));
    for (int i = 0; i < m; ++i) order_[std::size_t(i)] = i;
    S first = 0;
    for (int i = 0; i < m; ++i) {
      // Pivot: the remaining column of J^T with the largest norm on rows i..n-1.
      int best = i;
      S bestNorm2 = -1;
      for (int c = i; c < m; ++c) {
        const S* v = column(c);
        S norm2 = 0;
        for (int r = i; r < n; ++r) norm2 += v[r] * v[r];
        if (norm2 > bestNorm2) bestNorm2 = norm2, best = c;
      }
      if (best != i) {
        std::swap_ranges(column(i), column(i) + n, column(best));
        std::swap(order_[std::size_t(i)], order_[std::size_t(best)]);
      }
      const S norm = sqrt(bestNorm2);
      if (!isFinite(norm)) return false;
      if (i == 0) first = norm;
      if (!(norm > threshold * first) || !(norm > 0)) return false;
      // Reflector I - beta v v^T mapping the column to alpha e_i; alpha has the opposite sign
      // of v_i, so v_i - alpha does not cancel.
      S* v = column(i);
      const S alpha = v[i] > 0 ? S(-norm) : norm;
      const S vv = 2 * (bestNorm2 - alpha * v[i]);
      v[i] -= alpha;
      beta_[std::size_t(i)] = 2 / vv;
      diag_[std::size_t(i)] = alpha;
      for (int c = i + 1; c < m; ++c) reflect(i, column(c));
    }
    return true;
  }

  /// s = J^T w with R^T R P^T w = P^T f, into `s` (n values); `f` has m values. This is
  /// Q [R^-T P^T f; 0] = J^+ f, formed from the rows of J itself (the seminormal equations of
  /// the minimum-norm problem, analysed by Paige 1973; a Newton step only needs to be accurate
  /// to first order, the iteration corrects the rest): the step lies in J's row space up to
  /// the rounding of one sum, and rows of J that are mirror images of each other give
  /// mirror-image steps, where applying Q's reflectors mixes the coordinates' roundings.
  void solve(const S* f, S* s) {
    const int m = m_, n = n_;
    // R^T z = P^T f (forward), R w' = z (backward), R(t, i) above the diagonal in column i.
    for (int i = 0; i < m; ++i) {
      S sum = f[order_[std::size_t(i)]];
      for (int t = 0; t < i; ++t) sum -= column(i)[t] * z_[std::size_t(t)];
      z_[std::size_t(i)] = sum / diag_[std::size_t(i)];
    }
    for (int i = m - 1; i >= 0; --i) {
      S sum = z_[std::size_t(i)];
      for (int c = i + 1; c < m; ++c) sum -= column(c)[i] * z_[std::size_t(c)];
      z_[std::size_t(i)] = sum / diag_[std::size_t(i)];
    }
    // s = J^T w, w_order[i] = w'_i.
    for (int j = 0; j < n; ++j) s[j] = 0;
    for (int i = 0; i < m; ++i) {
      const S* row = jac_.data() + static_cast<std::size_t>(order_[std::size_t(i)]) * n;
      const S& w = z_[std::size_t(i)];
      for (int j = 0; j < n; ++j) s[j] += row[j] * w;
    }
  }

 private:
  S* column(int c) { return a_.data() + static_cast<std::size_t>(c) * std::size_t(n_); }
  const S* column(int c) const { return a_.data() + static_cast<std::size_t>(c) * std::size_t(n_); }
  /// x <- (I - beta_i v_i v_i^T) x on rows i..n-1, v_i the i-th reflector.
  void reflect(int i, S* x) const {
    const S* v = column(i);
    S dot = 0;
    for (int r = i; r < n_; ++r) dot += v[r] * x[r];
    dot *= beta_[std::size_t(i)];
    for (int r = i; r < n_; ++r) x[r] -= dot * v[r];
  }

  int m_ = 0, n_ = 0;
  std::vector<S> a_, beta_, diag_;  // the reflectors below and R above the diagonal
  std::vector<S> jac_, z_;          // J, and solve's z then w
  std::vector<int> order_;          // P: row order_[i] of J is column i of J^T P
};

}  // namespace ndc
