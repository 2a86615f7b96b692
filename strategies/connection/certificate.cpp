#include "strategies/connection/certificate.hpp"

#include "framework/core/iteration.hpp"
#include "framework/core/parallel.hpp"

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <algorithm>
#include <numeric>
#include <optional>
#include <type_traits>

namespace ndc {

template <class S>
Interval<S> derivativeHull(const Bernstein<S>& p, int axis, const S& margin) {
  using I = Interval<S>;
  const int d = p.degree(axis);
  if (d == 0) return I(S(0));
  const std::size_t stride = p.stride(axis), size = p.size();
  const auto c = p.coefficients();
  S lo = 0, hi = 0;
  bool first = true;
  // Every coefficient but the last along the axis, in index order: blocks of (d + 1) strides,
  // of which the first d (no integer division per coefficient: this runs over 3^n of them).
  const std::size_t block = stride * std::size_t(d + 1), span = stride * std::size_t(d);
  for (std::size_t b = 0; b < size; b += block) {
    for (std::size_t i = b; i < b + span; ++i) {
      const S diff = c[i + stride] - c[i];
      if (first || diff < lo) lo = diff;
      if (first || diff > hi) hi = diff;
      first = false;
    }
  }
  // Two coefficient errors, and the rounding of the difference itself (below one margin).
  const S widen = 3 * margin;
  const Box<S>& box = p.domain();
  if constexpr (std::is_same_v<S, double>)  // one rounding-mode switch, the same bounds
    return scaledQuotient(I(lo - widen, hi + widen), double(d), box.hi[axis] - box.lo[axis]);
  else
    return (I(lo - widen, hi + widen) * I(S(d))).dividedBy(box.hi[axis] - box.lo[axis]);
}

template <class S>
bool clearsRange(const Bernstein<S>& p, const S& a, const S& b, const S& margin) {
  const auto [lo, hi] = p.coefficientRange();
  return lo > b + margin || hi < a - margin;
}

template <class S>
bool combinationExcludes(const System<S>& system, std::span<const S> level, const Box<S>& box,
                         std::span<const Interval<S>> jacobian, std::span<const int> axes) {
  using I = Interval<S>;
  const int m = system.m(), n = system.n(), a = static_cast<int>(axes.size());
  // lambda: the direction of the normal space most nearly orthogonal to the box's free axes.
  Eigen::MatrixXd mid(m, a);
  for (int i = 0; i < m; ++i) {
    for (int t = 0; t < a; ++t)
      mid(i, t) = toDouble(jacobian[std::size_t(i) * n + axes[t]].midpoint());
  }
  Eigen::VectorXd lambda = Eigen::VectorXd::Ones(m);
  if (m > 1)
    lambda = Eigen::JacobiSVD<Eigen::MatrixXd>(mid, Eigen::ComputeFullU).matrixU().col(m - 1);
  if (!lambda.allFinite()) return false;
  // g(x0) at the box's midpoint, in point intervals.
  std::vector<I> x0;
  for (int j = 0; j < n; ++j) x0.emplace_back((box.lo[j] + box.hi[j]) / 2);
  I g(S(0));
  for (int i = 0; i < m; ++i) {
    if (lambda(i) == 0) continue;
    g += I(S(lambda(i))) *
         (system.equations()[i].template evaluate<S>(std::span<const I>(x0)) - I(level[i]));
  }
  // Plus the enclosure of the first-order change along each free axis.
  for (int j : axes) {
    I slope(S(0));
    for (int i = 0; i < m; ++i) slope += I(S(lambda(i))) * jacobian[std::size_t(i) * n + j];
    I step(box.lo[j], box.hi[j]);
    step -= x0[j];
    slope *= step;
    g += slope;
  }
  return !g.containsZero();
}

namespace {

/// GraphTest::graph's working storage (threadScratch).
template <class S>
struct GraphWork {
  using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  Matrix mid;
  Eigen::ColPivHouseholderQR<Matrix> qr;
  std::vector<int> columns, pick;
};

/// GraphTest::regularSquare's working storage (threadScratch).
template <class S>
struct SquareWork {
  std::vector<S> mid, inverse;  ///< m x m, column-major
};

/// Y ~ A^-1 for the m x m matrix `a` (column-major, overwritten) into `y` (column-major) by
/// Gauss-Jordan elimination with partial pivoting; false when a pivot is 0, not finite, or at
/// most m eps times the largest |entry| (A numerically singular). Y is only the
/// preconditioner of the graph test, which checks ||I - Y A|| < 1 itself, so how Y is computed
/// does not affect what the test proves.
template <class S>
bool invertMidpoint(int m, std::vector<S>& a, std::vector<S>& y) {
  using std::abs;
  const auto at = [m](std::vector<S>& v, int i, int j) -> S& {
    return v[std::size_t(j) * std::size_t(m) + std::size_t(i)];
  };
  S largest = 0;
  for (const S& v : a) largest = std::max<S>(largest, abs(v));
  const S floor = S(m) * ScalarTraits<S>::epsilon() * largest;
  y.assign(std::size_t(m) * std::size_t(m), S(0));
  for (int i = 0; i < m; ++i) at(y, i, i) = 1;
  for (int k = 0; k < m; ++k) {
    int p = k;
    for (int i = k + 1; i < m; ++i)
      if (abs(at(a, i, k)) > abs(at(a, p, k))) p = i;
    const S pivot = at(a, p, k);
    if (!(abs(pivot) > floor) || !isFinite(pivot)) return false;
    if (p != k)
      for (int j = 0; j < m; ++j)
        std::swap(at(a, p, j), at(a, k, j)), std::swap(at(y, p, j), at(y, k, j));
    // Row k scaled to a unit pivot, then eliminated from every other row.
    for (int j = 0; j < m; ++j) at(a, k, j) /= pivot, at(y, k, j) /= pivot;
    for (int i = 0; i < m; ++i) {
      if (i == k) continue;
      const S factor = at(a, i, k);
      if (factor == 0) continue;
      for (int j = 0; j < m; ++j) {
        at(a, i, j) -= factor * at(a, k, j);
        at(y, i, j) -= factor * at(y, k, j);
      }
    }
  }
  return true;
}

}  // namespace

template <class S>
bool GraphTest<S>::graph(std::span<const Interval<S>> jacobian, std::span<const int> axes) {
  const int a = static_cast<int>(axes.size());
  if (a < m_) return false;
  std::optional<GraphWork<S>> fresh;
  GraphWork<S>& w = threadScratch<S, GraphWork<S>>(fresh);
  // The m pivot columns of the midpoint Jacobian first: the best conditioned block.
  auto& mid = w.mid;
  mid.resize(m_, a);
  for (int i = 0; i < m_; ++i) {
    for (int t = 0; t < a; ++t) mid(i, t) = jacobian[std::size_t(i) * n_ + axes[t]].midpoint();
  }
  const auto& qr = w.qr.compute(mid);
  std::vector<int>& columns = w.columns;
  columns.clear();
  for (int t = 0; t < m_; ++t) columns.push_back(axes[qr.colsPermutation().indices()(t)]);
  if (regular(jacobian, columns)) return true;
  // A graph over the midpoint tangent space, which no coordinate block may be well placed for.
  if (tangentGraph(jacobian, axes)) return true;
  // Every other block: choose which a - m axes to drop.
  const int drop = a - m_;
  std::vector<int>& pick = w.pick;
  pick.resize(drop);
  std::iota(pick.begin(), pick.end(), 0);
  while (true) {
    columns.clear();
    for (int t = 0; t < a; ++t) {
      if (std::find(pick.begin(), pick.end(), t) == pick.end()) columns.push_back(axes[t]);
    }
    if (regular(jacobian, columns)) return true;
    int p = drop - 1;  // the next combination of `drop` out of `a`
    while (p >= 0 && pick[p] == a - drop + p) --p;
    if (p < 0) return false;
    ++pick[p];
    for (int q = p + 1; q < drop; ++q) pick[q] = pick[q - 1] + 1;
  }
}

template <class S>
bool GraphTest<S>::tangentGraph(std::span<const Interval<S>> jacobian,
                                std::span<const int> axes) const {
  using I = Interval<S>;
  using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  const int a = static_cast<int>(axes.size()), d = a - m_;
  if (d == 0) return false;  // the one block was tried
  Matrix mid(m_, a);
  for (int i = 0; i < m_; ++i) {
    for (int t = 0; t < a; ++t) mid(i, t) = jacobian[std::size_t(i) * n_ + axes[t]].midpoint();
  }
  // T: the orthogonal complement of the midpoint's row space, the last d columns of Q in the
  // QR factorization of its transpose. Any T would do (its entries are exact numbers in the
  // test); this one makes [J; T^T] best conditioned near the midpoint.
  const Eigen::HouseholderQR<Matrix> qr(mid.transpose());
  const Matrix q = qr.householderQ();
  // The square interval matrix [J over the axes; T^T], row-major.
  std::vector<I> square(std::size_t(a) * a);
  for (int i = 0; i < m_; ++i) {
    for (int t = 0; t < a; ++t)
      square[std::size_t(i) * a + t] = jacobian[std::size_t(i) * n_ + axes[t]];
  }
  for (int r = 0; r < d; ++r) {
    for (int t = 0; t < a; ++t) square[std::size_t(m_ + r) * a + t] = I(S(q(t, m_ + r)));
  }
  std::vector<int> all(a);
  std::iota(all.begin(), all.end(), 0);
  return regularSquare(a, square, a, all);
}

template <class S>
bool GraphTest<S>::regular(std::span<const Interval<S>> jacobian,
                           std::span<const int> columns) const {
  return regularSquare(m_, jacobian, std::size_t(n_), columns);
}

template <class S>
bool GraphTest<S>::regularSquare(int m, std::span<const Interval<S>> matrix, std::size_t stride,
                                 std::span<const int> columns) {
  using I = Interval<S>;
  const auto entry = [&](int i, int t) -> const I& {
    return matrix[std::size_t(i) * stride + columns[t]];
  };
  if (m == 1) return !entry(0, 0).containsZero();
  std::optional<SquareWork<S>> fresh;
  SquareWork<S>& w = threadScratch<S, SquareWork<S>>(fresh);
  auto& mid = w.mid;
  mid.resize(std::size_t(m) * std::size_t(m));
  for (int i = 0; i < m; ++i) {
    for (int t = 0; t < m; ++t) mid[std::size_t(t) * m + i] = entry(i, t).midpoint();
  }
  auto& y = w.inverse;
  if (!invertMidpoint(m, mid, y)) return false;
  // || I - Y A ||_inf < 1, every entry enclosed with outward rounding; in double, one kernel
  // with one rounding-mode switch (the same bounds; the switches were most of this test's time).
  if constexpr (std::is_same_v<S, double>) {
    const double norm = identityResidualNorm(m, std::span<const double>(y.data(), y.size()), matrix,
                                             stride, columns);
    return norm < 1;
  }
  for (int i = 0; i < m; ++i) {
    I row(S(0));
    for (int j = 0; j < m; ++j) {
      I r(S(i == j ? 1 : 0));
      for (int l = 0; l < m; ++l) r -= I(y[std::size_t(l) * m + i]) * entry(l, j);
      using std::abs;
      row += I(std::max<S>(abs(r.lower()), abs(r.upper())));
    }
    if (!(row.upper() < 1)) return false;
  }
  return true;
}

template Interval<double> derivativeHull(const Bernstein<double>&, int, const double&);
template Interval<Mpfr> derivativeHull(const Bernstein<Mpfr>&, int, const Mpfr&);
template bool clearsRange(const Bernstein<double>&, const double&, const double&, const double&);
template bool clearsRange(const Bernstein<Mpfr>&, const Mpfr&, const Mpfr&, const Mpfr&);
template bool combinationExcludes(const System<double>&, std::span<const double>,
                                  const Box<double>&, std::span<const Interval<double>>,
                                  std::span<const int>);
template bool combinationExcludes(const System<Mpfr>&, std::span<const Mpfr>, const Box<Mpfr>&,
                                  std::span<const Interval<Mpfr>>, std::span<const int>);
template class GraphTest<double>;
template class GraphTest<Mpfr>;

}  // namespace ndc
