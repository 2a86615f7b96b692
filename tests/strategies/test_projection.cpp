// Tests of the projection (minimum-norm Newton) and classification families.
#include <catch2/catch.hpp>

#include <boost/multiprecision/eigen.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "framework/numeric/iteration.hpp"
#include "framework/numeric/minimum_norm.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/projection/projection.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::toDouble;
using ndc::test::makeProblem;

/// Residual the tests demand at converged points: 1e-10 in double, 1e-30 in MPFR at 128 bits.
template <class S>
double residualLimit() {
  return std::is_same_v<S, double> ? 1e-10 : 1e-30;
}

/// Agreement with a closed-form answer.
template <class S>
double tight() {
  return std::is_same_v<S, double> ? 1e-12 : 1e-30;
}

template <class S>
S norm(std::span<const S> x) {
  using std::sqrt;
  S s = 0;
  for (const S& v : x) s += v * v;
  return sqrt(s);
}

template <class S>
S distance(std::span<const S> a, std::span<const S> b) {
  using std::sqrt;
  S s = 0;
  for (std::size_t j = 0; j < a.size(); ++j) s += (a[j] - b[j]) * (a[j] - b[j]);
  return sqrt(s);
}

/// A random direction scaled to length `r` (from double draws).
template <class S>
std::vector<S> randomPoint(std::mt19937& rng, int n, double r) {
  std::normal_distribution<double> g;
  std::vector<S> x(n);
  for (auto& v : x) v = S(g(rng));
  const S len = norm<S>(x);
  for (auto& v : x) v = v / len * S(r);
  return x;
}

}  // namespace

TEMPLATE_TEST_CASE("The minimum-norm solver against the pseudo-inverse", "[projection]",
                   NDC_SCALARS) {
  // Generated m x n systems (1 <= m <= n <= 9, rows of mixed scales): s solves J s = f to
  // rounding and lies in J's row space (J^T y for the y of J J^T y = f, solved independently
  // in 160 bits), so it is J^+ f. A row repeated, or a row that is a combination of the others,
  // makes factor decline; rows that are mirror images give mirror-image steps.
  using S = TestType;
  ndc::test::PrecisionScope<S> scope(128);
  const S eps = ndc::ScalarTraits<S>::epsilon();
  std::mt19937 rng(1973);
  ndc::MinimumNormSolver<S> solver;
  const S threshold = S(8 * 9) * eps;
  int solved = 0;
  for (int n = 1; n <= 9; ++n)
    for (int m = 1; m <= n; ++m)
      for (int trial = 0; trial < 6; ++trial) {
        std::vector<S> jac(std::size_t(m) * n), f(m), s(n);
        for (int i = 0; i < m; ++i) {
          const double scale = std::pow(10.0, ndc::test::uniform<double>(rng, -3, 3));
          for (int j = 0; j < n; ++j)
            jac[std::size_t(i) * n + j] = S(scale * ndc::test::uniform<double>(rng, -1, 1));
          f[i] = S(ndc::test::uniform<double>(rng, -1, 1));
        }
        REQUIRE(solver.factor(jac.data(), m, n, threshold));
        solver.solve(f.data(), s.data());
        ++solved;
        // The exact minimum-norm solution in 160 bits: s* = J^T y, (J J^T) y = f.
        ndc::test::PrecisionScope<ndc::Mpfr> exact(160);
        using Big = Eigen::Matrix<ndc::Mpfr, Eigen::Dynamic, Eigen::Dynamic>;
        Big a(m, n), rhs(m, 1);
        for (int i = 0; i < m; ++i) {
          rhs(i, 0) = ndc::Mpfr(toDouble(f[i]));
          for (int j = 0; j < n; ++j) a(i, j) = ndc::Mpfr(toDouble(jac[std::size_t(i) * n + j]));
        }
        const Big y = (a * a.transpose()).fullPivLu().solve(rhs);
        const Big truth = a.transpose() * y;
        // A solver of the minimum-norm problem that is stable for it errs by about
        // eps kappa(J) |s| (kappa the ratio of J's extreme singular values).
        const auto sigma = Eigen::JacobiSVD<Big>(a).singularValues();
        const double kappa = toDouble(sigma(0)) / toDouble(sigma(m - 1));
        double size = 0, error = 0;
        for (int j = 0; j < n; ++j) {
          size = std::max(size, std::abs(toDouble(truth(j, 0))));
          error = std::max(error, std::abs(toDouble(truth(j, 0)) - toDouble(s[j])));
        }
        INFO("m = " << m << ", n = " << n << ", trial " << trial << ", kappa " << kappa);
        CHECK(error <= 64 * n * toDouble(eps) * kappa * size);
      }
  CHECK(solved == 45 * 6);
  // Rank deficiency: a repeated row, and the sum of two rows.
  const std::vector<S> repeated = {S(1), S(2), S(3), S(1), S(2), S(3)};
  CHECK_FALSE(solver.factor(repeated.data(), 2, 3, threshold));
  const std::vector<S> summed = {S(1), S(0), S(2), S(0), S(1), S(-1), S(1), S(1), S(1)};
  CHECK_FALSE(solver.factor(summed.data(), 3, 3, threshold));
  // Mirror images: rows (a, a, 0, 0) and (0, 0, b, b) give s_0 = s_1 and s_2 = s_3 exactly.
  const std::vector<S> mirrored = {S(0.7), S(0.7), S(0), S(0), S(0), S(0), S(1.3), S(1.3)};
  const std::vector<S> f = {S(0.1), S(-0.3)};
  std::vector<S> s(4);
  REQUIRE(solver.factor(mirrored.data(), 2, 4, threshold));
  solver.solve(f.data(), s.data());
  CHECK(s[0] == s[1]);
  CHECK(s[2] == s[3]);
}

