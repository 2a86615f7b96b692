// Tests of the analysis stage: welding, topology and accuracy of hand-built complexes.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "framework/mesh/analysis.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "strategies/projection/projection.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::toDouble;
using ndc::test::makeProblem;

/// A complex from double coordinates and vertex numbers.
template <class S>
ndc::Complex<S> makeComplex(int n, int k, const std::vector<std::vector<double>>& vertices,
                            const std::vector<std::vector<std::int32_t>>& simplices) {
  ndc::Complex<S> c;
  c.n = n;
  c.k = k;
  for (const auto& v : vertices) {
    std::vector<S> x(v.begin(), v.end());
    c.addVertex(x);
  }
  for (const auto& s : simplices) c.addSimplex(s);
  return c;
}

/// A projector that leaves every point where it is (topology-only tests).
template <class S>
ndc::Projector<S> identity() {
  return [](std::span<S>) {
    ndc::ProjectedPoint<S> p;
    p.converged = true;
    return p;
  };
}

/// The octahedron: 6 vertices, 12 edges, 8 triangles, chi = 2.
const std::vector<std::vector<double>> kOctahedronVertices{{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                                           {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
const std::vector<std::vector<std::int32_t>> kOctahedronTriangles{
    {0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};

/// Polygon with vertices `first..first+count-1` closed or open, as segments.
void addPolyline(std::vector<std::vector<std::int32_t>>& segments, int first, int count,
                 bool closed) {
  for (int i = 0; i + 1 < count; ++i) segments.push_back({first + i, first + i + 1});
  if (closed) segments.push_back({first + count - 1, first});
}

}  // namespace

TEMPLATE_TEST_CASE("Topology of hand-built polylines", "[analysis]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  const ndc::Problem problem = makeProblem(2, {"x0^2 + x1^2 - 1"}, 2);
  const ndc::System<S> system(problem);

  SECTION("closed polygon") {
    std::vector<std::vector<double>> v;
    for (int i = 0; i < 7; ++i) v.push_back({std::cos(i * 0.9), std::sin(i * 0.9)});
    std::vector<std::vector<std::int32_t>> s;
    addPolyline(s, 0, 7, true);
    const auto stats = ndc::analyse<S>(makeComplex<S>(2, 1, v, s), system, identity<S>());
    CHECK(stats.vertices == 7);
    CHECK(stats.edges == 7);
    CHECK(stats.triangles == 0);
    CHECK(stats.components == 1);
    CHECK(stats.eulerCharacteristic == 0);
    CHECK(stats.openEnds == 0);
    CHECK(stats.branchVertices == 0);
    CHECK(stats.boundaryEdges == 0);
    CHECK(stats.nonmanifoldEdges == 0);
  }
  SECTION("open polyline") {
    std::vector<std::vector<double>> v;
    for (int i = 0; i < 5; ++i) v.push_back({0.1 * i, 0.0});
    std::vector<std::vector<std::int32_t>> s;
    addPolyline(s, 0, 5, false);
    const auto stats = ndc::analyse<S>(makeComplex<S>(2, 1, v, s), system, identity<S>());
    CHECK(stats.vertices == 5);
    CHECK(stats.edges == 4);
    CHECK(stats.components == 1);
    CHECK(stats.eulerCharacteristic == 1);
    CHECK(stats.openEnds == 2);
    CHECK(stats.branchVertices == 0);
  }
  SECTION("Y shape") {
    // Centre 0 and three arms of two segments each.
    const std::vector<std::vector<double>> v{{0, 0},      {0.1, 0},     {0.2, 0},    {-0.1, 0.1},
                                             {-0.2, 0.2}, {-0.1, -0.1}, {-0.2, -0.2}};
    const std::vector<std::vector<std::int32_t>> s{{0, 1}, {1, 2}, {0, 3}, {3, 4}, {0, 5}, {5, 6}};
    const auto stats = ndc::analyse<S>(makeComplex<S>(2, 1, v, s), system, identity<S>());
    CHECK(stats.vertices == 7);
    CHECK(stats.edges == 6);
    CHECK(stats.components == 1);
    CHECK(stats.eulerCharacteristic == 1);
    CHECK(stats.openEnds == 3);
    CHECK(stats.branchVertices == 1);
  }
  SECTION("two loops and an isolated vertex") {
    std::vector<std::vector<double>> v;
    for (int i = 0; i < 4; ++i) v.push_back({std::cos(i * 1.5), std::sin(i * 1.5)});
    for (int i = 0; i < 5; ++i) v.push_back({0.5 * std::cos(i * 1.2), 0.5 * std::sin(i * 1.2)});
    v.push_back({1.5, 1.5});
    std::vector<std::vector<std::int32_t>> s;
    addPolyline(s, 0, 4, true);
    addPolyline(s, 4, 5, true);
    const auto stats = ndc::analyse<S>(makeComplex<S>(2, 1, v, s), system, identity<S>());
    CHECK(stats.vertices == 10);
    CHECK(stats.edges == 9);
    CHECK(stats.components == 3);
    CHECK(stats.eulerCharacteristic == 1);
    CHECK(stats.openEnds == 0);
  }
}

TEMPLATE_TEST_CASE("Topology of hand-built triangle meshes", "[analysis]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  const ndc::Problem sphere = makeProblem(3, {"x0^2 + x1^2 + x2^2 - 1"}, 2);
  const ndc::System<S> system(sphere);

  SECTION("octahedron") {
    const auto complex = makeComplex<S>(3, 2, kOctahedronVertices, kOctahedronTriangles);
    const auto stats = ndc::analyse<S>(complex, system, identity<S>());
    CHECK(stats.vertices == 6);
    CHECK(stats.edges == 12);
    CHECK(stats.triangles == 8);
    CHECK(stats.components == 1);
    CHECK(stats.eulerCharacteristic == 2);
    CHECK(stats.boundaryEdges == 0);
    CHECK(stats.nonmanifoldEdges == 0);
    CHECK(stats.openEnds == 0);
    CHECK(stats.branchVertices == 0);
    // Its vertices are on the unit sphere.
    CHECK(stats.maxResidual == 0.0);
  }
  SECTION("single triangle") {
    const auto complex = makeComplex<S>(3, 2, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}});
    const auto stats = ndc::analyse<S>(complex, system, identity<S>());
    CHECK(stats.vertices == 3);
    CHECK(stats.edges == 3);
    CHECK(stats.triangles == 1);
    CHECK(stats.boundaryEdges == 3);
    CHECK(stats.nonmanifoldEdges == 0);
    CHECK(stats.eulerCharacteristic == 1);
  }
  SECTION("three triangles on one edge") {
    const auto complex =
        makeComplex<S>(3, 2, {{0, 0, -1}, {0, 0, 1}, {1, 0, 0}, {-0.5, 0.8, 0}, {-0.5, -0.8, 0}},
                       {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}});
    const auto stats = ndc::analyse<S>(complex, system, identity<S>());
    CHECK(stats.vertices == 5);
    CHECK(stats.edges == 7);
    CHECK(stats.triangles == 3);
    CHECK(stats.nonmanifoldEdges == 1);
    CHECK(stats.boundaryEdges == 6);
    CHECK(stats.components == 1);
    CHECK(stats.eulerCharacteristic == 1);
  }
}

