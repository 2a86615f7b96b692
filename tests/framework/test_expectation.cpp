// The comparison of a problem's [expect] with the mesh (expectation.hpp) and the summary fields
// and files of docs/contracts.md 4.5 that carry it, the singular points and the perturbation
// (io.hpp).
#include <catch2/catch.hpp>

#include <sstream>
#include <string>

#include "experiments/runner/experiment.hpp"
#include "framework/io/io.hpp"
#include "framework/problem/expectation.hpp"

namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// A closed connected surface with Euler characteristic `chi`.
ndc::MeshStats closedSurface(long chi) {
  ndc::MeshStats m;
  m.vertices = 100;
  m.edges = 300 - 3 * chi;
  m.triangles = 200 - 2 * chi;
  m.components = 1;
  m.eulerCharacteristic = chi;
  return m;
}

const ndc::ExpectCheck& find(const std::vector<ndc::ExpectCheck>& checks, const std::string& key) {
  for (const auto& c : checks)
    if (c.key == key) return c;
  FAIL("no check of " << key);
  return checks.front();
}

}  // namespace

TEST_CASE("expect: every key is compared or reported, in a fixed order", "[expect]") {
  ndc::Expectation x;
  x.components = 1;
  x.eulerCharacteristic = -2;
  x.other = {{"genus", 2}, {"boundary_edges", 0}, {"boundary_loops", 0}, {"vertices", 99}};
  const auto checks = ndc::checkExpectation(x, closedSurface(-2), 2);
  REQUIRE(checks.size() == 6);
  // components, euler_characteristic, then the others by name.
  CHECK(checks[0].key == "components");
  CHECK(checks[1].key == "euler_characteristic");
  CHECK(checks[2].key == "boundary_edges");
  CHECK(checks[3].key == "boundary_loops");
  CHECK(checks[4].key == "genus");
  CHECK(checks[5].key == "vertices");

  CHECK((checks[0].ok && checks[0].got == 1 && checks[0].notComparable.empty()));
  CHECK((checks[1].ok && checks[1].got == -2));
  CHECK((checks[2].ok && checks[2].got == 0));
  // genus = (2 - chi) / 2 on one closed surface.
  CHECK((checks[4].ok && checks[4].got == 2 && checks[4].notComparable.empty()));
  // A mesh statistic that differs.
  CHECK((!checks[5].ok && checks[5].got == 100 && checks[5].wanted == 99));
  CHECK(ndc::describeCheck(checks[5]) == "expect vertices = 99, got 100");
  // A key that is no mesh statistic is reported, not skipped, and is no mismatch.
  CHECK(!checks[3].ok);
  CHECK(contains(checks[3].notComparable, "not a mesh statistic"));
  CHECK(contains(ndc::describeCheck(checks[3]), "expect boundary_loops = 0: not comparable"));
  CHECK(ndc::expectationMismatch(checks));
  x.other.erase("vertices");
  CHECK(!ndc::expectationMismatch(ndc::checkExpectation(x, closedSurface(-2), 2)));

  // A wrong count is a mismatch; the genus of a torus is 1.
  ndc::Expectation torus;
  torus.components = 2;
  torus.other = {{"genus", 1}};
  const auto t = ndc::checkExpectation(torus, closedSurface(0), 2);
  CHECK(!find(t, "components").ok);
  CHECK(ndc::describeCheck(find(t, "components")) == "expect components = 2, got 1");
  CHECK((find(t, "genus").ok && find(t, "genus").got == 1));
  CHECK(ndc::expectationMismatch(t));

  // No [expect]: no checks.
  CHECK(ndc::checkExpectation(ndc::Expectation{}, closedSurface(0), 2).empty());
}