TEMPLATE_TEST_CASE("Newton projects onto the circle and sphere radially", "[projection]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  for (int n : {2, 3}) {
    INFO("n = " << n);
    const ndc::Problem problem =
        makeProblem(n, {n == 2 ? "x0^2 + x1^2 - 1" : "x0^2 + x1^2 + x2^2 - 1"});
    const ndc::System<S> system(problem);
    const ndc::NewtonProjection<S> newton(system);
    std::mt19937 rng(7 + n);
    std::uniform_real_distribution<double> radius(0.3, 2.5);
    for (int trial = 0; trial < 40; ++trial) {
      std::vector<S> x = randomPoint<S>(rng, n, radius(rng));
      // Minimum-norm steps follow the gradient, which is radial: the nearest point x / |x|.
      std::vector<S> nearest = x;
      const S len = norm<S>(x);
      for (auto& v : nearest) v /= len;
      const auto r = newton.project(x);
      REQUIRE(r.converged);
      CHECK(r.iterations > 0);
      CHECK(r.iterations < 15);
      CHECK(toDouble(system.maxResidual(x)) <= residualLimit<S>());
      CHECK(toDouble(distance<S>(x, nearest)) <= tight<S>());
      // A point that is already on M stays where it is.
      const std::vector<S> before = x;
      const auto again = newton.project(x);
      CHECK(again.converged);
      CHECK(again.iterations == 0);
      CHECK(x == before);
    }
  }
}

//! [newton-nearest]
TEMPLATE_TEST_CASE("Newton from (2, 0) lands on the nearest point (1, 0)", "[projection]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  const ndc::Problem problem = makeProblem(2, {"x0^2 + x1^2 - 1"});
  const ndc::System<S> system(problem);
  const ndc::NewtonProjection<S> newton(system);
  std::vector<S> x{S(2), S(0)};
  const auto r = newton.project(x);
  REQUIRE(r.converged);
  CHECK(toDouble(abs(x[0] - S(1))) <= tight<S>());
  CHECK(toDouble(abs(x[1])) <= tight<S>());

  // A point given on M (to the working precision of its decimal literals) is not moved.
  std::vector<S> onCircle{ndc::ScalarTraits<S>::fromString("0.6"),
                          ndc::ScalarTraits<S>::fromString("0.8")};
  const std::vector<S> before = onCircle;
  const auto stay = newton.project(onCircle);
  CHECK(stay.converged);
  CHECK(stay.iterations == 0);
  CHECK(onCircle == before);
}
//! [newton-nearest]

