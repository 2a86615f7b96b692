// Singular points of M (pipeline/singular.hpp, docs/singular.md) through the whole
// pipeline (ndc::runPipeline, default settings): every case checks that a located point lies within
// one cell width (on every axis) of the true singular point, in double and MPFR (128 bits), and the
// smooth cases that nothing is reported.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "applications/load.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline/singular.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/projection/projection.hpp"
#include "strategies/subdivision/subdivision.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

using ndc::Problem;
using ndc::RunResult;
using ndc::Settings;

/// A problem in x, y, z (and w, u, ...) on a box, from its equations.
Problem inlineProblem(const std::vector<std::string>& variables,
                      const std::vector<std::pair<double, double>>& domain,
                      const std::vector<std::string>& equations) {
  std::ostringstream text;
  text.precision(17);
  text << "name = \"singular\"\nvariables = [";
  for (std::size_t j = 0; j < variables.size(); ++j)
    text << (j ? ", " : "") << '"' << variables[j] << '"';
  text << "]\ndomain = [";
  for (std::size_t j = 0; j < domain.size(); ++j)
    text << (j ? ", [" : "[") << domain[j].first << ", " << domain[j].second << "]";
  text << "]\nequations = [";
  for (std::size_t i = 0; i < equations.size(); ++i)
    text << (i ? ", " : "") << '"' << equations[i] << '"';
  text << "]\n";
  return ndc::parseProblem(text.str(), "singular.toml");
}

Problem cube(const std::vector<std::string>& equations, double half = 1) {
  return inlineProblem({"x", "y", "z"}, {{-half, half}, {-half, half}, {-half, half}}, equations);
}

Problem example(const std::string& name) {
  return ndc::loadProblem(fs::path(ndc::test::sourceDir()) / "experiments" / "problems" /
                          (name + ".toml"));
}

/// A run with the default settings (crossing connection) in scalar S, MPFR at 128 bits.
template <class S>
RunResult run(const Problem& problem, int depth) {
  ndc::test::PrecisionScope<S> scope(128);
  Settings s;
  s.depth = depth;
  s.scalar = std::is_same_v<S, double> ? "double" : "mpfr";
  s.precisionBits = std::is_same_v<S, double> ? 53 : 128;
  return ndc::runPipeline(problem, s);
}

/// Cell width of the run along each axis.
std::vector<double> cellWidths(const Problem& problem, int depth) {
  std::vector<double> w;
  for (int j = 0; j < problem.n(); ++j) w.push_back(problem.domain.width(j) / double(1 << depth));
  return w;
}

/// Whether `p` is within one cell width of `truth` on every axis.
bool within(const std::vector<double>& p, const std::vector<double>& truth,
            const std::vector<double>& width) {
  for (std::size_t j = 0; j < truth.size(); ++j)
    if (!(std::abs(p[j] - truth[j]) <= width[j])) return false;
  return true;
}

std::string describe(const RunResult& r) {
  std::ostringstream out;
  out.precision(10);
  out << r.summary.problem << " depth " << r.summary.settings.depth << " "
      << r.summary.settings.scalar << ": " << r.summary.singularPoints.size() << " singular points";
  for (const auto& p : r.summary.singularPoints) {
    out << "\n  (";
    for (std::size_t j = 0; j < p.point.size(); ++j) out << (j ? ", " : "") << p.point[j];
    out << ") sigma_min " << p.sigmaMin;
  }
  return out.str();
}

/// sigma_min of J at an accepted point: 1e-6 of the gradient scale in double, far less in MPFR.
template <class S>
double sigmaBound(double gradientScale) {
  return (std::is_same_v<S, double> ? 1e-6 : 1e-15) * gradientScale;
}

/// Exactly one singular point, within one cell width of `truth`.
//! [singular-check]
template <class S>
void checkIsolated(const Problem& problem, int depth, const std::vector<double>& truth,
                   double gradientScale) {
  const RunResult r = run<S>(problem, depth);
  INFO(describe(r));
  const auto& points = r.summary.singularPoints;
  REQUIRE(points.size() == 1);
  CHECK(within(points[0].point, truth, cellWidths(problem, depth)));
  CHECK(points[0].sigmaMin <= sigmaBound<S>(gradientScale));
}
//! [singular-check]

