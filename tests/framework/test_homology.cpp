// Betti numbers and facet counts (framework/mesh/homology.hpp) of complexes with known
// homology, under random relabelling, and their place in summary.json and [expect].
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "framework/io/io.hpp"
#include "framework/mesh/analysis.hpp"
#include "framework/mesh/homology.hpp"
#include "framework/problem/expectation.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_support.hpp"

namespace {

using Betti = std::vector<std::int64_t>;

/// A complex by its vertex count and k-simplices, with its known homology.
struct Known {
  std::string name;
  int k = 0;
  int vertices = 0;
  std::vector<std::int32_t> simplices;  // k + 1 per simplex
  Betti betti, bettiZ2;
  std::int64_t boundary = 0, nonmanifold = 0;
};

/// Vertex number of (i, j, l) on an `n`-periodic grid (l unused when 2D).
int wrap(int i, int n) { return ((i % n) + n) % n; }

/// The torus: an n x n periodic grid, two triangles per square.
std::vector<std::int32_t> gridTorus(int n, int first = 0) {
  std::vector<std::int32_t> s;
  const auto id = [&](int i, int j) { return first + wrap(i, n) * n + wrap(j, n); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      s.insert(s.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1),
                         id(i, j + 1)});
  return s;
}

/// The Klein bottle: an n x n grid, periodic in i, and glued to itself reflected (i -> -i)
/// across j = n.
std::vector<std::int32_t> kleinBottle(int n) {
  std::vector<std::int32_t> s;
  const auto id = [&](int i, int j) { return j == n ? wrap(-i, n) * n : wrap(i, n) * n + j; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      s.insert(s.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1),
                         id(i, j + 1)});
  return s;
}

/// Kuhn's triangulation of an n^3 grid of cubes into 6 tetrahedra each: periodic (the 3-torus)
/// or not (a ball on (n + 1)^3 vertices).
std::vector<std::int32_t> kuhnCube(int n, bool periodic) {
  const int m = periodic ? n : n + 1;
  const auto id = [&](const std::array<int, 3>& x) {
    return (wrap(x[0], m) * m + wrap(x[1], m)) * m + wrap(x[2], m);
  };
  std::vector<std::int32_t> s;
  std::array<int, 3> axes{0, 1, 2};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int l = 0; l < n; ++l) {
        std::sort(axes.begin(), axes.end());
        do {
          std::array<int, 3> x{i, j, l};
          s.push_back(id(x));
          for (int a : axes) ++x[a], s.push_back(id(x));
        } while (std::next_permutation(axes.begin(), axes.end()));
      }
  return s;
}

/// An open n x n grid of squares (a disk on (n + 1)^2 vertices).
std::vector<std::int32_t> gridDisk(int n) {
  std::vector<std::int32_t> s;
  const auto id = [&](int i, int j) { return i * (n + 1) + j; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      s.insert(s.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1),
                         id(i, j + 1)});
  return s;
}

/// Every (k+1)-subset of {0 .. k+1}: the boundary of the (k+1)-simplex, a k-sphere.
std::vector<std::int32_t> simplexBoundary(int k) {
  std::vector<std::int32_t> s;
  for (int omit = 0; omit <= k + 1; ++omit)
    for (int v = 0; v <= k + 1; ++v)
      if (v != omit) s.push_back(v);
  return s;
}

