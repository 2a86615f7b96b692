// The crossing connection for manifolds of dimension k >= 3 (docs/crossing.md, "Any k"):
//  - [kuhn] the combinatorics: the axis subsets, the Kuhn chains, the Freudenthal split of a
//    block of cubes (every inner ridge on two simplices, induced orientations opposite) and the
//    sphere test on known complexes;
//  - [higher-k] whole runs (ndc::runPipeline): 3-manifolds with known Betti numbers (3-spheres
//    in R^4 and R^5, S^1 x S^2 in R^5, a torus times a segment cut by the domain, half a
//    3-sphere ending on the domain's boundary), in double and MPFR, every mesh closed (or
//    bounded where M leaves the domain) and consistently oriented; and a falsification corpus
//    of seeded random rotations and offsets in which no certified run may be wrong.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "applications/load.hpp"
#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "strategies/connection/crossing/kuhn.hpp"
#include "tests/solve_support.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::crossing_detail::axisSubsets;
using ndc::crossing_detail::kuhnChains;
using ndc::crossing_detail::SphereCheck;
using ndc::crossing_detail::sphereTest;

/// The facets of an oriented simplex with their induced signs: facet i (vertex i dropped)
/// sorted, and (-1)^i times the sign of the sort.
std::vector<std::pair<std::vector<int>, int>> orientedFacets(const std::vector<int>& simplex) {
  std::vector<std::pair<std::vector<int>, int>> out;
  for (std::size_t i = 0; i < simplex.size(); ++i) {
    std::vector<int> facet;
    for (std::size_t j = 0; j < simplex.size(); ++j)
      if (j != i) facet.push_back(simplex[j]);
    int sign = i % 2 ? -1 : 1;
    for (std::size_t a = 0; a < facet.size(); ++a)
      for (std::size_t b = a + 1; b < facet.size(); ++b) sign *= facet[a] > facet[b] ? -1 : 1;
    std::sort(facet.begin(), facet.end());
    out.emplace_back(facet, sign);
  }
  return out;
}

/// Whether every ridge of the complex lies on at most two simplices, and those on two induce
/// opposite orientations on it; `boundary` gets the ridges on one.
bool consistentlyOriented(const std::vector<std::vector<int>>& simplices, long& boundary) {
  std::map<std::vector<int>, std::vector<int>> signs;
  for (const auto& s : simplices)
    for (const auto& [facet, sign] : orientedFacets(s)) signs[facet].push_back(sign);
  boundary = 0;
  for (const auto& [facet, on] : signs) {
    if (on.size() > 2) return false;
    if (on.size() == 1) ++boundary;
    if (on.size() == 2 && on[0] == on[1]) return false;
  }
  return true;
}

TEST_CASE("kuhn: axis subsets and chains", "[kuhn]") {
  for (int n = 1; n <= 8; ++n) {
    for (int k = 0; k <= n; ++k) {
      const auto subsets = axisSubsets(n, k);
      long binomial = 1;
      for (int i = 0; i < k; ++i) binomial = binomial * (n - i) / (i + 1);
      CHECK(long(subsets.size()) == binomial);
      for (const auto& s : subsets) CHECK(std::is_sorted(s.begin(), s.end()));
    }
  }
  for (int k = 1; k <= 5; ++k) {
    const auto chains = kuhnChains(k);
    long factorial = 1;
    for (int i = 2; i <= k; ++i) factorial *= i;
    CHECK(long(chains.size()) == factorial);
    int sum = 0;
    for (const auto& c : chains) sum += c.sign;
    CHECK(sum == (k == 1 ? 1 : 0));
  }
}

TEST_CASE("kuhn: the split of a block of cubes is a consistently oriented manifold", "[kuhn]") {
  // Every cube of a 3^k block (k = 2, 3, 4) split by the chains, oriented by their signs: a
  // triangulated k-ball whose boundary is a (k-1)-sphere.
  for (int k = 2; k <= 4; ++k) {
    const int side = 3, points = side + 1;
    const auto chains = kuhnChains(k);
    std::vector<std::vector<int>> simplices;
    std::vector<int> cube(static_cast<std::size_t>(k), 0);
    long cubes = 1;
    for (int t = 0; t < k; ++t) cubes *= side;
    for (long c = 0; c < cubes; ++c) {
      long rest = c;
      for (int t = 0; t < k; ++t) cube[std::size_t(t)] = int(rest % side), rest /= side;
      for (const auto& chain : chains) {
        std::vector<int> at = cube;
        const auto number = [&] {
          int v = 0;
          for (int t = k - 1; t >= 0; --t) v = v * points + at[std::size_t(t)];
          return v;
        };
        std::vector<int> simplex{number()};
        for (int t : chain.order) {
          ++at[std::size_t(t)];
          simplex.push_back(number());
        }
        if (chain.sign < 0) std::swap(simplex[0], simplex[1]);
        simplices.push_back(simplex);
      }
    }
    long boundary = 0;
    CHECK(consistentlyOriented(simplices, boundary));
    // The boundary: 2k faces of side^(k-1) cubes, (k-1)! ridges each.
    long expected = 2 * k;
    for (int t = 0; t < k - 1; ++t) expected *= side * (t + 1);
    CHECK(boundary == expected);
  }
}