TEMPLATE_TEST_CASE("Newton converges onto a torus in R^3", "[projection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  // Ring torus with R = 1, r = 0.4 (R^2 - r^2 = 0.84).
  const ndc::Problem problem = makeProblem(3, {"(x0^2 + x1^2 + x2^2 + 0.84)^2 - 4*(x0^2 + x1^2)"});
  const ndc::System<S> system(problem);
  const ndc::NewtonProjection<S> newton(system);
  const auto torusDistance = [](std::span<const S> p) {
    const S rho = sqrt(p[0] * p[0] + p[1] * p[1]) - 1;
    return sqrt(rho * rho + p[2] * p[2]) - ndc::ScalarTraits<S>::fromString("0.4");
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI), offset(-0.05, 0.05);
  for (int trial = 0; trial < 40; ++trial) {
    const double u = angle(rng), v = angle(rng);
    std::vector<S> x{S((1 + 0.4 * std::cos(v)) * std::cos(u) + offset(rng)),
                     S((1 + 0.4 * std::cos(v)) * std::sin(u) + offset(rng)),
                     S(0.4 * std::sin(v) + offset(rng))};
    const std::vector<S> start = x;
    const S startDistance = abs(torusDistance(start));
    const auto r = newton.project(x);
    REQUIRE(r.converged);
    CHECK(toDouble(system.maxResidual(x)) <= residualLimit<S>());
    CHECK(toDouble(abs(torusDistance(x))) <= tight<S>());
    // Minimum norm: the point found is nearly the nearest one (second order in the offset).
    CHECK(toDouble(distance<S>(x, start)) <= 1.05 * toDouble(startDistance) + tight<S>());
  }
}

TEMPLATE_TEST_CASE("Newton converges onto the Clifford torus in R^4", "[projection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  const ndc::Problem problem = makeProblem(4, {"x0^2 + x1^2 - 0.5", "x2^2 + x3^2 - 0.5"});
  const ndc::System<S> system(problem);
  const ndc::NewtonProjection<S> newton(system);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> coordinate(-1.2, 1.2);
  const S half = sqrt(S(ndc::ScalarTraits<S>::fromString("0.5")));
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<S> x(4);
    for (auto& v : x) v = S(coordinate(rng));
    // The equations decouple: the nearest point is radial in the (x0, x1) and (x2, x3) planes.
    std::vector<S> nearest = x;
    for (int plane : {0, 2}) {
      const S len = sqrt(x[plane] * x[plane] + x[plane + 1] * x[plane + 1]);
      nearest[plane] = x[plane] / len * half;
      nearest[plane + 1] = x[plane + 1] / len * half;
    }
    const auto r = newton.project(x);
    REQUIRE(r.converged);
    CHECK(toDouble(system.maxResidual(x)) <= residualLimit<S>());
    CHECK(toDouble(distance<S>(x, nearest)) <= tight<S>());
  }
}

TEMPLATE_TEST_CASE("Newton converges onto a circle in R^8", "[projection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  // The unit sphere of R^8 cut by 6 affine hyperplanes: a circle in a 2-plane near the origin.
  const ndc::Problem problem = makeProblem(
      8,
      {"x0^2 + x1^2 + x2^2 + x3^2 + x4^2 + x5^2 + x6^2 + x7^2 - 1", "x2 - 0.1*x0 + 0.2*x1 - 0.05",
       "x3 + 0.3*x0 - 0.1*x1 + 0.1", "x4 - 0.2*x0 - 0.2*x1", "x5 + 0.1*x0 + 0.4*x1 - 0.02",
       "x6 - 0.25*x0 + 0.05*x1 + 0.03", "x7 + 0.15*x0 - 0.3*x1 - 0.07"},
      2);
  const ndc::System<S> system(problem);
  const ndc::NewtonProjection<S> newton(system);
  std::mt19937 rng(17);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<S> x = randomPoint<S>(rng, 8, 0.5 + 0.1 * (trial % 10));
    const auto r = newton.project(x);
    REQUIRE(r.converged);
    CHECK(r.iterations < 20);
    CHECK(toDouble(system.maxResidual(x)) <= residualLimit<S>());
    CHECK(std::abs(toDouble(norm<S>(x)) - 1) <= 1e-12);
  }
}

//! [newton-failed]
TEMPLATE_TEST_CASE("Newton reports non-convergence", "[projection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  SECTION("no real zero: x^2 + y^2 + 1 = 0") {
    const ndc::Problem problem = makeProblem(2, {"x0^2 + x1^2 + 1"});
    const ndc::System<S> system(problem);
    const ndc::NewtonProjection<S> newton(system);
    std::mt19937 rng(19);
    std::uniform_real_distribution<double> coordinate(-2, 2);
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<S> x{S(coordinate(rng)), S(coordinate(rng))};
      CHECK_FALSE(newton.project(x).converged);
    }
    // A zero Jacobian at the start: rank deficient, no step.
    std::vector<S> origin{S(0), S(0)};
    const auto atOrigin = newton.project(origin);
    CHECK_FALSE(atOrigin.converged);
    CHECK(atOrigin.iterations == 0);
    // A nearly flat start throws the iterate far away: divergence stops at once.
    std::vector<S> flat{S(1e-9), S(0)};
    const auto diverged = newton.project(flat);
    CHECK_FALSE(diverged.converged);
    CHECK(diverged.iterations == 1);
  }
  SECTION("a Newton 2-cycle: x^3 - 2x + 2 from x = 0") {
    const ndc::Problem problem = makeProblem(2, {"x0^3 - 2*x0 + 2"});
    const ndc::System<S> system(problem);
    const ndc::NewtonProjection<S> newton(system, 25);
    std::vector<S> x{S(0), S(0.3)};
    const auto r = newton.project(x);
    CHECK_FALSE(r.converged);
    CHECK(r.iterations == 25);
    // The y coordinate is free: minimum-norm steps never move it.
    CHECK(x[1] == S(0.3));
  }
}
//! [newton-failed]

