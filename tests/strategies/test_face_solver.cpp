// The crossing connection's face solver by evaluation
// (strategies/connection/crossing/face_solver.hpp, docs/crossing.md "Faces by evaluation") on
// generated faces with a planted root: square systems F(x) = A (x - p) + b (x_s - p_s)(x_t - p_t)
// with small integer A and b, whose only root in the face is p (the test checks that bound), placed
// where the solver's boxes make roots hard to prove: on the planes where it halves a face, and a
// billionth of the face width inside or outside its ends (where the level perturbation puts the
// crossings of inputs symmetric about grid planes; exactly on an end, Newton's rounding decides the
// owner, which the perturbation exists to avoid). The solver must decide every such face by
// evaluation (no fallback to the Bernstein solve), find p, to rounding, when p lies in the
// half-open face, and nothing otherwise; two faces split a billionth of the width from p find it
// once between them.
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "strategies/connection/crossing/face_solver.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::crossing_detail::FaceEnds;
using ndc::crossing_detail::FaceSolver;

/// A planted system in R^n: m = n - 2 equations, free axes 0 .. m - 1, fixed axes m, m + 1.
struct Planted {
  ndc::Problem problem;
  std::vector<double> p;  ///< the root, at random in [-1, 1]: F(p) rounds, as on real inputs
  /// Every other root x has |x - p| >= 1 / (|A^-1| |b|) in the max norm (A d = -b d_s d_t).
  double isolation = 0;
};

/// Draws A (m x m on the free axes, integer in [-3, 3], plus integer columns for the fixed
/// axes) and b (integer in [-1, 1], on the product of free axes s and t; with `graph`, rows
/// x_i - g_i(x_0, fixed) for i >= 1, nonlinear in x_0 only) until A's free block is regular.
/// The equations are written expanded, as a user writes them, so that evaluating them near p
/// cancels and rounds.
Planted planted(int n, bool graph, std::mt19937& rng) {
  const int m = n - 2;
  std::uniform_int_distribution<int> coefficient(-3, 3), small(-1, 1), axis(0, m - 1);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<std::string> names;
  for (int j = 0; j < n; ++j) names.push_back("x" + std::to_string(j));
  while (true) {
    Planted out;
    out.p.resize(n);
    for (double& v : out.p) v = unit(rng);
    Eigen::MatrixXd a(m, n);
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < n; ++j) a(i, j) = coefficient(rng);
      // Graph form: x_i - g_i(x_0, fixed) for i >= 1, as the u, v, w of torus-r6.toml.
      for (int j = 1; graph && j < m; ++j) a(i, j) = i == j;
    }
    const Eigen::MatrixXd free = a.leftCols(m);
    if (std::abs(free.determinant()) < 0.5) continue;
    const double inverseNorm = free.inverse().cwiseAbs().rowwise().sum().maxCoeff();
    std::vector<int> b(m), s(m), t(m);
    for (int i = 0; i < m; ++i) b[i] = small(rng), s[i] = axis(rng), t[i] = axis(rng);
    for (int i = 0; graph && i < m; ++i) b[i] = i == 0 ? 1 : b[i], s[i] = t[i] = 0;
    out.isolation = 1 / inverseNorm;  // |b| <= 1
    std::vector<std::string> equations;
    for (int i = 0; i < m; ++i) {
      // sum_j a_ij x_j + b_i (x_s x_t - p_t x_s - p_s x_t) + c_i, zero at p.
      const double ps = out.p[s[i]], pt = out.p[t[i]];
      double c = b[i] * ps * pt;
      std::ostringstream e;
      e.precision(17);
      for (int j = 0; j < n; ++j) {
        e << (j ? " + " : "") << "(" << a(i, j) << ")*" << names[j];
        c -= a(i, j) * out.p[j];
      }
      e << " + (" << b[i] << ")*(" << names[s[i]] << "*" << names[t[i]] << " - (" << pt << ")*"
        << names[s[i]] << " - (" << ps << ")*" << names[t[i]] << ") + (" << c << ")";
      equations.push_back(e.str());
    }
    out.problem = ndc::test::makeProblem(n, equations, 2);
    return out;
  }
}