//! [analysis-clifford]
TEMPLATE_TEST_CASE("A triangulated Clifford torus has chi = 0", "[analysis]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::acos;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const ndc::Problem problem = makeProblem(4, {"x0^2 + x1^2 - 0.5", "x2^2 + x3^2 - 0.5"}, 2);
  const ndc::System<S> system(problem);
  const int rows = 6, cols = 8;
  const S pi = acos(S(-1));
  const S radius = sqrt(ndc::ScalarTraits<S>::fromString("0.5"));
  ndc::Complex<S> complex;
  complex.n = 4;
  complex.k = 2;
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const S a = 2 * pi * S(i) / S(rows), b = 2 * pi * S(j) / S(cols);
      const std::vector<S> x{radius * cos(a), radius * sin(a), radius * cos(b), radius * sin(b)};
      complex.addVertex(x);
    }
  }
  const auto at = [&](int i, int j) { return ((i + rows) % rows) * cols + (j + cols) % cols; };
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const std::vector<std::int32_t> lower{at(i, j), at(i + 1, j), at(i + 1, j + 1)};
      const std::vector<std::int32_t> upper{at(i, j), at(i + 1, j + 1), at(i, j + 1)};
      complex.addSimplex(lower);
      complex.addSimplex(upper);
    }
  }
  const ndc::NewtonProjection<S> newton(system);
  const auto stats = ndc::analyse<S>(complex, system, ndc::makeProjector<S>(newton));
  CHECK(stats.vertices == rows * cols);
  CHECK(stats.edges == 3 * rows * cols);
  CHECK(stats.triangles == 2 * rows * cols);
  CHECK(stats.components == 1);
  CHECK(stats.eulerCharacteristic == 0);
  CHECK(stats.boundaryEdges == 0);
  CHECK(stats.nonmanifoldEdges == 0);
  CHECK(stats.maxResidual <= (std::is_same_v<S, double> ? 1e-15 : 1e-35));
  CHECK(stats.chordFailures == 0);
  CHECK(stats.maxChordError > 0.01);
  CHECK(stats.maxChordError < 0.2);
}
//! [analysis-clifford]

