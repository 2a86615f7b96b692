// The whole pipeline (docs/algorithm1.md, paper Algorithm 1) on known manifolds: every strategy
// runs on every example problem and every combination on some, the cell counts add up, double and
// MPFR agree on the cells and their classes, and the vertices lie on M to working precision.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "applications/load.hpp"
#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/subdivision/subdivision.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> exampleProblems() {
  std::vector<fs::path> files;
  for (const auto& entry :
       fs::directory_iterator(fs::path(ndc::test::sourceDir()) / "experiments" / "problems")) {
    if (entry.path().extension() == ".toml") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

ndc::Problem example(const std::string& name) {
  return ndc::loadProblem(fs::path(ndc::test::sourceDir()) / "experiments" / "problems" /
                          (name + ".toml"));
}

}  // namespace

//! [pipeline-every-strategy]
TEST_CASE("pipeline: every strategy runs on every example problem, every combination on some",
          "[pipeline][slow]") {
  const auto files = exampleProblems();
  REQUIRE(files.size() >= 8);
  const auto boundings = ndc::boundingRegistry().names();
  const auto subdivisions = ndc::subdivisionRegistry().names();
  const auto connections = ndc::connectionRegistry().names();
  const ndc::Settings defaults;
  // The combinations, in a fixed order: problem p runs every model of each family with the
  // other two at their defaults, and the combinations j with j = p (mod the problem count), so
  // every combination runs on some problem. (The whole product on every problem took 409 s of
  // the slow suite's 489 s for the same failures.)
  struct Combination {
    std::string bounding, subdivision, connection;
  };
  std::vector<Combination> all;
  for (const std::string& b : boundings)
    for (const std::string& s : subdivisions)
      for (const std::string& c : connections) all.push_back({b, s, c});
  // The rotation runs over the curves and surfaces, which every connection builds; a k >= 3
  // example in R^4 or R^5 runs each bounding and subdivision with the crossing connection (the
  // only one that builds it). Those in R^6 and beyond cost tens of seconds each in this loop,
  // O(3) in R^9 minutes at any depth (docs/crossing.md, "Any k");
  // tests/strategies/test_higher_crossing.cpp solves them with the defaults.
  std::vector<ndc::Problem> problems;
  std::size_t rotation = 0;
  for (const fs::path& file : files) {
    problems.push_back(ndc::loadProblem(file));
    rotation += problems.back().k() <= 2;
  }
  std::size_t combinationsRun = 0, turn = 0;
  for (const ndc::Problem& problem : problems) {
    if (problem.k() >= 3 && problem.n() > 5) continue;
    const bool rotates = problem.k() <= 2;
    for (std::size_t j = 0; j < all.size(); ++j) {
      const Combination& c = all[j];
      const int defaultsKept = (c.bounding == defaults.bounding) +
                               (c.subdivision == defaults.subdivision) +
                               (c.connection == defaults.connection);
      const bool rotated = rotates && j % rotation == turn;
      if (defaultsKept < 2 && !rotated) continue;
      if (!rotates && c.connection != defaults.connection) continue;
      ++combinationsRun;
      ndc::Settings settings;
      // Small depths: this checks that every combination runs end to end and that its counts
      // are consistent, not the quality of the result.
      settings.depth = problem.n() <= 4 ? 3 : 2;
      settings.bounding = c.bounding;
      settings.subdivision = c.subdivision;
      settings.connection = c.connection;
      INFO(problem.name << " " << c.bounding << " " << c.subdivision << " " << c.connection);
      const ndc::Summary s = ndc::runPipeline(problem, settings).summary;
      CHECK(s.normal + s.abnormal + s.failed == s.solution);
      CHECK(s.visited >= s.solution);
      CHECK(s.solution > 0);
      CHECK(s.mesh.vertices > 0);
    }
    turn += rotates;
  }
  CHECK(combinationsRun >= all.size());
}
//! [pipeline-every-strategy]

