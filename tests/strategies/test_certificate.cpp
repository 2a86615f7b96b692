// The cell tests of the topology certificate (strategies/connection/crossing/certificate.hpp)
// against ground truth: a 2-sphere in R^4, M = {x0^2 + x1^2 + x2^2 = 1, x3 = x0}, whose coordinate
// x3 has a maximum at p = (1, 0, 0, 1). Faces x3 = c near p are where the face-graph test cannot
// succeed (the normal space of M contains e3 at p) and each equation alone meets the face, so
// only a combination of the equations can prove that M misses a face above the maximum.
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <span>
#include <vector>

#include "applications/load.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/inverse.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "strategies/connection/crossing/certificate.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Box;
using ndc::Interval;

const char* const kTiltedSphere = R"(name = "tilted-sphere"
variables = ["x0", "x1", "x2", "x3"]
domain = [[-2, 2], [-2, 2], [-2, 2], [-2, 2]]
equations = ["x0^2 + x1^2 + x2^2 - 1", "x3 - x0"]
)";

/// An enclosure of the Jacobian of `system` over `box` (m x n, row-major), from interval
/// gradients of the exact expressions.
template <class S>
std::vector<Interval<S>> jacobianOver(const ndc::System<S>& system, const Box<S>& box) {
  using I = Interval<S>;
  const int n = system.n(), m = system.m();
  std::vector<I> x, gradient(static_cast<std::size_t>(n)), out;
  for (int j = 0; j < n; ++j) x.emplace_back(box.lo[j], box.hi[j]);
  for (int i = 0; i < m; ++i) {
    system.equations()[i].template evaluate<S>(std::span<const I>(x), std::span<I>(gradient));
    out.insert(out.end(), gradient.begin(), gradient.end());
  }
  return out;
}

/// Whether M meets the face x3 = c of `box` (x0 = c on M, then x1^2 + x2^2 = 1 - c^2).
bool meets(const Box<double>& box, double c) {
  if (c < box.lo[0] || c > box.hi[0] || 1 - c * c < 0) return false;
  const auto range = [&](int j) {  // min and max of x_j^2 over the box
    const double lo = box.lo[j], hi = box.hi[j];
    const double top = std::max(lo * lo, hi * hi);
    return std::array<double, 2>{lo <= 0 && hi >= 0 ? 0 : std::min(lo * lo, hi * hi), top};
  };
  const auto a = range(1), b = range(2);
  return a[0] + b[0] <= 1 - c * c && 1 - c * c <= a[1] + b[1];
}

}  // namespace

TEMPLATE_TEST_CASE(
    "certificate: a combination of the equations excludes faces that no single "
    "equation or graph test can",
    "[certificate]", NDC_SCALARS) {
  using S = TestType;
  ndc::test::PrecisionScope<S> precision;
  const ndc::Problem problem = ndc::parseProblem(kTiltedSphere, "tilted-sphere.toml");
  const ndc::System<S> system(problem);
  const std::vector<S> level{S(0), S(0)};
  const std::vector<int> axes{0, 1, 2};
  ndc::GraphTest<S> graphTest(4, 2);
  long aboveExcluded = 0, above = 0;
  for (double h : {1.0 / 16, 1.0 / 64, 1.0 / 256}) {
    // Faces x3 = c from 3 h below to 3 h above the maximum, boxes of half-width h in x0..x2
    // whose centres sweep a 5 x 5 x 5 grid around p.
    for (int t = -6; t <= 6; ++t) {
      const double c = 1 + t * h / 2;
      for (int a = -2; a <= 2; ++a) {
        for (int b = -2; b <= 2; ++b) {
          for (int e = -2; e <= 2; ++e) {
            Box<double> box;
            const double centre[3] = {1 + a * h / 2, b * h / 2, e * h / 2};
            for (int j = 0; j < 3; ++j) {
              box.lo.push_back(centre[j] - h);
              box.hi.push_back(centre[j] + h);
            }
            box.lo.push_back(c), box.hi.push_back(c);
            Box<S> boxS;
            for (int j = 0; j < 4; ++j)
              boxS.lo.push_back(S(box.lo[j])), boxS.hi.push_back(S(box.hi[j]));
            const auto jacobian = jacobianOver(system, boxS);
            const bool excluded = ndc::combinationExcludes(system, std::span<const S>(level), boxS,
                                                           std::span<const Interval<S>>(jacobian),
                                                           std::span<const int>(axes));
            INFO("h = " << h << ", face x3 = " << c << ", centre " << centre[0] << " " << centre[1]
                        << " " << centre[2]);
            // Soundness: never excludes a face that M meets.
            if (meets(box, c)) CHECK_FALSE(excluded);
            // Near p (the box holds x0 = 1), the graph test must fail, so the exclusion is
            // what certifies these faces.
            if (box.lo[0] <= 1 && box.hi[0] >= 1 && std::abs(centre[1]) <= h &&
                std::abs(centre[2]) <= h)
              CHECK_FALSE(graphTest.graph(std::span<const Interval<S>>(jacobian),
                                          std::span<const int>(axes)));
            // Completeness above the maximum: from 2 h above (far beyond the second-order
            // error of the mean value form) every box is excluded.
            if (t >= 4) {
              ++above;
              aboveExcluded += excluded;
            }
          }
        }
      }
    }
  }
  CHECK(above > 0);
  CHECK(aboveExcluded == above);
}

