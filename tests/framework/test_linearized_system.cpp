// The bounds on the solutions of a linearized system over a box (framework/numeric/
// linearized_system.hpp, solutionBox), on generated systems whose solutions are known by
// construction.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "framework/numeric/linearized_system.hpp"
#include "tests/test_support.hpp"

namespace {

/// A solvable system m x n over the box |d_j| <= h_j: J with N(0, 1) entries, every rho_i > 0,
/// and a solution d* (on the box's boundary along some axes) with mu = -J d* - s*,
/// |s*_i| <= 0.9 rho_i. The margin of 0.1 rho_i absorbs the rounding of mu and of the other
/// solutions sampled from d* along J's kernel (computed in double).
struct Generated {
  Eigen::MatrixXd jac;
  std::vector<double> h, rho, slack, solution;
};

Generated generate(std::mt19937& rng, int n, int m, bool corner, double rhoScale) {
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit(0, 1);
  Generated g;
  g.jac.resize(m, n);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) g.jac(i, j) = gauss(rng);
  g.h.resize(n), g.rho.resize(m), g.slack.resize(m), g.solution.resize(n);
  for (double& v : g.h) v = 0.1 + 0.9 * unit(rng);
  for (int i = 0; i < m; ++i) {
    g.rho[i] = rhoScale * (0.001 + unit(rng));
    g.slack[i] = 0.9 * (2 * unit(rng) - 1) * g.rho[i];
  }
  for (int j = 0; j < n; ++j) {
    // Near a corner: every coordinate within 5% of the box's boundary.
    const double side = rng() % 2 ? 1.0 : -1.0;
    g.solution[j] = (corner ? side * (0.95 + 0.05 * unit(rng)) : 2 * unit(rng) - 1) * g.h[j];
  }
  return g;
}

template <class S>
void fill(const Generated& g, ndc::LinearizedSystem<S>& system) {
  const int m = static_cast<int>(g.jac.rows()), n = static_cast<int>(g.jac.cols());
  system.resize(n, m);
  for (int i = 0; i < m; ++i) {
    S v = -S(g.slack[i]);
    for (int j = 0; j < n; ++j) {
      system.jac[std::size_t(i * n + j)] = S(g.jac(i, j));
      v -= S(g.jac(i, j)) * S(g.solution[j]);
    }
    system.mu[i] = v;
    system.rho[i] = S(g.rho[i]);
  }
  for (int j = 0; j < n; ++j) system.h[j] = S(g.h[j]);
}

/// Solutions d* + N t inside the box (N an orthonormal basis of J's kernel), t in a ball that
/// reaches beyond the box: `count` of them.
std::vector<std::vector<double>> kernelSolutions(const Generated& g, std::mt19937& rng, int count) {
  const int n = static_cast<int>(g.jac.cols());
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(g.jac);
  const Eigen::MatrixXd kernel =
      lu.kernel().householderQr().householderQ() * Eigen::MatrixXd::Identity(n, lu.kernel().cols());
  std::normal_distribution<double> gauss;
  double reach = 0;
  for (double v : g.h) reach += 2 * v;
  std::vector<std::vector<double>> out;
  for (int s = 0; s < 50 * count && int(out.size()) < count; ++s) {
    Eigen::VectorXd t(kernel.cols());
    for (int p = 0; p < t.size(); ++p) t(p) = gauss(rng) * reach;
    const Eigen::VectorXd w = kernel * t * std::pow(0.5, s % 8);
    std::vector<double> d(g.solution);
    bool inside = true;
    for (int j = 0; j < n; ++j) {
      d[j] += w(j);
      inside = inside && std::abs(d[j]) <= g.h[j];
    }
    if (inside) out.push_back(d);
  }
  return out;
}

}  // namespace

TEMPLATE_TEST_CASE("linearized system: the solutions' box holds every solution", "[linearized]",
                   NDC_SCALARS) {
  // Random solvable systems with 1 <= m < n <= 8, their solution d* in the box or near a
  // corner, and up to 40 more solutions along J's kernel: every one lies in solutionBox. For
  // k = n - m = 1 with tiny rho the solutions form a segment, whose range along each axis step
  // 7's propagation finds exactly: the bounds lie within 1e-4 of the segment's ends. And the bounds
  // are often narrower than the box, which is what contracting a box needs.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(71);
  ndc::LinearizedSystem<S> system;
  std::vector<S> lo, hi;
  int bounded = 0, narrow = 0, checked = 0, segments = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 7);
    const int m = 1 + static_cast<int>(rng() % (n - 1));
    const bool segment = trial % 4 == 3;
    const Generated g =
        generate(rng, n, segment ? n - 1 : m, trial % 2 == 1, segment ? 1e-9 : 0.05);
    fill(g, system);
    S hh = 0;
    for (const S& v : system.h) hh += v * v;
    INFO("trial " << trial << ", n = " << n << ", m = " << g.jac.rows());
    REQUIRE_FALSE(system.excludes(hh * (1 + system.tolerance()), 8));
    if (!system.solutionBox(lo, hi)) continue;  // J_c (nearly) rank-deficient
    ++bounded;
    std::vector<std::vector<double>> solutions = kernelSolutions(g, rng, 40);
    solutions.push_back(g.solution);
    for (const std::vector<double>& d : solutions)
      for (int j = 0; j < n; ++j) {
        ++checked;
        // Compared in S (Catch would print S; the doubles say enough).
        const bool inside = lo[j] <= S(d[j]) && S(d[j]) <= hi[j];
        INFO("axis " << j << ": " << d[j] << " in [" << ndc::toDouble(lo[j]) << ", "
                     << ndc::toDouble(hi[j]) << "]");
        CHECK(inside);
      }
    double before = 0, after = 0;
    for (int j = 0; j < n; ++j) {
      before += g.h[j] * g.h[j];
      after += std::pow(ndc::toDouble(hi[j] - lo[j]) / 2, 2);
    }
    narrow += after < 0.5 * before;
    if (segment) {
      // The segment d* + tau u (u spans J's kernel) within the box, exactly.
      const Eigen::FullPivLU<Eigen::MatrixXd> lu(g.jac);
      if (lu.kernel().cols() != 1) continue;
      const Eigen::VectorXd u = lu.kernel().col(0);
      double tauLo = -1e300, tauHi = 1e300;
      for (int j = 0; j < n; ++j) {
        if (u(j) == 0) continue;
        const double a = (-g.h[j] - g.solution[j]) / u(j), b = (g.h[j] - g.solution[j]) / u(j);
        tauLo = std::max(tauLo, std::min(a, b)), tauHi = std::min(tauHi, std::max(a, b));
      }
      ++segments;
      for (int j = 0; j < n; ++j) {
        const double e0 = g.solution[j] + tauLo * u(j), e1 = g.solution[j] + tauHi * u(j);
        CHECK(ndc::toDouble(lo[j]) >= std::min(e0, e1) - 1e-4);
        CHECK(ndc::toDouble(hi[j]) <= std::max(e0, e1) + 1e-4);
      }
    }
  }
  INFO(bounded << " systems bounded, " << narrow << " narrower than half the box, " << checked
               << " coordinates checked, " << segments << " segments");
  CHECK(bounded >= 100);
  CHECK(narrow >= bounded / 10);
  CHECK(segments >= 20);
}