const std::vector<std::int32_t> kOctahedron{0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4,
                                            2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

/// Every complex with its known homology.
std::vector<Known> knownComplexes() {
  std::vector<Known> all;
  all.push_back({"circle", 1, 5, {0, 1, 1, 2, 2, 3, 3, 4, 4, 0}, {1, 1}, {1, 1}});
  all.push_back({"path", 1, 4, {0, 1, 1, 2, 2, 3}, {1, 0}, {1, 0}, 2, 0});
  all.push_back({"star", 1, 4, {0, 1, 0, 2, 0, 3}, {1, 0}, {1, 0}, 3, 1});
  // Two circles (3 and 4 vertices) and two isolated vertices.
  all.push_back({"two circles and two points",
                 1,
                 9,
                 {0, 1, 1, 2, 2, 0, 3, 4, 4, 5, 5, 6, 6, 3},
                 {4, 2},
                 {4, 2}});
  all.push_back({"octahedron", 2, 6, kOctahedron, {1, 0, 1}, {1, 0, 1}});
  all.push_back({"torus", 2, 16, gridTorus(4), {1, 2, 1}, {1, 2, 1}});
  // The 6-vertex real projective plane (half an icosahedron).
  all.push_back(
      {"RP^2",
       2,
       6,
       {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 1, 5, 1, 2, 4, 1, 3, 4, 1, 3, 5, 2, 3, 5, 2, 4, 5},
       {1, 0, 0},
       {1, 1, 1}});
  all.push_back({"Klein bottle", 2, 25, kleinBottle(5), {1, 1, 0}, {1, 2, 1}});
  all.push_back({"disk", 2, 16, gridDisk(3), {1, 0, 0}, {1, 0, 0}, 12, 0});
  all.push_back({"three triangles on an edge",
                 2,
                 5,
                 {0, 1, 2, 0, 1, 3, 1, 0, 4},
                 {1, 0, 0},
                 {1, 0, 0},
                 6,
                 1});
  // An octahedron, a torus and two isolated vertices.
  std::vector<std::int32_t> union_ = kOctahedron;
  const std::vector<std::int32_t> torus = gridTorus(3, 6);
  union_.insert(union_.end(), torus.begin(), torus.end());
  all.push_back({"sphere, torus and two points", 2, 17, union_, {4, 2, 2}, {4, 2, 2}});
  all.push_back({"S^3", 3, 5, simplexBoundary(3), {1, 0, 0, 1}, {1, 0, 0, 1}});
  all.push_back({"3-torus", 3, 27, kuhnCube(3, true), {1, 3, 3, 1}, {1, 3, 3, 1}});
  all.push_back({"ball", 3, 27, kuhnCube(2, false), {1, 0, 0, 0}, {1, 0, 0, 0}, 48, 0});
  all.push_back({"S^6", 6, 8, simplexBoundary(6), {1, 0, 0, 0, 0, 0, 1}, {1, 0, 0, 0, 0, 0, 1}});
  return all;
}

/// The complex of `known` in R^n and scalar S (coordinates: the vertex number, then zeros), its
/// vertices renumbered
/// at random, its simplices in random order with their vertices in random order.
template <class S>
ndc::Complex<S> shuffled(const Known& known, std::mt19937& rng, int n = 1) {
  std::vector<std::int32_t> label(std::size_t(known.vertices));
  std::iota(label.begin(), label.end(), 0);
  std::shuffle(label.begin(), label.end(), rng);
  const std::size_t w = std::size_t(known.k + 1), count = known.simplices.size() / w;
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::shuffle(order.begin(), order.end(), rng);
  ndc::Complex<S> c;
  c.n = n;
  c.k = known.k;
  for (int v = 0; v < known.vertices; ++v)
    for (int j = 0; j < n; ++j) c.vertices.push_back(S(j == 0 ? v : 0));
  for (std::size_t s : order) {
    std::vector<std::int32_t> simplex;
    for (std::size_t i = 0; i < w; ++i) simplex.push_back(label[known.simplices[s * w + i]]);
    std::shuffle(simplex.begin(), simplex.end(), rng);
    c.addSimplex(simplex);
  }
  return c;
}

std::int64_t alternating(const Betti& b) {
  std::int64_t sum = 0;
  for (std::size_t d = 0; d < b.size(); ++d) sum += d % 2 == 0 ? b[d] : -b[d];
  return sum;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEMPLATE_TEST_CASE("homology: complexes with known Betti numbers, relabelled and shuffled",
                   "[homology]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  std::mt19937 rng(44);
  for (const Known& known : knownComplexes()) {
    for (int round = 0; round < 3; ++round) {
      INFO(known.name << ", round " << round);
      const ndc::Homology h = ndc::homology(shuffled<TestType>(known, rng));
      CHECK(h.betti == known.betti);
      CHECK(h.bettiZ2 == known.bettiZ2);
      CHECK(h.boundaryFacets == known.boundary);
      CHECK(h.nonmanifoldFacets == known.nonmanifold);
      CHECK(alternating(h.betti) == h.eulerCharacteristic());
      CHECK(alternating(h.bettiZ2) == h.eulerCharacteristic());
    }
  }
}

TEST_CASE("homology: repeated and degenerate simplices, an empty complex", "[homology]") {
  // The circle with one segment repeated (reversed) and one degenerate segment.
  const std::vector<std::int32_t> s{0, 1, 1, 2, 2, 0, 1, 0, 2, 2};
  const ndc::Homology h = ndc::homology(4, 1, s);
  CHECK(h.faces == Betti{4, 3});
  CHECK(h.betti == Betti{2, 1});
  // Vertices only.
  CHECK(ndc::homology(3, 2, {}).betti == Betti{3, 0, 0});
  CHECK(ndc::homology(0, 2, {}).betti == Betti{0, 0, 0});
}

TEST_CASE("homology: random complexes satisfy Euler-Poincare", "[homology]") {
  std::mt19937 rng(2026);
  for (int round = 0; round < 60; ++round) {
    const int k = 1 + round % 4, vertices = k + 2 + int(rng() % 9);
    std::vector<std::int32_t> s;
    const int count = 1 + int(rng() % 40);
    std::vector<std::int32_t> all(static_cast<std::size_t>(vertices));
    std::iota(all.begin(), all.end(), 0);
    for (int i = 0; i < count; ++i) {
      std::shuffle(all.begin(), all.end(), rng);
      s.insert(s.end(), all.begin(), all.begin() + k + 1);
    }
    INFO("round " << round << ", k = " << k);
    const ndc::Homology h = ndc::homology(std::size_t(vertices), k, s);
    CHECK(alternating(h.betti) == h.eulerCharacteristic());
    CHECK(alternating(h.bettiZ2) == h.eulerCharacteristic());
    // Universal coefficients: over Z/2 a Betti number is at least the rational one.
    for (int d = 0; d <= k; ++d) CHECK(h.bettiZ2[d] >= h.betti[d]);
    CHECK(h.betti[0] >= 1);
  }
}

TEMPLATE_TEST_CASE("homology: the analysis fills the mesh fields for k = 1 and 2", "[homology]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  const auto identity = [](std::span<S>) {
    ndc::ProjectedPoint<S> p;
    p.converged = true;
    return p;
  };
  std::mt19937 rng(7);
  for (const Known& known : knownComplexes()) {
    if (known.k > 2) continue;
    INFO(known.name);
    const ndc::Problem problem =
        ndc::test::makeProblem(known.k + 1, {"x0^2 + x1^2 - 1"}, 2);  // only its system is used
    const ndc::System<S> system(problem);
    const ndc::MeshStats m =
        ndc::analyse<S>(shuffled<S>(known, rng, known.k + 1), system, identity);
    CHECK(m.betti == known.betti);
    CHECK(m.bettiZ2 == known.bettiZ2);
    CHECK(m.boundaryFacets == (known.k == 1 ? m.openEnds : m.boundaryEdges));
    CHECK(m.nonmanifoldFacets == (known.k == 1 ? m.branchVertices : m.nonmanifoldEdges));
    CHECK(alternating(m.betti) == m.eulerCharacteristic);
  }
}

TEST_CASE("homology: summary.json of k = 1 and k = 2 runs, and [expect] betti", "[homology]") {
  ndc::Settings settings;
  settings.depth = 3;
  settings.threads = 1;
  // A circle (k = 1): the fields are there, with the circle's Betti numbers.
  ndc::Problem circle = ndc::test::makeProblem(2, {"x0^2 + x1^2 - 4"});
  ndc::RunResult r = ndc::runPipeline(circle, settings);
  std::string json = ndc::toJson(r.summary);
  INFO(json);
  CHECK(contains(json,
                 "\"betti\": [1, 1], \"betti_z2\": [1, 1], \"boundary_facets\": 0, "
                 "\"nonmanifold_facets\": 0"));
  // A sphere (k = 2) whose [expect] says torus: a mismatch in summary.json and its message.
  ndc::Problem sphere = ndc::parseProblem(
      "name = \"s\"\nvariables = [\"x\", \"y\", \"z\"]\n"
      "domain = [[-3, 3], [-3, 3], [-3, 3]]\nequations = [\"x^2 + y^2 + z^2 - 4\"]\n"
      "[expect]\nbetti = [1, 2, 1]\nbetti_z2 = [1, 0, 1]\nboundary_facets = 0\n",
      "s.toml");
  r = ndc::runPipeline(sphere, settings);
  CHECK(r.summary.mesh.betti == Betti{1, 0, 1});
  CHECK(r.summary.mesh.bettiZ2 == Betti{1, 0, 1});
  r.summary.expect = ndc::checkExpectation(sphere.expect, r.summary.mesh, r.k);
  CHECK(ndc::expectationMismatch(r.summary.expect));
  json = ndc::toJson(r.summary);
  CHECK(contains(json, "\"betti\": [1, 0, 1], \"betti_z2\": [1, 0, 1], \"boundary_facets\": 0"));
  CHECK(contains(json,
                 "\"expect\": {\"boundary_facets\": {\"wanted\": 0, \"got\": 0, \"ok\": true}, "
                 "\"betti\": {\"wanted\": [1, 2, 1], \"got\": [1, 0, 1], \"ok\": false}, "
                 "\"betti_z2\": {\"wanted\": [1, 0, 1], \"got\": [1, 0, 1], \"ok\": true}}"));
  REQUIRE(r.summary.expect.size() == 3);
  CHECK(ndc::describeCheck(r.summary.expect[1]) == "expect betti = [1, 2, 1], got [1, 0, 1]");
  // A list of the wrong length is not comparable; a bad value is refused when read.
  ndc::Expectation x;
  x.lists["betti"] = {1, 0};
  const auto checks = ndc::checkExpectation(x, r.summary.mesh, 2);
  CHECK(contains(checks.at(0).notComparable, "k + 1 = 3 numbers"));
  CHECK_THROWS_AS(ndc::parseProblem("name = \"s\"\nvariables = [\"x\", \"y\"]\n"
                                    "domain = [[-3, 3], [-3, 3]]\nequations = [\"x^2 + y^2 - 4\"]\n"
                                    "[expect]\nbetti = [1, -1]\n",
                                    "s.toml"),
                  ndc::InputError);
  CHECK_THROWS_AS(ndc::parseProblem("name = \"s\"\nvariables = [\"x\", \"y\"]\n"
                                    "domain = [[-3, 3], [-3, 3]]\nequations = [\"x^2 + y^2 - 4\"]\n"
                                    "[expect]\nbetti = 1\n",
                                    "s.toml"),
                  ndc::InputError);
}