/// Where p lies on one free axis of the face box.
enum class Place { kInside, kHalvingPlane, kNearLower, kNearUpper, kBelow, kAbove };

/// The face box's interval on one axis of width w for p_j placed as `place`; whether p_j lies
/// in the half-open [lo, hi).
bool placeAxis(Place place, double pj, double w, double u, double& lo, double& hi) {
  const double near = 1e-9 * w;
  switch (place) {
    case Place::kInside:
      lo = pj - (0.1 + 0.8 * u) * w;
      break;
    case Place::kHalvingPlane:
      lo = pj - w / 2;
      break;
    case Place::kNearLower:
      lo = pj - near;
      break;
    case Place::kNearUpper:
      lo = pj + near - w;
      break;
    case Place::kBelow:
      lo = pj + near;
      break;
    case Place::kAbove:
      lo = pj - near - w;
      break;
  }
  hi = lo + w;
  return lo <= pj && pj < hi;
}

/// Solves the face (fixed axes at p, free box `lo..hi`) by evaluation, with the caller's
/// exclusion test `excludesFace`; false if undecided.
template <class S, class ExcludesFace>
bool solveFaceWith(const ndc::System<S>& system, const std::vector<double>& p,
                   const std::vector<double>& lo, const std::vector<double>& hi,
                   std::vector<std::vector<S>>& roots, const ExcludesFace& excludesFace) {
  const int n = system.n(), m = system.m();
  std::vector<S> point(n);
  for (int j = 0; j < n; ++j) point[j] = S(p[j]);
  std::vector<int> freeAxes(m);
  ndc::Box<S> face{std::vector<S>(m), std::vector<S>(m)};
  for (int j = 0; j < m; ++j) freeAxes[j] = j, face.lo[j] = S(lo[j]), face.hi[j] = S(hi[j]);
  FaceEnds ends{std::vector<bool>(m, false), std::vector<bool>(m, false)};
  FaceSolver<S> solver(system, 20, std::vector<S>(m, S(0)), S(0));
  roots.clear();
  return solver.solveByEvaluation(point, freeAxes, face, ends, roots, excludesFace);
}

/// solveFaceWith without a test of the caller's.
template <class S>
bool solveFace(const ndc::System<S>& system, const std::vector<double>& p,
               const std::vector<double>& lo, const std::vector<double>& hi,
               std::vector<std::vector<S>>& roots) {
  return solveFaceWith(system, p, lo, hi, roots, [] { return false; });
}

}  // namespace