TEMPLATE_TEST_CASE("Welding merges duplicate vertices within tolerance", "[analysis]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  const ndc::Problem sphere = makeProblem(3, {"x0^2 + x1^2 + x2^2 - 1"}, 2);
  const ndc::System<S> system(sphere);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> jiggle(-1e-13, 1e-13);

  SECTION("an octahedron with a private copy of the vertices for every triangle") {
    ndc::Complex<S> soup;
    soup.n = 3;
    soup.k = 2;
    for (const auto& t : kOctahedronTriangles) {
      std::vector<std::int32_t> copy;
      for (std::int32_t v : t) {
        std::vector<S> x;
        for (double c : kOctahedronVertices[v]) x.push_back(S(c + jiggle(rng)));
        copy.push_back(soup.addVertex(x, v));
      }
      soup.addSimplex(copy);
    }
    // A second copy of every triangle, reversed: a duplicate simplex after welding.
    for (const auto& t : kOctahedronTriangles) {
      std::vector<std::int32_t> copy;
      for (auto it = t.rbegin(); it != t.rend(); ++it) {
        std::vector<S> x;
        for (double c : kOctahedronVertices[*it]) x.push_back(S(c + jiggle(rng)));
        copy.push_back(soup.addVertex(x, *it));
      }
      soup.addSimplex(copy);
    }
    REQUIRE(soup.vertexCount() == 48);
    const ndc::Complex<S> welded = ndc::weld(soup, 1e-9);
    CHECK(welded.vertexCount() == 6);
    CHECK(welded.simplexCount() == 8);
    CHECK(welded.vertexCell.size() == 6);
    const auto stats = ndc::analyse<S>(welded, system, identity<S>());
    const auto reference = ndc::analyse<S>(
        makeComplex<S>(3, 2, kOctahedronVertices, kOctahedronTriangles), system, identity<S>());
    CHECK(stats.vertices == reference.vertices);
    CHECK(stats.edges == reference.edges);
    CHECK(stats.triangles == reference.triangles);
    CHECK(stats.components == reference.components);
    CHECK(stats.eulerCharacteristic == 2);
    CHECK(stats.boundaryEdges == 0);
    CHECK(stats.nonmanifoldEdges == 0);
    CHECK(stats.maxResidual <= 1e-12);

    // Tolerance 0 merges only identical points: nothing here.
    CHECK(ndc::weld(soup, 0.0).vertexCount() == 48);
  }

  SECTION("pairs closer than the tolerance merge, farther pairs do not, across bucket faces") {
    const double tol = 1e-6;
    for (int n : {2, 3, 5}) {
      INFO("n = " << n);
      std::uniform_real_distribution<double> position(-1, 1);
      std::normal_distribution<double> direction;
      ndc::Complex<S> close, apart;
      close.n = apart.n = n;
      close.k = apart.k = 1;
      const int pairs = 300;
      for (int p = 0; p < pairs; ++p) {
        std::vector<double> a(n), d(n);
        double len = 0;
        for (int j = 0; j < n; ++j) {
          a[j] = position(rng);
          d[j] = direction(rng);
          len += d[j] * d[j];
        }
        len = std::sqrt(len);
        // Every tenth pair straddles the plane x0 = 0, a bucket face for any bucket size.
        if (p % 10 == 0) a[0] = -0.2 * tol;
        std::vector<S> x(n), y(n), z(n);
        for (int j = 0; j < n; ++j) {
          x[j] = S(a[j]);
          y[j] = S(a[j] + 0.5 * tol * d[j] / len);
          z[j] = S(a[j] + 3.0 * tol * d[j] / len);
        }
        if (p % 10 == 0) {
          y[0] = S(0.2 * tol);
          for (int j = 1; j < n; ++j) y[j] = x[j];
        }
        const std::int32_t seg[2] = {close.addVertex(x), close.addVertex(y)};
        close.addSimplex(seg);
        apart.addVertex(x);
        apart.addVertex(z);
      }
      const auto weldedClose = ndc::weld(close, tol);
      CHECK(weldedClose.vertexCount() == pairs);
      // Every segment collapsed to a point: degenerate, dropped.
      CHECK(weldedClose.simplexCount() == 0);
      CHECK(ndc::weld(apart, tol).vertexCount() == 2 * pairs);
    }
  }

  SECTION("degenerate and duplicate simplices are dropped") {
    ndc::Complex<S> c = makeComplex<S>(3, 2, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1e-12}},
                                       {{0, 1, 2}, {2, 1, 0}, {0, 1, 3}, {1, 2, 3}});
    const auto welded = ndc::weld(c, 1e-9);
    CHECK(welded.vertexCount() == 3);
    // (2, 1, 0) repeats (0, 1, 2); (0, 1, 3) becomes (0, 1, 0); (1, 2, 3) becomes (1, 2, 0).
    CHECK(welded.simplexCount() == 1);
    // The first copy keeps its orientation.
    CHECK(welded.simplices == std::vector<std::int32_t>{0, 1, 2});
  }
}