/// No singular point.
template <class S>
void checkSmooth(const Problem& problem, int depth) {
  const RunResult r = run<S>(problem, depth);
  INFO(describe(r));
  CHECK(r.summary.mesh.vertices > 0);
  CHECK(r.summary.singularPoints.empty());
}

}  // namespace

//! [singular-cases]
TEMPLATE_TEST_CASE("singular: double cone apex on a grid vertex", "[singular]", NDC_SCALARS) {
  // The apex (0, 0, 0) is a vertex of the grid on [-1, 1]^3 at every depth.
  const Problem cone = cube({"x^2 + y^2 - z^2"});
  for (int depth : {3, 4, 5}) {
    DYNAMIC_SECTION("depth " << depth) { checkIsolated<TestType>(cone, depth, {0, 0, 0}, 2.9); }
  }
}

TEMPLATE_TEST_CASE("singular: double cone apex off the grid", "[singular]", NDC_SCALARS) {
  const Problem cone = cube({"(x - 0.1234)^2 + (y + 0.071)^2 - (z - 0.0333)^2"});
  checkIsolated<TestType>(cone, 4, {0.1234, -0.071, 0.0333}, 2.9);
}

TEMPLATE_TEST_CASE("singular: Viviani's double point", "[singular]", NDC_SCALARS) {
  // The sphere and the cylinder tangent to it at (1, 0, 0), where the curve crosses itself.
  const Problem viviani = cube({"x^2 + y^2 + z^2 - 1", "(x - 0.5)^2 + y^2 - 0.25"}, 1.1);
  checkIsolated<TestType>(viviani, 5, {1, 0, 0}, 2.2);
}

TEMPLATE_TEST_CASE("singular: two spheres touching at a point", "[singular]", NDC_SCALARS) {
  // The product of the spheres |x -+ (0.5, 0, 0)| = 0.5: its gradient vanishes at the origin,
  // where they touch (a degenerate singular point: the Hessian has rank 1 there).
  const Problem spheres =
      inlineProblem({"x", "y", "z"}, {{-1.1, 1.1}, {-0.6, 0.6}, {-0.6, 0.6}},
                    {"((x - 0.5)^2 + y^2 + z^2 - 0.25) * ((x + 0.5)^2 + y^2 + z^2 - 0.25)"});
  checkIsolated<TestType>(spheres, 4, {0, 0, 0}, 1.5);
}

TEMPLATE_TEST_CASE("singular: Whitney umbrella", "[singular]", NDC_SCALARS) {
  // x^2 = y^2 z: the gradient (2x, -2yz, -y^2) vanishes on the whole z axis, which lies on M
  // (the double line for z > 0, the pinch point at the origin, the "handle" for z < 0). The
  // augmented system is degenerate along the axis (-y^2 = 0 has a double root), so Gauss-Newton
  // slides along it to the pinch point, where it converges (docs/singular.md). Expected: the
  // pinch point, every reported point within one cell of the axis, and a bounded number of
  // points (at most one per block of the grid the axis crosses: 8 at block level 3).
  const auto check = [](const Problem& umbrella, int depth) {
    const RunResult r = run<TestType>(umbrella, depth);
    INFO(describe(r));
    const auto& points = r.summary.singularPoints;
    const std::vector<double> w = cellWidths(umbrella, depth);
    REQUIRE(!points.empty());
    CHECK(points.size() <= 8);
    bool pinch = false;
    for (const auto& p : points) {
      CHECK(within(p.point, {0, 0, p.point[2]}, w));
      pinch = pinch || within(p.point, {0, 0, 0}, w);
    }
    CHECK(pinch);
  };
  SECTION("axis off the grid") {
    check(inlineProblem({"x", "y", "z"}, {{-0.93, 1.07}, {-1.04, 0.96}, {-1, 1}}, {"x^2 - y^2*z"}),
          5);
  }
  SECTION("axis on a grid line, pinch point on a grid vertex") { check(cube({"x^2 - y^2*z"}), 4); }
}

