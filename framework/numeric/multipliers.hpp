/// \file multipliers.hpp
/// The multiplier (Farkas) test of a linearized system over a box: no d with |d_j| <= h_j
/// satisfies |mu_i + (J d)_i| <= rho_i for every i (docs/subdivision.md, "multiplier test").
#pragma once

#include <cstddef>
#include <vector>

#include "framework/numeric/scalar.hpp"

namespace ndc {

/// Index of (row, col) in a row-major matrix with `cols` columns.
inline std::size_t rowMajor(int row, int col, int cols) {
  return static_cast<std::size_t>(row) * static_cast<std::size_t>(cols) +
         static_cast<std::size_t>(col);
}

/// Decides whether the linearized system mu + J d + s = 0, |s_i| <= rho_i, |d_j| <= h_j (m
/// equations, n unknowns) has no solution, by multipliers y in R^m: every solution satisfies
/// y^T (mu + J d + s) = 0, which is impossible when
///
///     |y . mu| > sum_i |y_i| rho_i + sum_j |(J^T y)_j| h_j.
///
/// By Farkas' lemma such a y exists exactly when the system has no solution. The best y
/// minimises the right side over y . mu = 1, a convex piecewise-linear problem, approached by
/// iteratively reweighted least squares: y = W^{-1} mu with
/// W = diag(rho_i / |y'_i|) + J diag(h_j / |(J^T y')_j|) J^T from the previous y' (weights of
/// one at first; a Cholesky factorisation of an m x m matrix per step), while a step gains 1%.
/// Every y is checked with the rounding of its dot products bounded by the relative margin
/// `tol` (at least 2 gamma_p for the longest p-term sum, p = max(m, n)), so an inexact y only
/// keeps a box. The working storage is sized once per shape: excludes() does not allocate in
/// double; use one instance per thread.
template <class S>
class MultiplierTest {
 public:
  /// True when some y proves the system empty. `jac` is m x n row-major; `iterations` caps
  /// the least-squares steps.
  bool excludes(int m, int n, const S* jac, const S* mu, const S* rho, const S* h, const S& tol,
                int iterations);

 private:
  /// y_ = W^{-1} mu for W in the lower triangle of gram_ (Cholesky, in place); false when W is
  /// not numerically positive definite.
  bool solveGram(int m, const S* mu);
  /// The check for the current y_ (fills z_ = J^T y_); `ratio` is the right side over
  /// |y . mu| (the system is excluded iff below 1, up to the margins).
  bool check(int m, int n, const S* jac, const S* mu, const S* rho, const S* h, const S& tol,
             S& ratio);

  std::vector<S> gram_, y_, z_, yWeight_, zWeight_;
};

extern template class MultiplierTest<double>;
extern template class MultiplierTest<Mpfr>;

}  // namespace ndc
