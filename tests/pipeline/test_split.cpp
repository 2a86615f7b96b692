// The plan of a split solve (pipeline/split.hpp): the pieces tile the domain on grid planes,
// neighbours share their faces to the last bit, and what a split cannot do is refused.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "framework/util/errors.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline/split.hpp"
#include "tests/test_support.hpp"

namespace {

ndc::Problem boxProblem(const std::vector<double>& lo, const std::vector<double>& hi) {
  std::vector<std::string> equations;
  std::string sphere;
  for (std::size_t j = 0; j < lo.size(); ++j)
    sphere += (j ? " + x" : "x") + std::to_string(j) + "^2";
  equations.push_back(sphere + " - 1");
  ndc::Problem problem = ndc::test::makeProblem(static_cast<int>(lo.size()), equations);
  problem.domain.lo = lo;
  problem.domain.hi = hi;
  return problem;
}

}  // namespace

TEST_CASE("split: the pieces tile the domain on planes of the grid", "[split]") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 5);
    std::vector<double> lo(n), hi(n);
    std::uniform_real_distribution<double> corner(-3, 1), width(0.1, 4);
    for (int j = 0; j < n; ++j) lo[j] = corner(rng), hi[j] = lo[j] + width(rng);
    const ndc::Problem problem = boxProblem(lo, hi);
    ndc::Settings settings;
    settings.depth = 4;
    const int halvings = static_cast<int>(rng() % std::min(9, 3 * n + 1));
    const ndc::SplitPlan plan = ndc::planSplit(problem, settings, 1 << halvings);
    INFO("n " << n << ", 2^" << halvings << " pieces");
    REQUIRE(plan.boxes.size() == std::size_t{1} << halvings);
    CHECK(plan.levels == halvings / n);
    CHECK(plan.pieceDepth == 4 - halvings / n);
    CHECK(plan.pieceMaxDepth == ndc::maxDepthOf(problem, settings) - halvings / n);
    double volume = 0, whole = 1;
    for (int j = 0; j < n; ++j) whole *= hi[j] - lo[j];
    for (const ndc::Box<double>& box : plan.boxes) {
      double v = 1;
      for (int j = 0; j < n; ++j) {
        // Each end is a plane of the whole grid (2^depth cells per axis).
        const double cells = (box.lo[j] - lo[j]) / (hi[j] - lo[j]) * 16;
        CHECK(std::abs(cells - std::round(cells)) < 1e-9);
        v *= box.hi[j] - box.lo[j];
      }
      volume += v;
    }
    CHECK(volume == Approx(whole).epsilon(1e-12));
    // Neighbours along an axis share that face to the last bit.
    for (const ndc::Box<double>& a : plan.boxes)
      for (const ndc::Box<double>& b : plan.boxes)
        for (int j = 0; j < n; ++j)
          if (std::abs(a.hi[j] - b.lo[j]) < 1e-9 * (hi[j] - lo[j])) CHECK(a.hi[j] == b.lo[j]);
  }
}

TEST_CASE("split: what a split cannot do is refused with one line", "[split]") {
  const ndc::Problem problem = boxProblem({-1, -1, -1}, {1, 1, 1});
  ndc::Settings settings;
  settings.depth = 2;
  for (int pieces : {0, 3, 6, 1024, -4})
    CHECK_THROWS_AS(ndc::planSplit(problem, settings, pieces), ndc::UsageError);
  // 2^6 pieces in R^3 are boxes of the depth-2 grid: depth 2 leaves them no level.
  CHECK_THROWS_WITH(ndc::planSplit(problem, settings, 64),
                    Catch::Contains("needs --depth 3 or more"));
  CHECK_NOTHROW(ndc::planSplit(problem, settings, 32));
  settings.jitter = 5;
  CHECK_THROWS_WITH(ndc::planSplit(problem, settings, 8), Catch::Contains("--jitter"));
}

TEST_CASE("split: --domain text reads back to the same box", "[split]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> value(-1e3, 1e3);
  for (int trial = 0; trial < 50; ++trial) {
    ndc::Box<double> box;
    for (int j = 0; j < 4; ++j) {
      const double a = value(rng), b = value(rng);
      box.lo.push_back(std::min(a, b));
      box.hi.push_back(std::max(a, b) + 1e-300);
    }
    const ndc::Box<double> back = ndc::parseDomainText(ndc::domainText(box), 4);
    CHECK(back.lo == box.lo);
    CHECK(back.hi == box.hi);
  }
  for (const char* bad :
       {"", "1:2", "0:1,0:1,1:0", "0:1,0:1,a:2", "0:1,0:1,0:inf", "0:1,0:1,0-1", "0:1,0:1,0:1,0:1"})
    CHECK_THROWS_AS(ndc::parseDomainText(bad, 3), ndc::UsageError);
}