TEMPLATE_TEST_CASE("The residual tolerance scales with the precision and the terms", "[projection]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  const ndc::Problem problem = makeProblem(3, {"x0^2 + x1^2 - 1", "1000*x0 - 1000"}, 3);
  const ndc::System<S> system(problem);
  const ndc::NewtonProjection<S> newton(system);
  const double eps = toDouble(ndc::ScalarTraits<S>::epsilon());
  std::vector<S> x{S(1), S(0), S(0)}, tol(2);
  newton.residualTolerance(x, tol);
  // Both are a small multiple of eps times the magnitude of the terms (3 and 2000 here).
  CHECK(toDouble(tol[0]) >= 3 * eps);
  CHECK(toDouble(tol[0]) <= 100 * 3 * eps);
  CHECK(toDouble(tol[1]) >= 2000 * eps);
  CHECK(toDouble(tol[1]) <= 100 * 2000 * eps);
  // Larger points, larger terms.
  std::vector<S> far{S(10), S(0), S(0)}, tolFar(2);
  newton.residualTolerance(far, tolFar);
  CHECK(toDouble(tolFar[0]) > 30 * toDouble(tol[0]));
}

TEMPLATE_TEST_CASE("createProjection and projectCells", "[projection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  const ndc::Problem problem = makeProblem(2, {"x0^2 + x1^2 - 1"}, 1.5);
  const ndc::System<S> system(problem);
  CHECK_THROWS_AS(ndc::createProjection<S>("bogus", system), ndc::InputError);
  const ndc::Projection<S> projection = ndc::createProjection<S>("newton", system);

  // Every cell of the 4 x 4 grid on [-1.5, 1.5]^2 (no centroid is at the origin).
  ndc::SolutionCells cells;
  cells.grid.n = 2;
  cells.grid.depth = 2;
  cells.grid.domain = problem.domain;
  for (std::int32_t i = 0; i < 4; ++i) {
    for (std::int32_t j = 0; j < 4; ++j) {
      const std::int32_t index[2] = {i, j};
      cells.add(index);
    }
  }
  const ndc::Box<S> domain = problem.domainAs<S>();
  double lastFraction = 0;
  int calls = 0;
  const ndc::Projections<S> out =
      ndc::projectCells<S>(projection, cells, domain, [&](const char* stage, double f) {
        CHECK(std::string(stage) == "projection");
        CHECK(f >= lastFraction);
        lastFraction = f;
        ++calls;
      });
  CHECK(calls > 0);
  CHECK(lastFraction == 1.0);
  REQUIRE(out.n == 2);
  REQUIRE(out.converged.size() == 16);
  const ndc::Projector<S> project = ndc::makeProjector(projection);
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const ndc::Box<S> box = ndc::cellBox<S>(cells.grid, domain, cells.cell(c));
    std::vector<S> centre{(box.lo[0] + box.hi[0]) / 2, (box.lo[1] + box.hi[1]) / 2};
    const S len = norm<S>(centre);
    std::vector<S> nearest{centre[0] / len, centre[1] / len};
    CHECK(out.converged[c] == 1);
    CHECK(toDouble(distance<S>(out.at(c), nearest)) <= tight<S>());
    // The Projector wrapper does the same.
    const auto r = project(centre);
    CHECK(r.converged);
    CHECK(r.iterations == out.iterations[c]);
    CHECK(toDouble(distance<S>(centre, out.at(c))) == 0.0);
  }
}