TEMPLATE_TEST_CASE("singular: a cone in a 3-flat of R^4", "[singular]", NDC_SCALARS) {
  const Problem cone = inlineProblem({"x", "y", "z", "w"}, {{-1, 1}, {-1, 1}, {-1, 1}, {-1, 1}},
                                     {"x^2 + y^2 - z^2", "w - 0.3*x - 0.2"});
  checkIsolated<TestType>(cone, 4, {0, 0, 0, 0.2}, 2.9);
}

TEMPLATE_TEST_CASE("singular: more isolated points", "[singular]", NDC_SCALARS) {
  SECTION("lemniscate of Bernoulli (R^2): its node on a grid vertex") {
    const Problem lemniscate =
        inlineProblem({"x", "y"}, {{-1.2, 1.2}, {-1.2, 1.2}}, {"(x^2 + y^2)^2 - (x^2 - y^2)"});
    checkIsolated<TestType>(lemniscate, 5, {0, 0}, 3);
  }
  SECTION("cone apex at a corner of the domain") {
    const Problem cone =
        inlineProblem({"x", "y", "z"}, {{0, 1}, {0, 1}, {0, 1}}, {"x^2 + y^2 - z^2"});
    checkIsolated<TestType>(cone, 4, {0, 0, 0}, 2.9);
  }
}

TEMPLATE_TEST_CASE("singular: Steinmetz curve, two double points", "[singular]", NDC_SCALARS) {
  // Two cylinders of radius 1 with perpendicular axes meet in two ellipses that cross at
  // (-1, 0, 0) and (1, 0, 0).
  const Problem steinmetz =
      inlineProblem({"x", "y", "z"}, {{-1.1, 1.13}, {-1.07, 1.1}, {-1.1, 1.1}},
                    {"x^2 + y^2 - 1", "x^2 + z^2 - 1"});
  const int depth = 5;
  const RunResult r = run<TestType>(steinmetz, depth);
  INFO(describe(r));
  const auto& points = r.summary.singularPoints;
  REQUIRE(points.size() == 2);  // sorted by coordinates
  const std::vector<double> w = cellWidths(steinmetz, depth);
  CHECK(within(points[0].point, {-1, 0, 0}, w));
  CHECK(within(points[1].point, {1, 0, 0}, w));
}

TEMPLATE_TEST_CASE("singular: the same points, bit for bit, on 1, 2 and 3 threads",
                   "[singular][threads]", NDC_SCALARS) {
  // Step 1 tests the cells in parallel and merges their gradient scales in cell order, which
  // step 3 divides by: any dependence on the schedule would move the located points' last bits.
  const Problem steinmetz =
      inlineProblem({"x", "y", "z"}, {{-1.1, 1.13}, {-1.07, 1.1}, {-1.1, 1.1}},
                    {"x^2 + y^2 - 1", "x^2 + z^2 - 1"});
  const Problem cone = cube({"x^2 + y^2 - z^2"});
  for (const Problem* problem : {&steinmetz, &cone}) {
    const auto pointsOn = [&](int threads) {
      return ndc::withThreads(threads, [&] { return run<TestType>(*problem, 5); })
          .summary.singularPoints;
    };
    const std::vector<ndc::SingularPoint> one = pointsOn(1);
    CHECK(!one.empty());
    for (const int threads : {2, 3}) {
      INFO(problem->name << " on " << threads << " threads");
      const std::vector<ndc::SingularPoint> other = pointsOn(threads);
      REQUIRE(other.size() == one.size());
      for (std::size_t p = 0; p < one.size(); ++p) {
        CHECK(other[p].point == one[p].point);
        CHECK(other[p].sigmaMin == one[p].sigmaMin);
      }
    }
  }
}

TEMPLATE_TEST_CASE("singular: smooth manifolds report none", "[singular]", NDC_SCALARS) {
  SECTION("sphere") { checkSmooth<TestType>(example("sphere"), 4); }
  SECTION("torus") { checkSmooth<TestType>(example("torus"), 4); }
  SECTION("circle in R^4") {
    checkSmooth<TestType>(
        inlineProblem(
            {"x", "y", "z", "w"}, {{-1.2, 1.2}, {-1.2, 1.2}, {-1.2, 1.2}, {-1.2, 1.2}},
            {"x^2 + y^2 + z^2 + w^2 - 1", "x + y - z + 0.5*w + 0.1", "0.5*x - y + z + w - 0.15"}),
        4);
  }
}
//! [singular-cases]