TEMPLATE_TEST_CASE("The preconditioners' Gauss-Jordan inverse", "[certificate]", NDC_SCALARS) {
  // Generated m x m matrices (m = 1..9): random, with rows of mixed scales, and with a zero
  // leading entry (a pivot must be searched for): ||I - Y A||_inf stays at rounding level
  // times the condition number. Singular ones (a repeated row, a zero column) are declined.
  using S = TestType;
  ndc::test::PrecisionScope<S> precision(128);
  std::mt19937 rng(1928);
  const S eps = ndc::ScalarTraits<S>::epsilon();
  std::vector<S> a, copy, y;
  for (int m = 1; m <= 9; ++m)
    for (int trial = 0; trial < 8; ++trial) {
      a.resize(std::size_t(m) * m);
      for (int i = 0; i < m; ++i) {
        const double scale = trial % 2 ? std::pow(10.0, ndc::test::uniform<double>(rng, -4, 4)) : 1;
        for (int j = 0; j < m; ++j)
          a[std::size_t(j) * m + i] = S(scale * ndc::test::uniform<double>(rng, -1, 1));
      }
      if (trial % 4 == 2 && m > 1) a[0] = 0;
      copy = a;
      REQUIRE(ndc::invertGaussJordan(m, copy, y));
      // ||I - Y A||_inf, and kappa_inf = ||A|| ||Y|| as the scale it may reach.
      using std::abs;
      S residual = 0, normA = 0, normY = 0;
      for (int i = 0; i < m; ++i) {
        S row = 0, rowA = 0, rowY = 0;
        for (int j = 0; j < m; ++j) {
          S e = i == j ? S(1) : S(0);
          for (int l = 0; l < m; ++l) e -= y[std::size_t(l) * m + i] * a[std::size_t(j) * m + l];
          row += abs(e);
          rowA += abs(a[std::size_t(j) * m + i]);
          rowY += abs(y[std::size_t(j) * m + i]);
        }
        residual = std::max(residual, row);
        normA = std::max(normA, rowA);
        normY = std::max(normY, rowY);
      }
      INFO("m = " << m << ", trial " << trial);
      CHECK(residual <= S(16 * m * m) * eps * normA * normY);
    }
  const std::vector<S> repeated = {S(1), S(2), S(1), S(2)};  // column-major: rows (1, 1), (2, 2)
  copy = repeated;
  CHECK_FALSE(ndc::invertGaussJordan(2, copy, y));
  const std::vector<S> zeroColumn = {S(1), S(2), S(3), S(0), S(0), S(0), S(4), S(5), S(7)};
  copy = zeroColumn;
  CHECK_FALSE(ndc::invertGaussJordan(3, copy, y));
}