TEST_CASE("kuhn: the sphere test on known complexes", "[kuhn]") {
  using V = std::vector<std::vector<int>>;
  CHECK(sphereTest(0, V{}) == SphereCheck::kEmpty);
  CHECK(sphereTest(0, V{{1}, {4}}) == SphereCheck::kSphere);
  CHECK(sphereTest(0, V{{1}, {2}, {3}, {4}}) == SphereCheck::kNotSphere);
  CHECK(sphereTest(1, V{{0, 1}, {1, 2}, {0, 2}}) == SphereCheck::kSphere);
  // Two cycles; a path.
  CHECK(sphereTest(1, V{{0, 1}, {1, 2}, {0, 2}, {3, 4}, {4, 5}, {3, 5}}) ==
        SphereCheck::kNotSphere);
  CHECK(sphereTest(1, V{{0, 1}, {1, 2}}) == SphereCheck::kNotSphere);
  // The boundary of a tetrahedron and the octahedron: S^2.
  CHECK(sphereTest(2, V{{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}}) == SphereCheck::kSphere);
  V octahedron;
  for (int a : {0, 1})
    for (int b : {2, 3})
      for (int c : {4, 5}) octahedron.push_back({a, b, c});
  CHECK(sphereTest(2, octahedron) == SphereCheck::kSphere);
  // The 7-vertex torus: closed and connected, chi = 0.
  V torus;
  for (int i = 0; i < 7; ++i) {
    std::vector<int> a{i, (i + 1) % 7, (i + 3) % 7}, b{i, (i + 2) % 7, (i + 3) % 7};
    std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
    torus.push_back(a), torus.push_back(b);
  }
  CHECK(sphereTest(2, torus) == SphereCheck::kNotSphere);
  // Two disjoint tetrahedron boundaries.
  V two{{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}, {4, 5, 6}, {4, 5, 7}, {4, 6, 7}, {5, 6, 7}};
  CHECK(sphereTest(2, two) == SphereCheck::kNotSphere);
  // The boundary of the 4-simplex is S^3, but for j >= 3 no count proves a sphere.
  V s3;
  for (int drop = 0; drop < 5; ++drop) {
    std::vector<int> f;
    for (int v = 0; v < 5; ++v)
      if (v != drop) f.push_back(v);
    s3.push_back(f);
  }
  CHECK(sphereTest(3, s3) == SphereCheck::kUndecided);
}

// --- whole runs ------------------------------------------------------------------------------

/// A problem in R^n with the equations given, on [lo, hi]^n.
ndc::Problem problemOf(int n, const std::vector<std::string>& equations, double lo, double hi) {
  std::ostringstream text;
  text << "name = \"k3\"\nvariables = [";
  for (int j = 0; j < n; ++j) text << (j ? ", " : "") << "\"x" << j << "\"";
  text << "]\ndomain = [";
  for (int j = 0; j < n; ++j) text << (j ? ", " : "") << "[" << lo << ", " << hi << "]";
  text << "]\nequations = [";
  for (std::size_t i = 0; i < equations.size(); ++i)
    text << (i ? ", " : "") << "\"" << equations[i] << "\"";
  text << "]\n";
  return ndc::parseProblem(text.str(), "k3.toml");
}

using ndc::test::solveAt;

/// The mesh's simplices as vertex lists.
std::vector<std::vector<int>> simplicesOf(const ndc::RunResult& r) {
  std::vector<std::vector<int>> out;
  const auto width = std::size_t(r.k + 1);
  for (std::size_t s = 0; s + width <= r.simplices.size(); s += width)
    out.emplace_back(r.simplices.begin() + long(s), r.simplices.begin() + long(s + width));
  return out;
}

