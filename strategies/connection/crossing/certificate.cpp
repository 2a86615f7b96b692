#include "strategies/connection/crossing/certificate.hpp"

#include "framework/numeric/inverse.hpp"
#include "framework/numeric/parallel.hpp"

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <algorithm>
#include <limits>
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
  std::vector<S> mid;  ///< m x a, column-major
  std::vector<int> order, columns, pick;
};

/// The order in which a Householder QR with column pivoting takes the columns of the m x a
/// matrix `w` (column-major, overwritten): at each step the column with the largest norm below
/// the rows already reduced. Its first m entries are the best conditioned block it finds.
template <class S>
void pivotColumns(int m, int a, std::vector<S>& w, std::vector<int>& order) {
  using std::sqrt;
  const auto column = [&](int c) { return w.data() + std::size_t(c) * std::size_t(m); };
  order.resize(std::size_t(a));
  std::iota(order.begin(), order.end(), 0);
  for (int i = 0; i < std::min(m, a); ++i) {
    int best = i;
    S bestNorm2 = -1;
    for (int c = i; c < a; ++c) {
      S norm2 = 0;
      for (int r = i; r < m; ++r) norm2 += column(c)[r] * column(c)[r];
      if (norm2 > bestNorm2) bestNorm2 = norm2, best = c;
    }
    if (best != i) {
      std::swap_ranges(column(i), column(i) + m, column(best));
      std::swap(order[std::size_t(i)], order[std::size_t(best)]);
    }
    if (!(bestNorm2 > 0)) return;  // the rest is zero (or not finite): any order will do
    // Reflector on rows i..m-1 of column i, applied to the columns after it.
    S* v = column(i);
    const S norm = sqrt(bestNorm2);
    const S alpha = v[i] > 0 ? S(-norm) : norm;
    const S beta = 2 / (2 * (bestNorm2 - alpha * v[i]));
    v[i] -= alpha;
    for (int c = i + 1; c < a; ++c) {
      S* x = column(c);
      S dot = 0;
      for (int r = i; r < m; ++r) dot += v[r] * x[r];
      dot *= beta;
      for (int r = i; r < m; ++r) x[r] -= dot * v[r];
    }
  }
}

/// GraphTest::regularSquare's working storage (threadScratch).
template <class S>
struct SquareWork {
  std::vector<S> mid, inverse;  ///< m x m, column-major
};

}  // namespace