/// Greedy welding by brute force: each vertex in order merges into the first vertex kept so
/// far within `tol` (Euclidean), the kept ones numbered in order; degenerate simplices and
/// repeated vertex sets (the first copy kept) are dropped.
template <class S>
ndc::Complex<S> referenceWeld(const ndc::Complex<S>& c, double tol) {
  ndc::Complex<S> out;
  out.n = c.n;
  out.k = c.k;
  std::vector<std::int32_t> remap(c.vertexCount());
  for (std::size_t v = 0; v < c.vertexCount(); ++v) {
    std::int32_t found = -1;
    for (std::size_t r = 0; r < out.vertexCount() && found < 0; ++r) {
      S d2 = 0;
      for (int j = 0; j < c.n; ++j)
        d2 += (c.vertex(v)[j] - out.vertex(r)[j]) * (c.vertex(v)[j] - out.vertex(r)[j]);
      if (d2 <= S(tol) * S(tol)) found = static_cast<std::int32_t>(r);
    }
    remap[v] = found >= 0 ? found
                          : out.addVertex(c.vertex(v), c.vertexCell.empty() ? -1 : c.vertexCell[v]);
  }
  std::vector<std::vector<std::int32_t>> seen;
  const auto width = static_cast<std::size_t>(c.k + 1);
  for (std::size_t s = 0; s < c.simplexCount(); ++s) {
    std::vector<std::int32_t> simplex(width);
    for (std::size_t i = 0; i < width; ++i) simplex[i] = remap[c.simplices[s * width + i]];
    std::vector<std::int32_t> key = simplex;
    std::sort(key.begin(), key.end());
    if (std::adjacent_find(key.begin(), key.end()) != key.end()) continue;
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;
    seen.push_back(key);
    out.addSimplex(simplex);
  }
  return out;
}

TEMPLATE_TEST_CASE("Welding merges like a brute-force greedy weld on generated clusters",
                   "[analysis][weld]", NDC_SCALARS) {
  using S = TestType;
  const double tol = 1e-6;
  for (int n = 1; n <= 5; ++n) {
    for (unsigned seed = 0; seed < 4; ++seed) {
      CAPTURE(n, seed);
      std::mt19937 rng(seed * 31 + static_cast<unsigned>(n));
      // Cluster centres on bucket faces (multiples of 16 tol) and inside buckets; points
      // scattered within 0.2 .. 1.5 tol of them: chains, pairs across faces and corners, and
      // exact duplicates.
      std::uniform_int_distribution<int> cell(-3, 3);
      std::uniform_real_distribution<double> unit(-1, 1), frac(0, 1);
      ndc::Complex<S> c;
      c.n = n;
      c.k = 2;
      for (int cluster = 0; cluster < 60; ++cluster) {
        std::vector<double> centre(n);
        for (int j = 0; j < n; ++j)
          centre[j] = 16 * tol * (cell(rng) + (cluster % 3 == 0 ? 0.0 : frac(rng)));
        const int points = 1 + cluster % 5;
        for (int p = 0; p < points; ++p) {
          std::vector<S> x(n);
          const double spread = p == 0 ? 0.0 : (p % 2 ? 0.6 : 1.5) * tol / std::sqrt(double(n));
          for (int j = 0; j < n; ++j) x[j] = S(centre[j] + spread * unit(rng));
          c.addVertex(x, cluster);
          if (p == 3) c.addVertex(x, cluster);  // an exact duplicate
        }
      }
      std::uniform_int_distribution<std::int32_t> vertex(
          0, static_cast<std::int32_t>(c.vertexCount()) - 1);
      for (int s = 0; s < 200; ++s) {
        const std::int32_t t[3] = {vertex(rng), vertex(rng), vertex(rng)};
        c.addSimplex(t);
      }
      const ndc::Complex<S> welded = ndc::weld(c, tol), expected = referenceWeld(c, tol);
      CHECK(welded.vertexCount() < c.vertexCount());
      CHECK(welded.vertices == expected.vertices);
      CHECK(welded.vertexCell == expected.vertexCell);
      CHECK(welded.simplices == expected.simplices);
    }
  }
}