std::string describe(const ndc::RunResult& r) {
  std::ostringstream out;
  const auto& m = r.summary.mesh;
  out << "k " << r.k << " depth " << r.summary.settings.depth << " " << r.summary.settings.scalar
      << ": V " << m.vertices << " components " << m.components << " chi " << m.eulerCharacteristic
      << " betti";
  for (auto b : m.betti) out << " " << b;
  out << " boundary facets " << m.boundaryFacets << " non-manifold " << m.nonmanifoldFacets
      << " | certified " << r.summary.topology.certified << " '" << r.summary.topology.reason
      << "'";
  return out.str();
}

/// The mesh is a manifold with the Betti numbers given, consistently oriented, its boundary
/// facets present exactly when M has a boundary.
void checkMesh(const ndc::RunResult& r, const std::vector<std::int64_t>& betti, bool bounded) {
  INFO(describe(r));
  const auto& m = r.summary.mesh;
  CHECK(m.betti == betti);
  CHECK(m.nonmanifoldFacets == 0);
  CHECK((m.boundaryFacets > 0) == bounded);
  long boundary = 0;
  CHECK(consistentlyOriented(simplicesOf(r), boundary));
  CHECK(boundary == m.boundaryFacets);
  CHECK(m.maxResidual < 1e-9);
}

TEMPLATE_TEST_CASE("higher k: 3-manifolds with known Betti numbers", "[higher-k]", NDC_SCALARS) {
  const bool mpfr = !std::is_same_v<TestType, double>;
  // A 3-sphere in R^4 off the grid's centre, and one centred on it (M through grid vertices).
  const auto s3 = problemOf(4,
                            {"(x0-0.0123)^2 + (x1+0.0371)^2 + (x2-0.0217)^2 + "
                             "(x3+0.0089)^2 - 0.5"},
                            -1, 1);
  checkMesh(solveAt<TestType>(s3, 3), {1, 0, 0, 1}, false);
  if (mpfr) return;
  checkMesh(solveAt<TestType>(s3, 4), {1, 0, 0, 1}, false);
  const auto centred = problemOf(4, {"x0^2 + x1^2 + x2^2 + x3^2 - 0.5"}, -1, 1);
  checkMesh(solveAt<TestType>(centred, 3), {1, 0, 0, 1}, false);
  // S^1 x S^2 in R^5.
  const auto s1s2 = problemOf(5, {"x0^2 + x1^2 - 0.55", "x2^2 + x3^2 + x4^2 - 0.62"}, -1, 1);
  checkMesh(solveAt<TestType>(s1s2, 3), {1, 1, 1, 1}, false);
  // A torus times a segment, cut by the domain along x4: T^2 x I.
  const auto slab = problemOf(5, {"x0^2 + x1^2 - 0.55", "x2^2 + x3^2 - 0.47"}, -0.93, 0.91);
  const auto r = solveAt<TestType>(slab, 3);
  checkMesh(r, {1, 2, 1, 0}, true);
  INFO(describe(r));
  CHECK(r.summary.topology.certified);
  // Half a 3-sphere: a ball ending on the domain's face w = -0.3.
  const auto half = ndc::parseProblem(
      "name = \"half\"\nvariables = [\"x\", \"y\", \"z\", \"w\"]\n"
      "domain = [[-1, 1], [-1, 1], [-1, 1], [-0.3, 1]]\n"
      "equations = [\"(x-0.0123)^2 + (y+0.0371)^2 + (z-0.0217)^2 + (w+0.0089)^2 - 0.5\"]\n",
      "half.toml");
  checkMesh(solveAt<TestType>(half, 3), {1, 0, 0, 0}, true);
}

/// A random rotation of R^5 (Gram-Schmidt on a Gaussian matrix), as rows.
std::vector<std::vector<double>> randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> gauss;
  std::vector<std::vector<double>> q(5, std::vector<double>(5));
  for (auto& row : q)
    for (double& v : row) v = gauss(rng);
  for (std::size_t i = 0; i < 5; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      double dot = 0;
      for (std::size_t t = 0; t < 5; ++t) dot += q[i][t] * q[j][t];
      for (std::size_t t = 0; t < 5; ++t) q[i][t] -= dot * q[j][t];
    }
    double norm = 0;
    for (double v : q[i]) norm += v * v;
    for (double& v : q[i]) v /= std::sqrt(norm);
  }
  return q;
}

/// Coordinate i of the rotated frame around c, (q_i . (x - c)), as text.
std::string rotated(const std::vector<std::vector<double>>& q, const std::vector<double>& c,
                    std::size_t i) {
  std::ostringstream out;
  out.precision(10);
  out << "(";
  for (std::size_t t = 0; t < 5; ++t)
    out << (t ? " + " : "") << q[i][t] << "*(x" << t << " - " << c[t] << ")";
  out << ")";
  return out.str();
}

