/// \file jacobian_work.hpp
/// The Jacobian of a system at a point with the factorizations the crossing connection asks of
/// it (a face's local degree, a dual vertex's singularity test), in per-thread storage.
/// Internal to the crossing connection.
#pragma once

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <span>
#include <vector>

#include "framework/numeric/scalar.hpp"
#include "framework/problem/system.hpp"

namespace ndc::crossing_detail {

template <class S>
using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// The Jacobian at a point and its factorizations, in per-thread storage (threadScratch).
template <class S>
struct JacobianWork {
  using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;

  std::vector<S> f, j;
  Matrix full, square, gram;
  Eigen::FullPivLU<Matrix> lu;
  Eigen::JacobiSVD<Matrix> svd;
  Eigen::LLT<Matrix> llt;

  /// The m x n Jacobian of the system at x, into `full`.
  const Matrix& jacobianAt(const System<S>& system, std::span<const S> x) {
    const int m = system.m(), n = system.n();
    f.resize(m), j.resize(std::size_t(m) * n);
    system.evaluate(x, f, j);
    full.resize(m, n);
    for (int r = 0; r < m; ++r) {
      for (int c = 0; c < n; ++c) full(r, c) = j[std::size_t(r) * n + c];
    }
    return full;
  }

  /// Singular values of `full`, largest first.
  const Vector& singularValues() { return svd.compute(full).singularValues(); }

  /// Whether sigma_min(full) > ratio sigma_max(full) clearly: a Cholesky factorization of
  /// J J^T - t I with t = 2 ratio^2 trace(J J^T) >= 2 ratio^2 sigma_max^2 exists, so
  /// sigma_min^2 > t. A tenth of the singular values' cost; false says nothing.
  bool clearlyRegular(const S& ratio) {
    gram.noalias() = full * full.transpose();
    const S t = 2 * ratio * ratio * gram.trace();
    gram.diagonal().array() -= t;
    return t > 0 && llt.compute(gram).info() == Eigen::Success;
  }
};

}  // namespace ndc::crossing_detail