TEST_CASE("expect: genus only where chi = 2 - 2g holds", "[expect]") {
  ndc::Expectation x;
  x.other = {{"genus", 0}};
  const auto reason = [&](const ndc::MeshStats& m, int k) {
    const auto checks = ndc::checkExpectation(x, m, k);
    REQUIRE(checks.size() == 1);
    CHECK(!checks[0].ok);
    return checks[0].notComparable;
  };
  ndc::MeshStats two = closedSurface(4);
  two.components = 2;  // two spheres
  CHECK(contains(reason(two, 2), "one component, the mesh has 2"));
  ndc::MeshStats open = closedSurface(1);
  open.boundaryEdges = 12;  // a disk
  CHECK(contains(reason(open, 2), "12 boundary"));
  ndc::MeshStats pinched = closedSurface(2);
  pinched.nonmanifoldEdges = 3;
  CHECK(contains(reason(pinched, 2), "3 non-manifold"));
  CHECK(contains(reason(closedSurface(1), 2), "even Euler characteristic"));
  CHECK(contains(reason(closedSurface(0), 1), "k = 2"));
  // A sphere: genus 0, compared.
  const auto sphere = ndc::checkExpectation(x, closedSurface(2), 2);
  CHECK((sphere[0].notComparable.empty() && sphere[0].ok && sphere[0].got == 0));
  // Only compared keys decide a mismatch.
  CHECK(!ndc::expectationMismatch(ndc::checkExpectation(x, two, 2)));
}

TEST_CASE("expect: summary.json carries expect, singular points, perturbation", "[expect]") {
  ndc::RunResult r;
  r.n = r.summary.n = 3;
  r.k = r.summary.k = 2;
  r.summary.problem = "p";
  ndc::Summary& s = r.summary;

  // Without [expect], singular points or perturbation: the lists are present and empty.
  std::string json = ndc::toJson(s);
  CHECK(!contains(json, "\"expect\""));
  CHECK(contains(json, "\"singular_points\": []"));
  CHECK(contains(json, "\"off_manifold_vertices\": 0"));
  CHECK(contains(
      json, "\"perturbation\": {\"level\": [], \"attempts\": 0, \"degenerate_crossings\": 0}"));
  std::ostringstream csv;
  ndc::writeSingularCsv(csv, r);
  CHECK(csv.str() == "point,sigma_min,u0,u1,u2\n");

  s.singularPoints = {{{0.5, -0.25, 0}, 1e-9}, {{1, 2, 3}, 0.125}};
  s.offManifoldVertices = 4;
  s.perturbation = {{1e-7}, 2, 3};
  ndc::Expectation x;
  x.components = 2;
  x.eulerCharacteristic = 0;
  x.other = {{"boundary_loops", 1}};
  s.mesh = closedSurface(0);
  s.expect = ndc::checkExpectation(x, s.mesh, r.k);
  json = ndc::toJson(s);
  INFO(json);
  CHECK(contains(json, "{\"point\": [0.5, -0.25, 0], \"sigma_min\": 1.0000000000000001e-09}"));
  CHECK(contains(json, "{\"point\": [1, 2, 3], \"sigma_min\": 0.125}"));
  CHECK(contains(json, "\"off_manifold_vertices\": 4"));
  CHECK(contains(json,
                 "\"perturbation\": {\"level\": [9.9999999999999995e-08], \"attempts\": 2, "
                 "\"degenerate_crossings\": 3}"));
  CHECK(contains(json,
                 "\"expect\": {\"components\": {\"wanted\": 2, \"got\": 1, \"ok\": false}, "
                 "\"euler_characteristic\": {\"wanted\": 0, \"got\": 0, \"ok\": true}, "
                 "\"boundary_loops\": {\"wanted\": 1, \"got\": null, \"ok\": null, "
                 "\"not_comparable\": \"not a mesh statistic"));
  CHECK(contains(json, "\"boundary_components\": 0"));
  // The document still flattens; the list elements are numbered paths.
  const auto numbers = ndc::flattenJsonNumbers(json);
  const auto has = [&](const std::string& name, const std::string& value) {
    for (const auto& [n, v] : numbers)
      if (n == name) return v == value;
    return false;
  };
  CHECK(has("diagnostics.singular_points.1.sigma_min", "0.125"));
  CHECK(has("diagnostics.singular_points.0.point.1", "-0.25"));
  CHECK(has("diagnostics.perturbation.attempts", "2"));
  CHECK(has("expect.components.got", "1"));
  csv.str("");
  ndc::writeSingularCsv(csv, r);
  CHECK(csv.str() ==
        "point,sigma_min,u0,u1,u2\n0,1.0000000000000001e-09,0.5,-0.25,0\n1,0.125,1,2,3\n");
}