std::string number(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

/// Seeded random tori times a segment (T^2 x I: two circles in orthogonal planes of R^5, times
/// the line left, cut by the domain) and 3-spheres (a sphere cut by a hyperplane), rotated when
/// `rotate`, else in the axes' planes with random centres and radii, at `depth`. A certified run
/// must have the true Betti numbers; returns how many were certified.
int falsify(int seeds, bool rotate, int depth, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> offset(-0.08, 0.08), radius(0.45, 0.7);
  int certified = 0, runs = 0;
  for (int s = 0; s < seeds; ++s) {
    std::vector<std::vector<double>> q = randomRotation(rng);
    if (!rotate) {
      // The axes' frame in a random order.
      std::vector<std::size_t> order{0, 1, 2, 3, 4};
      std::shuffle(order.begin(), order.end(), rng);
      for (std::size_t i = 0; i < 5; ++i) q[i].assign(5, 0.0), q[i][order[i]] = 1;
    }
    std::vector<double> c(5);
    for (double& v : c) v = offset(rng);
    const auto y = [&](std::size_t i) { return rotated(q, c, i); };
    const double r1 = radius(rng), r2 = radius(rng), r3 = radius(rng);
    const std::vector<std::pair<std::vector<std::string>, std::vector<std::int64_t>>> cases{
        {{y(0) + "^2 + " + y(1) + "^2 - " + number(r1 * r1),
          y(2) + "^2 + " + y(3) + "^2 - " + number(r2 * r2)},
         {1, 2, 1, 0}},
        {{y(0) + "^2 + " + y(1) + "^2 + " + y(2) + "^2 + " + y(3) + "^2 - " + number(r3 * r3),
          y(4)},
         {1, 0, 0, 1}}};
    for (const auto& [equations, betti] : cases) {
      const auto r = solveAt<double>(problemOf(5, equations, -1, 1), depth);
      ++runs;
      INFO("seed " << s << ": " << describe(r));
      if (!r.summary.topology.certified) continue;
      ++certified;
      CHECK(r.summary.mesh.betti == betti);
      CHECK(r.summary.mesh.nonmanifoldFacets == 0);
    }
  }
  WARN("higher k falsification (" << (rotate ? "rotated" : "axes") << ", depth " << depth
                                  << "): " << certified << " of " << runs << " runs certified");
  return certified;
}

TEST_CASE("higher k: no false certificate on seeded random offsets and radii", "[higher-k]") {
  // Some must be certified, or the test would prove nothing.
  CHECK(falsify(6, false, 3, 20261207) > 0);
}

TEST_CASE("higher k: no false certificate on seeded random rotations", "[higher-k][slow]") {
  falsify(4, true, 4, 71202621);
}

}  // namespace

namespace {

/// The example problems for k >= 3 (experiments/problems/) at two depths: the mesh has the
/// Betti numbers over Q and Z/2 and the components their [expect] states, is closed, and is
/// consistently oriented; those that the certificate reaches (docs/certificate.md, "Any k")
/// are certified.
TEST_CASE("higher k: the example 3- and 4-manifolds at two depths", "[higher-k][slow]") {
  struct Case {
    const char* name;
    std::vector<int> depths;
    bool certified;  ///< at the deeper depth
  };
  const std::vector<Case> cases{{"sphere3-r4", {3, 4}, false},
                                {"sphere3-r5", {3, 4}, false},
                                {"s1xs2-r5", {3, 4}, true},
                                {"flat-3torus-r6", {2, 3}, true},
                                {"sphere4-r6", {2, 3}, false}};
  for (const Case& c : cases) {
    const ndc::Problem p =
        ndc::loadProblem(std::filesystem::path(ndc::test::sourceDir()) / "experiments" /
                         "problems" / (std::string(c.name) + ".toml"));
    for (int depth : c.depths) {
      const auto r = solveAt<double>(p, depth);
      INFO(c.name << ": " << describe(r));
      const auto& m = r.summary.mesh;
      std::vector<std::int64_t> betti(p.expect.lists.at("betti").begin(),
                                      p.expect.lists.at("betti").end());
      std::vector<std::int64_t> z2(p.expect.lists.at("betti_z2").begin(),
                                   p.expect.lists.at("betti_z2").end());
      checkMesh(r, betti, false);
      CHECK(m.bettiZ2 == z2);
      CHECK(m.components == *p.expect.components);
      if (depth == c.depths.back()) CHECK(r.summary.topology.certified == c.certified);
    }
  }
}

}  // namespace