//! [classification-paper]
TEMPLATE_TEST_CASE("Paper classification of known points", "[classification]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using ndc::CellClass;
  using std::abs;
  using std::sqrt;
  const ndc::PaperClassification paper;
  const ndc::Box<S> box{{S(0), S(-1), S(2)}, {S(1), S(1), S(4)}};
  const auto classify = [&](std::vector<S> p, bool converged) {
    return paper.classify<S>(box, p, converged);
  };
  CHECK(classify({S(0.5), S(0), S(3)}, true) == CellClass::kNormal);
  // The cell is closed: faces, edges and corners are inside.
  CHECK(classify({S(1), S(0), S(3)}, true) == CellClass::kNormal);
  CHECK(classify({S(0), S(-1), S(2)}, true) == CellClass::kNormal);
  CHECK(classify({S(1), S(1), S(4)}, true) == CellClass::kNormal);
  // Just outside one face: abnormal.
  const S tiny = ndc::ScalarTraits<S>::epsilon() * 4;
  CHECK(classify({S(1) + tiny, S(0), S(3)}, true) == CellClass::kAbnormal);
  CHECK(classify({S(0.5), S(-1) - tiny, S(3)}, true) == CellClass::kAbnormal);
  CHECK(classify({S(0.5), S(0), S(7)}, true) == CellClass::kAbnormal);
  // No convergence: failed, wherever the point is.
  CHECK(classify({S(0.5), S(0), S(3)}, false) == CellClass::kFailed);
  CHECK(classify({S(9), S(9), S(9)}, false) == CellClass::kFailed);
}
//! [classification-paper]

//! [classify-cells]
TEMPLATE_TEST_CASE("classifyCells labels a grid from its projections", "[classification]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::abs;
  using std::sqrt;
  CHECK_THROWS_AS(ndc::createClassification("bogus"), ndc::InputError);
  const ndc::Classification classification = ndc::createClassification("paper");

  const ndc::Problem problem = makeProblem(2, {"x0^2 + x1^2 - 1"}, 1.5);
  ndc::SolutionCells cells;
  cells.grid.n = 2;
  cells.grid.depth = 2;
  cells.grid.domain = problem.domain;
  // Cells [0, 0.75] x [0.75, 1.5] (holds the projection of its centroid), [0, 0.75]^2
  // (its point (0.8, 0.6) lies outside it) and [0.75, 1.5] x [0, 0.75] (marked not converged).
  const std::int32_t indices[3][2] = {{2, 3}, {2, 2}, {3, 2}};
  for (const auto& index : indices) cells.add(index);
  ndc::Projections<S> projections;
  projections.n = 2;
  projections.point = {S(0.375) / sqrt(S(0.375 * 0.375 + 1.125 * 1.125)),
                       S(1.125) / sqrt(S(0.375 * 0.375 + 1.125 * 1.125)),
                       S(0.8),
                       S(0.6),
                       S(1),
                       S(0.2)};
  projections.converged = {1, 1, 0};
  projections.iterations = {3, 3, 40};
  const std::vector<ndc::CellClass> classes =
      ndc::classifyCells<S>(classification, cells, problem.domainAs<S>(), projections);
  REQUIRE(classes.size() == 3);
  CHECK(classes[0] == ndc::CellClass::kNormal);
  CHECK(classes[1] == ndc::CellClass::kAbnormal);
  CHECK(classes[2] == ndc::CellClass::kFailed);
}
//! [classify-cells]

TEMPLATE_TEST_CASE("Newton iterations share their stopping rules and step halving", "[projection]",
                   NDC_SCALARS) {
  using S = TestType;
  ndc::test::PrecisionScope<S> precision;
  const std::vector<S> start{S(3), S(-4)};
  const ndc::IterationGuard<S> guard{std::span<const S>(start)};
  // Divergence: beyond 1e4 (1 + |x0|) = 50000, or not finite.
  CHECK_FALSE(guard.diverged(S(49999)));
  CHECK(guard.diverged(S(50001)));
  CHECK(guard.diverged(S(std::numeric_limits<double>::infinity())));
  CHECK(guard.diverged(S(std::numeric_limits<double>::quiet_NaN())));
  // Stagnation: a step within 16 eps (1 + |x|) of the iterate.
  const S eps = ndc::ScalarTraits<S>::epsilon();
  CHECK(ndc::IterationGuard<S>::stagnated(S(15) * eps * 2, S(1)));
  CHECK_FALSE(ndc::IterationGuard<S>::stagnated(S(17) * eps * 2, S(1)));
  // Step halving: the first accepted lambda, in order 1, 1/2, 1/4, ...; 0 when none is.
  std::vector<S> tried;
  const S lambda = ndc::halveStep<S>(10, [&](const S& t, int halving) {
    tried.push_back(t);
    CHECK(halving + 1 == static_cast<int>(tried.size()));
    return t < S(0.2);
  });
  CHECK(lambda == S(0.125));
  CHECK(tried.size() == 4);
  CHECK(ndc::halveStep<S>(5, [](const S&, int) { return false; }) == S(0));
}