//! [analysis-chord]
TEMPLATE_TEST_CASE("Residual and chord error of a polygon inscribed in the unit circle",
                   "[analysis]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using std::acos;
  using std::cos;
  using std::sin;
  const ndc::Problem problem = makeProblem(2, {"x0^2 + x1^2 - 1"}, 2);
  const ndc::System<S> system(problem);
  const ndc::Projection<S> projection = ndc::createProjection<S>("newton", system);
  const S pi = acos(S(-1));
  for (int count : {5, 12, 64}) {
    INFO("N = " << count);
    ndc::Complex<S> polygon;
    polygon.n = 2;
    polygon.k = 1;
    for (int i = 0; i < count; ++i) {
      const S a = 2 * pi * S(i) / S(count);
      const std::vector<S> x{cos(a), sin(a)};
      polygon.addVertex(x);
    }
    for (int i = 0; i < count; ++i) {
      const std::int32_t seg[2] = {i, (i + 1) % count};
      polygon.addSimplex(seg);
    }
    const auto stats =
        ndc::analyse<S>(ndc::weld(polygon, 1e-9), system, ndc::makeProjector(projection));
    CHECK(stats.vertices == count);
    CHECK(stats.eulerCharacteristic == 0);
    CHECK(stats.maxResidual <= (std::is_same_v<S, double> ? 1e-15 : 1e-35));
    // A chord's midpoint is at radius cos(pi / N); its projection is radial.
    const double expected = 1 - std::cos(M_PI / count);
    CHECK(stats.chordFailures == 0);
    CHECK(std::abs(stats.maxChordError - expected) <= 1e-14);
  }

  SECTION("a projector that always fails leaves the chord error out and counts it") {
    ndc::Complex<S> segment = makeComplex<S>(2, 1, {{1, 0}, {0, 1}}, {{0, 1}});
    const ndc::Projector<S> fail = [](std::span<S>) { return ndc::ProjectedPoint<S>{}; };
    const auto stats = ndc::analyse<S>(segment, system, fail);
    CHECK(stats.chordFailures == 1);
    CHECK(stats.maxChordError == 0.0);
  }
}
//! [analysis-chord]

TEMPLATE_TEST_CASE("Welding then dropping unused vertices leaves no isolated vertex", "[analysis]",
                   NDC_SCALARS) {
  // Generated triangle fans with, between them, vertices of no triangle and triangles whose
  // corners weld into one point (as where M passes through a corner of the domain): every
  // vertex left belongs to a triangle, the triangles keep their corners' coordinates.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int round = 0; round < 20; ++round) {
    ndc::Complex<TestType> c;
    c.n = 3;
    c.k = 2;
    for (int t = 0; t < 30; ++t) {
      std::vector<TestType> x(3), y, z, w = {TestType(unit(rng)), TestType(2), TestType(2)};
      for (TestType& v : x) v = TestType(unit(rng));
      y = {TestType(unit(rng)), x[1], x[2]};
      z = {x[0], TestType(unit(rng)), x[2]};
      const auto a = c.addVertex(x), b = c.addVertex(y), d = c.addVertex(z);
      if (t % 3 == 0) c.addVertex(w);  // stray
      if (t % 4 == 0) {
        // Three corners within the weld tolerance of one point: a degenerate triangle.
        const auto e = c.addVertex(x), f = c.addVertex(x);
        const std::int32_t collapsed[3] = {a, e, f};
        c.addSimplex(collapsed);
      }
      const std::int32_t tri[3] = {a, b, d};
      c.addSimplex(tri);
    }
    ndc::Complex<TestType> welded = ndc::weld(c, 1e-9);
    const std::size_t triangles = welded.simplexCount();
    std::vector<TestType> before;
    for (std::int32_t v : welded.simplices)
      for (const TestType& x : welded.vertex(std::size_t(v))) before.push_back(x);
    ndc::dropUnusedVertices(welded);
    std::vector<char> used(welded.vertexCount(), 0);
    for (std::int32_t v : welded.simplices) used[std::size_t(v)] = 1;
    CHECK(std::count(used.begin(), used.end(), 0) == 0);
    CHECK(welded.vertexCount() == 90);  // 3 per fan triangle; the welded corners are theirs
    CHECK(welded.simplexCount() == triangles);
    std::vector<TestType> after;
    for (std::int32_t v : welded.simplices)
      for (const TestType& x : welded.vertex(std::size_t(v))) after.push_back(x);
    CHECK(after == before);
  }
}