template <class S>
bool GraphTest<S>::graph(std::span<const Interval<S>> jacobian, std::span<const int> axes) {
  const int a = static_cast<int>(axes.size());
  if (a < m_) return false;
  std::optional<GraphWork<S>> fresh;
  GraphWork<S>& w = threadScratch<S, GraphWork<S>>(fresh);
  // The m pivot columns of the midpoint Jacobian first: the best conditioned block.
  auto& mid = w.mid;
  mid.resize(std::size_t(m_) * std::size_t(a));
  for (int i = 0; i < m_; ++i) {
    for (int t = 0; t < a; ++t)
      mid[std::size_t(t) * m_ + i] = jacobian[std::size_t(i) * n_ + axes[t]].midpoint();
  }
  pivotColumns(m_, a, mid, w.order);
  std::vector<int>& columns = w.columns;
  columns.clear();
  for (int t = 0; t < m_; ++t) columns.push_back(axes[w.order[std::size_t(t)]]);
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

namespace {

/// GraphTest::facetGraphs' working storage (threadScratch).
template <class S>
struct FacetWork {
  std::vector<S> mid, square, inverse;  ///< m x n and m x m, column-major
  std::vector<S> zc, zr;                ///< Z = Y J: centres and radii, m x n, row-major
  std::vector<int> order;
};

/// Z = Y J in midpoint-radius form into w.zc, w.zr, with Y the inverse of the midpoint of B,
/// the m pivot columns of J (w.order: B first, the other columns after); false when B is
/// singular.
template <class S>
bool preconditioned(int m, int n, std::span<const Interval<S>> jacobian, FacetWork<S>& w) {
  using std::abs;
  const auto mm = std::size_t(m), nn = std::size_t(n);
  // B: the m pivot columns of the midpoint Jacobian (the best conditioned block).
  w.mid.resize(mm * nn);
  for (std::size_t i = 0; i < mm; ++i) {
    for (std::size_t j = 0; j < nn; ++j) w.mid[j * mm + i] = jacobian[i * nn + j].midpoint();
  }
  pivotColumns(m, n, w.mid, w.order);
  const std::vector<int>& order = w.order;  // B = order[0, m), the others after
  w.square.resize(mm * mm);
  for (std::size_t i = 0; i < mm; ++i) {
    for (std::size_t t = 0; t < mm; ++t)
      w.square[t * mm + i] = jacobian[i * nn + std::size_t(order[t])].midpoint();
  }
  if (!invertGaussJordan(m, w.square, w.inverse)) return false;
  // Z = Y J in midpoint-radius form: centre Y mid J, radius |Y| rad J plus the sums' rounding
  // (gamma of their magnitude; the same margin as the leaf model's).
  const S eps = ScalarTraits<S>::epsilon();
  const S gamma = S(8 * (n + m + 8)) * eps;
  const S tiny = S(std::numeric_limits<double>::min());
  const S up = S(1) + gamma;
  w.zc.resize(mm * nn);
  w.zr.resize(mm * nn);
  for (std::size_t i = 0; i < mm; ++i) {
    for (std::size_t j = 0; j < nn; ++j) {
      S centre = 0, magnitude = 0, radius = 0;
      for (std::size_t l = 0; l < mm; ++l) {
        const S y = w.inverse[l * mm + i];
        const Interval<S>& a = jacobian[l * nn + j];
        const S mid = a.midpoint();
        const S rad = std::max<S>(a.upper() - mid, mid - a.lower()) * (S(1) + 2 * eps);
        centre += y * mid;
        magnitude += abs(y * mid);
        radius += abs(y) * rad;
      }
      w.zc[i * nn + j] = centre;
      w.zr[i * nn + j] = radius * up + gamma * magnitude + tiny;
    }
  }
  return true;
}

}  // namespace

template <class S>
std::uint64_t GraphTest<S>::facetGraphs(std::span<const Interval<S>> jacobian,
                                        std::uint64_t wanted) {
  using std::abs;
  const int m = m_, n = n_;
  if (n > 64 || m < 1 || n <= m || wanted == 0) return 0;
  const auto nn = std::size_t(n);
  std::optional<FacetWork<S>> fresh;
  FacetWork<S>& w = threadScratch<S, FacetWork<S>>(fresh);
  if (!preconditioned(m, n, jacobian, w)) return 0;
  const std::vector<int>& order = w.order;  // B = order[0, m), the others after
  const S eps = ScalarTraits<S>::epsilon();
  const S gamma = S(8 * (n + m + 8)) * eps;
  const S tiny = S(std::numeric_limits<double>::min());
  const S up = S(1) + gamma;
  // Row i of I - T summed over the block's columns below one, T's entry (i, t) in centre c +-
  // radius r: sum |delta - c| + r, rounded up with gamma of the terms' magnitude.
  const auto rowBelowOne = [&](const auto& entry, int i, int p, int u) {
    S sum = 0, magnitude = 0;
    for (int t = 0; t < m; ++t) {
      const int column = t == p ? u : order[std::size_t(t)];
      S c, r;
      entry(i, column, c, r);
      const S delta = S(i == t ? 1 : 0);
      sum += abs(delta - c) + r;
      magnitude += abs(delta) + abs(c) + r;
    }
    return sum * up + gamma * magnitude + tiny < 1;
  };
  const auto zEntry = [&](int i, int j, S& c, S& r) {
    c = w.zc[std::size_t(i) * nn + std::size_t(j)];
    r = w.zr[std::size_t(i) * nn + std::size_t(j)];
  };
  for (int i = 0; i < m; ++i) {
    if (!rowBelowOne(zEntry, i, -1, -1)) return 0;
  }
  std::uint64_t proven = 0;
  for (int t = m; t < n; ++t) proven |= std::uint64_t(1) << order[std::size_t(t)];
  // An axis a = B_p: B with column p swapped for u outside B. mid Z_B' is near the eta matrix
  // I + (z - e_p) e_p^T, z = mid Z_u; E, its inverse, is I with column p replaced by e:
  // e_p = 1 / z_p, e_i = -z_i / z_p. T = E Z_B': rows i != p are Z_i + e_i Z_p, row p is
  // e_p Z_p.
  for (int p = 0; p < m; ++p) {
    const int a = order[std::size_t(p)];
    if (!((wanted >> a) & 1)) continue;
    for (int t = m; t < n && !((proven >> a) & 1); ++t) {
      const int u = order[std::size_t(t)];
      const S zp = w.zc[std::size_t(p) * nn + std::size_t(u)];
      if (!(abs(zp) > w.zr[std::size_t(p) * nn + std::size_t(u)])) continue;
      const auto tEntry = [&](int i, int j, S& c, S& r) {
        const S cp = w.zc[std::size_t(p) * nn + std::size_t(j)];
        const S rp = w.zr[std::size_t(p) * nn + std::size_t(j)];
        if (i == p) {
          const S e = 1 / zp;
          c = e * cp;
          r = (abs(e) * rp) * up + gamma * abs(c) + tiny;
          return;
        }
        const S e = -w.zc[std::size_t(i) * nn + std::size_t(u)] / zp;
        const S ci = w.zc[std::size_t(i) * nn + std::size_t(j)];
        const S ri = w.zr[std::size_t(i) * nn + std::size_t(j)];
        c = ci + e * cp;
        r = (ri + abs(e) * rp) * up + gamma * (abs(ci) + abs(e * cp)) + tiny;
      };
      bool regular = true;
      for (int i = 0; i < m && regular; ++i) regular = rowBelowOne(tEntry, i, p, u);
      if (regular) proven |= std::uint64_t(1) << a;
    }
  }
  return proven & wanted;
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
  if (!invertGaussJordan(m, mid, y)) return false;
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
