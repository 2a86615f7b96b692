// The multiplier (Farkas) test of a linearized system over a box
// (framework/numeric/multipliers.hpp), on generated systems whose answer is known by construction.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "framework/numeric/multipliers.hpp"
#include "tests/test_support.hpp"

TEMPLATE_TEST_CASE("multiplier test: sound on solvable systems, decisive on separated ones",
                   "[multipliers]", NDC_SCALARS) {
  // Random m x n systems (1 <= m <= n <= 8, entries N(0, 1)), half-widths h in [0.1, 1] and
  // radii rho of 0 (an affine equation) or up to 0.5.
  //  - Solvable: mu = -J d* - s* for d* in the box and |s*| <= rho; no y may exclude it.
  //  - Separated: for a random y*, mu moved along y* until
  //    |y* . mu| = 1.05 (sum_i |y*_i| rho_i + sum_j |(J^T y*)_j| h_j), so y* proves the system
  //    empty with 5% to spare; the least-squares steps must find such a y in nearly every case.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(53);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit(0, 1);
  ndc::MultiplierTest<S> test;
  int separated = 0, found = 0, solvable = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 8);
    const int m = 1 + static_cast<int>(rng() % n);
    std::vector<S> jac(std::size_t(m * n)), mu(m), rho(m), h(n);
    std::vector<double> jd(std::size_t(m * n)), rd(m), hd(n);
    for (double& v : jd) v = gauss(rng);
    for (double& v : hd) v = 0.1 + 0.9 * unit(rng);
    for (double& v : rd) v = unit(rng) < 0.5 ? 0 : 0.5 * unit(rng);
    const S tol = S(8 * (n + m + 8)) * ndc::ScalarTraits<S>::epsilon();
    if (trial % 2 == 0) {
      // Solvable: a point d* of the box and s* in +-rho.
      std::vector<double> d(n);
      for (int j = 0; j < n; ++j)  // on the boundary along some axes
        d[j] = (trial % 4 == 0 && j % 2 == 0 ? 1.0 : 2 * unit(rng) - 1) * hd[j];
      for (int i = 0; i < m; ++i) {
        // In S, so that d* stays in the box up to S's rounding (which tol covers).
        S v = -S(2 * unit(rng) - 1) * S(rd[i]);
        for (int j = 0; j < n; ++j) v -= S(jd[std::size_t(i * n + j)]) * S(d[j]);
        mu[i] = v;
      }
      ++solvable;
    } else {
      std::vector<double> y(m);
      for (double& v : y) v = gauss(rng);
      double bound = 0, yy = 0;
      for (int i = 0; i < m; ++i) bound += std::abs(y[i]) * rd[i], yy += y[i] * y[i];
      for (int j = 0; j < n; ++j) {
        double z = 0;
        for (int i = 0; i < m; ++i) z += y[i] * jd[std::size_t(i * n + j)];
        bound += std::abs(z) * hd[j];
      }
      // mu = t y with t yy = 1.05 bound (a random sign).
      const double t = (rng() % 2 ? 1 : -1) * 1.05 * bound / yy;
      for (int i = 0; i < m; ++i) mu[i] = S(t * y[i]);
      ++separated;
    }
    for (std::size_t q = 0; q < jd.size(); ++q) jac[q] = S(jd[q]);
    for (int i = 0; i < m; ++i) rho[i] = S(rd[i]);
    for (int j = 0; j < n; ++j) h[j] = S(hd[j]);
    const bool excluded = test.excludes(m, n, jac.data(), mu.data(), rho.data(), h.data(), tol, 8);
    INFO("trial " << trial << ", m = " << m << ", n = " << n);
    if (trial % 2 == 0) CHECK_FALSE(excluded);
    found += trial % 2 == 1 && excluded;
  }
  INFO(found << " of " << separated << " separated systems excluded");
  CHECK(solvable == 300);
  CHECK(double(found) >= 0.9 * double(separated));
}