TEST_CASE("singular: a cone in a 3-flat of R^5", "[singular][slow]") {
  const Problem cone =
      inlineProblem({"x", "y", "z", "w", "u"}, {{-1, 1}, {-1, 1}, {-1, 1}, {-1, 1}, {-1, 1}},
                    {"x^2 + y^2 - z^2", "w - 0.3*x - 0.2", "u - 0.1*y + 0.3"});
  checkIsolated<double>(cone, 4, {0, 0, 0, 0.2, -0.3}, 2.9);
}

TEMPLATE_TEST_CASE("singular: deeper grids", "[singular][slow]", NDC_SCALARS) {
  SECTION("cone apex on a grid vertex, depth 6") {
    checkIsolated<TestType>(cube({"x^2 + y^2 - z^2"}), 6, {0, 0, 0}, 2.9);
  }
  SECTION("torus, depth 6") { checkSmooth<TestType>(example("torus"), 6); }
}

// --- findSingularPoints directly: the work it does and its caps
// -----------------------------------

namespace {

/// Subdivision and projection as the pipeline does them, then the search with `options`.
template <class S>
ndc::SingularSearch search(const Problem& problem, int depth, const ndc::SingularOptions& options) {
  ndc::test::PrecisionScope<S> scope(128);
  const ndc::Grid grid{problem.n(), depth, problem.domain};
  const ndc::Box<S> domain = problem.domainAs<S>();
  const ndc::System<S> system(problem);
  const ndc::Bounding<S> bounding = ndc::createBounding<S>("linearized", problem, domain);
  const ndc::SolutionCells cells =
      ndc::subdivide<S>(bounding, ndc::createSubdivision("binary"), grid, {});
  const ndc::Projection<S> projection = ndc::createProjection<S>("newton", system);
  const ndc::Projections<S> projections = ndc::projectCells<S>(projection, cells, domain, {});
  return ndc::findSingularPoints<S>(problem, system, projection, cells, projections, domain,
                                    options);
}

}  // namespace

TEMPLATE_TEST_CASE("singular: a smooth torus costs one Jacobian per cell", "[singular]",
                   NDC_SCALARS) {
  // At depth 5 the block Lipschitz test alone proves full rank in every cell: no Bernstein
  // enclosure, no candidate, no Gauss-Newton start.
  const ndc::SingularSearch s = search<TestType>(example("torus"), 5, {});
  CHECK(s.cells > 0);
  CHECK(s.excludedByLipschitz == s.cells);
  CHECK(s.candidates == 0);
  CHECK(s.attempts == 0);
  CHECK(s.points.empty());
}

TEMPLATE_TEST_CASE("singular: caps on points and starts", "[singular]", NDC_SCALARS) {
  const Problem steinmetz =
      inlineProblem({"x", "y", "z"}, {{-1.1, 1.13}, {-1.07, 1.1}, {-1.1, 1.1}},
                    {"x^2 + y^2 - 1", "x^2 + z^2 - 1"});
  SECTION("defaults: both double points, each candidate cell excluded or clustered") {
    const ndc::SingularSearch s = search<TestType>(steinmetz, 5, {});
    CHECK(s.points.size() == 2);
    CHECK(s.excludedByLipschitz + s.excludedByEnclosure + s.candidates == s.cells);
    CHECK(s.clusters <= s.candidates);
    CHECK(s.attempts <= 3 * s.clusters);
    CHECK(s.accepted >= 2);
  }
  SECTION("maxPoints = 1") {
    ndc::SingularOptions options;
    options.maxPoints = 1;
    CHECK(search<TestType>(steinmetz, 5, options).points.size() == 1);
  }
  SECTION("maxAttempts = 0") {
    ndc::SingularOptions options;
    options.maxAttempts = 0;
    const ndc::SingularSearch s = search<TestType>(steinmetz, 5, options);
    CHECK(s.candidates > 0);
    CHECK(s.attempts == 0);
    CHECK(s.points.empty());
  }
}