TEMPLATE_TEST_CASE("face solver: planted roots on halving planes and near face ends",
                   "[crossing][face-solver]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> unit(0, 1);
  std::uniform_int_distribution<int> places(0, 5);
  int found = 0, empty = 0;
  for (int n = 4; n <= 8; ++n) {
    for (int trial = 0; trial < 24; ++trial) {
      const Planted sys = planted(n, trial % 3 == 2, rng);
      // A face width of 1/4 .. 1/128, within a quarter of p's isolation: p is its only root.
      double w = std::pow(2.0, -2 - static_cast<int>(rng() % 6));
      while (w > sys.isolation / 4) w /= 2;
      const ndc::System<S> system(sys.problem);
      const int m = n - 2;
      // The first axis on a halving plane (the solver's first cut), the others drawn.
      std::vector<double> lo(m), hi(m);
      bool inside = true;
      for (int j = 0; j < m; ++j) {
        const auto place = j == 0 && trial % 2 ? Place::kHalvingPlane : Place(places(rng));
        inside = placeAxis(place, sys.p[j], w, unit(rng), lo[j], hi[j]) && inside;
      }
      std::vector<std::vector<S>> roots;
      INFO("n = " << n << ", trial " << trial << ", width " << w);
      REQUIRE(solveFace(system, sys.p, lo, hi, roots));
      REQUIRE(roots.size() == (inside ? 1u : 0u));
      if (inside) {
        ++found;
        for (int j = 0; j < n; ++j) CHECK(std::abs(double(roots[0][j]) - sys.p[j]) <= 1e-12);
      } else {
        ++empty;
      }
      // Split a billionth of the width beside p along axis 0: exactly one half finds p if the
      // face holds it, the one the split's side puts it in.
      const double cut = sys.p[0] + (trial % 4 < 2 ? 1e-9 : -1e-9) * w;
      if (cut <= lo[0] || cut >= hi[0]) continue;
      std::vector<double> lower = hi, upper = lo;
      lower[0] = upper[0] = cut;
      std::vector<std::vector<S>> below, above;
      REQUIRE(solveFace(system, sys.p, lo, lower, below));
      REQUIRE(solveFace(system, sys.p, upper, hi, above));
      CHECK(below.size() == (inside && sys.p[0] < cut ? 1u : 0u));
      CHECK(above.size() == (inside && sys.p[0] >= cut ? 1u : 0u));
    }
  }
  // Both outcomes are exercised.
  CHECK(found >= 20);
  CHECK(empty >= 20);
}

TEMPLATE_TEST_CASE("face solver: the caller's exclusion test is asked once, where a round fails",
                   "[crossing][face-solver]", NDC_SCALARS) {
  // The crossing connection passes the leaf model's multiplier test, which costs more than a
  // round of the solver. On planted faces: a face of 1e-6 around p is decided by the first
  // round (Krawczyk proves p unique), so the test is never asked; on faces of width 1/2 to 2
  // (the first round decides few) it is asked at most once per face, never changes the
  // roots when it says no, and when it says yes (a proof the caller vouches for) the face
  // has no roots.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> unit(0, 1);
  int asked = 0, wide = 0;
  for (int n = 4; n <= 8; ++n) {
    for (int trial = 0; trial < 12; ++trial) {
      const Planted sys = planted(n, trial % 3 == 2, rng);
      const ndc::System<S> system(sys.problem);
      const int m = n - 2;
      INFO("n = " << n << ", trial " << trial);
      std::vector<double> lo(m), hi(m);
      for (int j = 0; j < m; ++j) lo[j] = sys.p[j] - 0.5e-6, hi[j] = sys.p[j] + 0.5e-6;
      int calls = 0;
      const auto no = [&] { return ++calls, false; };
      std::vector<std::vector<S>> roots;
      REQUIRE(solveFaceWith(system, sys.p, lo, hi, roots, no));
      CHECK(roots.size() == 1u);
      CHECK(calls == 0);
      // A wide face: the same roots with a test that says no, asked at most once.
      const double w = 0.5 + 1.5 * unit(rng);
      for (int j = 0; j < m; ++j) lo[j] = sys.p[j] - w * unit(rng), hi[j] = lo[j] + w;
      std::vector<std::vector<S>> plain, with;
      const bool decided = solveFace(system, sys.p, lo, hi, plain);
      calls = 0;
      CHECK(solveFaceWith(system, sys.p, lo, hi, with, no) == decided);
      CHECK(calls <= 1);
      asked += calls;
      ++wide;
      if (decided) {
        REQUIRE(with.size() == plain.size());
        for (std::size_t r = 0; r < with.size(); ++r)
          for (int j = 0; j < n; ++j) CHECK(bool(with[r][j] == plain[r][j]));
      }
      // A test that says yes ends the face without roots wherever it is asked.
      calls = 0;
      std::vector<std::vector<S>> cut;
      const bool ended = solveFaceWith(system, sys.p, lo, hi, cut, [&] { return ++calls, true; });
      if (calls == 1) CHECK((ended && cut.empty()));
    }
  }
  INFO(asked << " of " << wide << " wide faces asked the test");
  CHECK(asked > 0);
}
