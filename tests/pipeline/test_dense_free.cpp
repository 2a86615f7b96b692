// Quadrics past the dense forms' cap (issue 42, docs/performance.md "Without dense forms"): a
// circle in R^13 and R^14 has a quadric of 3^13 = 1.6e6 and 3^14 = 4.8e6 Bernstein
// coefficients, over ndc::kMaxCoefficients. The reader accepts it (ndc::densityFree), the
// default strategies solve it without building a dense form, and the certificate still holds
// on seeded random embeddings. The `bernstein` bounding, which needs the form, refuses it, and
// an equation that vanishes everywhere is still refused.
#include <catch2/catch.hpp>

#include <string>
#include <type_traits>

#include "experiments/runner/generate.hpp"
#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_support.hpp"

namespace {

/// Solves the rotated circle (n, seed) at `depth` with the defaults in scalar S and checks the
/// certified topology against the generator's truth, and the vertices on M.
template <class S>
void solveWithoutForms(int n, std::uint64_t seed, int depth) {
  ndc::test::PrecisionScope<S> scope(128);
  const bool mpfr = !std::is_same_v<S, double>;
  const ndc::GeneratedProblem g = ndc::generateProblem("rotated-circle", n, seed);
  const ndc::Problem problem = ndc::parseProblem(g.text, g.name);
  INFO(g.name << " depth " << depth << (mpfr ? " mpfr" : " double"));
  // The test's premise: the quadric is past the cap, the hyperplanes are not.
  REQUIRE(ndc::denseCoefficients(problem.equations[0]) > ndc::kMaxCoefficients);
  REQUIRE(ndc::densityFree(problem.equations[0]));
  ndc::Settings settings;
  settings.depth = depth;
  settings.scalar = mpfr ? "mpfr" : "double";
  settings.precisionBits = 128;
  const ndc::Summary s = ndc::runPipeline(problem, settings).summary;
  INFO(s.topology.reason);
  CHECK(s.topology.certified);
  CHECK(s.mesh.components == g.components);
  CHECK(s.mesh.eulerCharacteristic == g.eulerCharacteristic);
  CHECK(s.mesh.branchVertices == 0);
  CHECK(s.mesh.openEnds == 0);
  CHECK(s.mesh.maxResidual <= (mpfr ? 1e-30 : 1e-10));
}

}  // namespace

TEST_CASE("dense-free: circles in R^13 and R^14 are certified without dense forms", "[pipeline]") {
  for (std::uint64_t seed : {0, 1, 2}) {
    solveWithoutForms<double>(13, seed, 4);
    solveWithoutForms<double>(13, seed, 5);
  }
  solveWithoutForms<double>(14, 0, 4);
}

TEST_CASE("dense-free: a circle in R^13 without dense forms in MPFR", "[pipeline][mpfr][slow]") {
  solveWithoutForms<ndc::Mpfr>(13, 0, 4);
}

TEST_CASE("dense-free: what needs the dense form refuses such an equation", "[pipeline]") {
  const ndc::GeneratedProblem g = ndc::generateProblem("rotated-circle", 13, 0);
  const ndc::Problem problem = ndc::parseProblem(g.text, g.name);
  ndc::Settings settings;
  settings.depth = 3;
  settings.bounding = "bernstein";
  try {
    ndc::runPipeline(problem, settings);
    FAIL("the bernstein bounding built a form of 1.6e6 coefficients");
  } catch (const ndc::InputError& e) {
    const std::string what = e.what();
    CHECK(what.find("bounding 'bernstein'") != std::string::npos);
    CHECK(what.find("equation 1") != std::string::npos);
    CHECK(what.find("linearized") != std::string::npos);
  }
  // A cubic of the same size needs its form for the certificate: still refused on reading.
  std::vector<std::string> equations{"x0^3"};
  for (int j = 1; j < 13; ++j) equations[0] += " + x" + std::to_string(j) + "^2";
  equations[0] += " - 1";
  for (int j = 2; j < 13; ++j) equations.push_back("x" + std::to_string(j) + " - 0.01");
  CHECK_THROWS_AS(ndc::test::makeProblem(13, equations), ndc::InputError);
}

TEST_CASE("dense-free: an equation that vanishes everywhere is refused without its form",
          "[pipeline]") {
  // Each term has degree 2 in two variables, so the form would have 3^13 coefficients; the
  // reader's canonical polynomial shows the sum is 0 before any form or evaluation.
  std::string zero;
  for (int j = 0; j + 1 < 13; ++j) {
    const std::string a = "x" + std::to_string(j), b = "x" + std::to_string(j + 1);
    zero += " + (" + a + " + " + b + ")^2 - " + a + "^2 - 2*" + a + "*" + b + " - " + b + "^2";
  }
  std::vector<std::string> equations{zero.substr(3), "x0^2 + x1^2 - 1"};
  for (int j = 2; j < 12; ++j) equations.push_back("x" + std::to_string(j) + " - 0.01");
  try {
    ndc::test::makeProblem(13, equations, 1.5);
    FAIL("an equation that vanishes everywhere was accepted");
  } catch (const ndc::InputError& e) {
    CHECK(std::string(e.what()).find("equation 1 is constant") != std::string::npos);
  }
}