//! [pipeline-cells-add-up]
TEMPLATE_TEST_CASE("pipeline: cells add up and vertices lie on M", "[pipeline]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const bool mpfr = !std::is_same_v<TestType, double>;
  for (const char* name : {"circle", "circle-3d", "space-curve-r4", "circle-r5", "sphere",
                           "clifford-torus", "torus"}) {
    const ndc::Problem problem = example(name);
    for (const std::string& connection : ndc::connectionRegistry().names()) {
      ndc::Settings settings;
      settings.depth = 4;
      settings.connection = connection;
      settings.scalar = mpfr ? "mpfr" : "double";
      settings.precisionBits = 128;
      INFO(name << " " << connection << " " << settings.scalar);
      const ndc::RunResult r = ndc::runPipeline(problem, settings);
      const ndc::Summary& s = r.summary;
      CHECK(s.normal + s.abnormal + s.failed == s.solution);
      CHECK(s.failed == 0);
      CHECK(s.mesh.vertices > 0);
      CHECK(s.mesh.maxResidual <= (mpfr ? 1e-30 : 1e-10));
      CHECK(r.cellClass.size() == static_cast<std::size_t>(s.solution));
    }
  }
}
//! [pipeline-cells-add-up]

TEST_CASE("pipeline: double and mpfr give the same cells and classes", "[pipeline][mpfr]") {
  ndc::test::PrecisionScope<ndc::Mpfr> scope(128);
  for (const char* name : {"circle", "circle-3d", "sphere", "torus", "clifford-torus"}) {
    const ndc::Problem problem = example(name);
    // On the natural grid (the Clifford torus meets cell faces): a projected point within
    // rounding of its cell's boundary is normal or abnormal by that rounding, so those cells
    // (ties) are not compared; every other class must agree.
    ndc::Settings settings;
    settings.depth = 4;
    settings.connection = "crossing";
    const ndc::RunResult d = ndc::runPipeline(problem, settings);
    settings.scalar = "mpfr";
    settings.precisionBits = 128;
    const ndc::RunResult m = ndc::runPipeline(problem, settings);
    INFO(name);
    REQUIRE(d.cellIndex == m.cellIndex);
    REQUIRE(d.cellClass.size() == m.cellClass.size());
    const int n = problem.n();
    std::size_t ties = 0, compared = 0;
    for (std::size_t c = 0; c < d.cellClass.size(); ++c) {
      // Distance of the double projection to the cell's boundary, in cell widths.
      double margin = 1;
      for (int j = 0; j < n; ++j) {
        const double width = (problem.domain.hi[j] - problem.domain.lo[j]) / (1 << settings.depth);
        const double offset = std::abs(d.cellPoint[c * n + j] - d.cellCentre[c * n + j]) / width;
        margin = std::min(margin, std::abs(0.5 - offset));
      }
      if (margin < 1e-9) {
        ++ties;
        continue;
      }
      ++compared;
      INFO("cell " << c << " margin " << margin);
      CHECK(d.cellClass[c] == m.cellClass[c]);
    }
    // The Clifford torus passes through the grid vertices (+-0.5, +-0.5, ., .): 704 of its
    // 2304 cells project exactly onto one.
    INFO(ties << " ties, " << compared << " compared");
    CHECK(compared >= ties);
    CHECK(d.summary.mesh.components == m.summary.mesh.components);
    CHECK(d.summary.mesh.eulerCharacteristic == m.summary.mesh.eulerCharacteristic);
  }
}

//! [pipeline-paper-curves]
TEST_CASE("pipeline: the paper connection closes well-resolved curves in R^3..R^6", "[pipeline]") {
  for (const char* name : {"circle-3d", "space-curve-r4", "circle-r5", "circle-r6"}) {
    const ndc::Problem problem = example(name);
    ndc::Settings settings;
    settings.depth = 5;
    settings.connection = "paper";
    INFO(name);
    const ndc::Summary s = ndc::runPipeline(problem, settings).summary;
    CHECK(s.mesh.components == 1);
    CHECK(s.mesh.openEnds == 0);
    CHECK(s.mesh.branchVertices == 0);
    CHECK(s.mesh.maxResidual <= 1e-10);
  }
}
//! [pipeline-paper-curves]

TEST_CASE("pipeline: bad settings are input errors", "[pipeline]") {
  const ndc::Problem problem = example("circle");
  ndc::Settings settings;
  settings.bounding = "hull";
  CHECK_THROWS_AS(ndc::runPipeline(problem, settings), ndc::InputError);
  settings = {};
  settings.depth = 40;
  CHECK_THROWS_AS(ndc::runPipeline(problem, settings), ndc::InputError);
  settings = {};
  settings.scalar = "float";
  CHECK_THROWS_AS(ndc::runPipeline(problem, settings), ndc::InputError);
}