TEST_CASE("The one-switch ||I - Y A|| kernel equals per-operation interval arithmetic",
          "[certificate]") {
  // Random interval matrices (m = 1..6 columns picked from n = m + 2), Y near their inverse or
  // random, some entries overflowing: the kernel's bound is the per-operation bound, bit for bit.
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(-2, 2), w(0, 0.2);
  int belowOne = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int m = trial % 100 == 99 ? 18 : 1 + trial % 6, n = m + 2;
    std::vector<Interval<double>> a;
    for (int k = 0; k < m * n; ++k) {
      const double lo = u(rng) / 3;
      a.emplace_back(lo, lo + w(rng) * (trial % 3 == 0 ? 0.01 : 1));
    }
    if (trial % 50 == 7)
      a[0] =
          Interval<double>(-std::numeric_limits<double>::max(), std::numeric_limits<double>::max());
    std::vector<int> columns;
    for (int j = 0; j < n && int(columns.size()) < m; ++j)
      if (j % 3 != 1 || n - j <= m - int(columns.size())) columns.push_back(j);
    std::vector<double> y(std::size_t(m) * m);
    for (double& v : y) v = u(rng) * (trial % 2 ? 1 : 0.05);
    for (int i = 0; i < m && trial % 2 == 0; ++i) y[std::size_t(i) * m + i] += 3;
    // The per-operation reference.
    double reference = 0;
    for (int i = 0; i < m; ++i) {
      Interval<double> row(0.0);
      for (int j = 0; j < m; ++j) {
        Interval<double> r(i == j ? 1.0 : 0.0);
        for (int l = 0; l < m; ++l)
          r -= Interval<double>(y[std::size_t(l) * m + i]) * a[std::size_t(l) * n + columns[j]];
        row += Interval<double>(std::max(std::abs(r.lower()), std::abs(r.upper())));
      }
      reference = std::isnan(row.upper()) || std::isnan(reference)
                      ? std::numeric_limits<double>::quiet_NaN()
                      : std::max(reference, row.upper());
    }
    const double kernel = ndc::identityResidualNorm(m, y, a, std::size_t(n), columns);
    INFO("trial " << trial << " m " << m);
    if (std::isnan(reference))
      CHECK(std::isnan(kernel));
    else
      CHECK(kernel == reference);
    belowOne += kernel < 1;
  }
  // Both outcomes of the test are exercised.
  CHECK(belowOne > 20);
  CHECK(belowOne < 580);
}

TEMPLATE_TEST_CASE("certificate: the graph test proves flats that lie obliquely to every axis",
                   "[certificate]", NDC_SCALARS) {
  // A k-flat in R^n whose tangent space T is near the diagonals (1, ..., 1) and
  // (1, -1, 1, ...): every coordinate is as far from being a good parameter as it can be. Its
  // Jacobian is an orthonormal basis N (m x n rows) of T's complement, enclosed with radius
  // r = 0.95 / (n max_j sum_i |N_ij|). Over T, [N; T^T] is orthogonal, its inverse is its
  // transpose, and ||I - Y A||_inf <= n r max_j sum_i |N_ij| = 0.95: the graph test must prove
  // every such flat a graph (over T), although at this radius most blocks of coordinates are
  // not proven regular (in R^6..R^8 nearly none).
  using S = TestType;
  ndc::test::PrecisionScope<S> precision;
  std::mt19937 rng(31);
  std::normal_distribution<double> normal;
  int proven = 0, cases = 0;
  for (int n = 3; n <= 8; ++n) {
    for (int k = 1; k <= 2; ++k) {
      const int m = n - k;
      ndc::GraphTest<S> graphTest(n, m);
      std::vector<int> axes(n);
      std::iota(axes.begin(), axes.end(), 0);
      for (int flat = 0; flat < 20; ++flat) {
        Eigen::MatrixXd g(n, n);
        for (int j = 0; j < n; ++j) {
          g(j, 0) = 1 + 0.05 * normal(rng);
          if (k == 2) g(j, 1) = (j % 2 ? -1 : 1) + 0.05 * normal(rng);
          for (int c = k; c < n; ++c) g(j, c) = normal(rng);
        }
        const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(g).householderQ();
        double worst = 0;  // max_j sum_i |N_ij|, N_ij = q(j, k + i)
        for (int j = 0; j < n; ++j) {
          double sum = 0;
          for (int i = 0; i < m; ++i) sum += std::abs(q(j, k + i));
          worst = std::max(worst, sum);
        }
        const double radius = 0.95 / (n * worst);
        std::vector<Interval<S>> jacobian;
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < n; ++j)
            jacobian.emplace_back(S(q(j, k + i) - radius), S(q(j, k + i) + radius));
        }
        INFO("n = " << n << ", k = " << k << ", flat " << flat << ", radius " << radius);
        const bool graph =
            graphTest.graph(std::span<const Interval<S>>(jacobian), std::span<const int>(axes));
        CHECK(graph);
        proven += graph;
        ++cases;
      }
    }
  }
  CHECK(proven == cases);
}

TEMPLATE_TEST_CASE("certificate: the facets' graph tests at once prove what each proves alone",
                   "[certificate]", NDC_SCALARS) {
  // Generated interval Jacobians J = A +- r (m x n, n = 3..8, k = n - m = 1..3), A Gaussian
  // and r from 1e-3 to 3e-2. GraphTest::facetGraphs claims, for each axis a, that the columns
  // other than a hold a block regular for every member of J. It must never claim an axis for
  // which a member's other columns have rank below m: A built so that the columns other than
  // one axis span only m - 1 dimensions (A itself is a member), and vertex members sampled
  // for every claim. And it must prove at least 90% of the axes that graph() proves on each
  // facet's columns alone.
  using S = TestType;
  ndc::test::PrecisionScope<S> precision;
  std::mt19937 rng(47);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> unit(0, 1);
  int byGraph = 0, byBoth = 0, claims = 0, deficient = 0;
  for (int n = 3; n <= 8; ++n) {
    for (int k = 1; k <= std::min(3, n - 1); ++k) {
      const int m = n - k;
      ndc::GraphTest<S> graphTest(n, m);
      for (int trial = 0; trial < 40; ++trial) {
        Eigen::MatrixXd a(m, n);
        for (int i = 0; i < m * n; ++i) a.data()[i] = normal(rng);
        // Every fourth trial: the columns other than `bad` in an (m - 1)-dimensional space.
        const int bad = trial % 4 == 0 ? static_cast<int>(rng() % n) : -1;
        if (bad >= 0) {
          const Eigen::MatrixXd u =
              Eigen::MatrixXd::NullaryExpr(m, m - 1, [&] { return normal(rng); });
          for (int j = 0; j < n; ++j) {
            if (j != bad)
              a.col(j) = u * Eigen::VectorXd::NullaryExpr(m - 1, [&] { return normal(rng); });
          }
        }
        const double radius = std::pow(10.0, -3 + 1.5 * unit(rng));
        std::vector<Interval<S>> jacobian;
        for (int i = 0; i < m; ++i) {
          for (int j = 0; j < n; ++j)
            jacobian.emplace_back(S(a(i, j) - radius), S(a(i, j) + radius));
        }
        const std::uint64_t all = (std::uint64_t(1) << n) - 1;
        const std::uint64_t proven =
            graphTest.facetGraphs(std::span<const Interval<S>>(jacobian), all);
        INFO("n = " << n << ", m = " << m << ", trial " << trial << ", radius " << radius);
        for (int axis = 0; axis < n; ++axis) {
          std::vector<int> free;
          for (int j = 0; j < n; ++j) {
            if (j != axis) free.push_back(j);
          }
          const bool alone =
              graphTest.graph(std::span<const Interval<S>>(jacobian), std::span<const int>(free));
          const bool claimed = (proven >> axis) & 1;
          byGraph += alone;
          byBoth += alone && claimed;
          if (!claimed) continue;
          ++claims;
          INFO("axis " << axis << " claimed");
          CHECK(axis != bad);
          // Vertex members: every one has rank m on the columns other than `axis`.
          for (int sample = 0; sample < 20; ++sample) {
            Eigen::MatrixXd member(m, n - 1);
            for (int i = 0; i < m; ++i) {
              for (int t = 0; t < n - 1; ++t)
                member(i, t) = a(i, free[t]) + (rng() % 2 ? radius : -radius);
            }
            const Eigen::JacobiSVD<Eigen::MatrixXd> svd(member);
            CHECK(svd.singularValues()(m - 1) > 1e-9);
          }
        }
        deficient += bad >= 0;
      }
    }
  }
  INFO(claims << " claims, " << byGraph << " axes proven by graph(), " << byBoth
              << " of them by facetGraphs too, " << deficient << " deficient trials");
  CHECK(claims > 1000);
  CHECK(deficient > 100);
  CHECK(byBoth >= 0.9 * byGraph);
}
