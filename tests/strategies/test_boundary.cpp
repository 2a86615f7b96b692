// The domain's boundary in the crossing connection (docs/crossing.md, "The domain's boundary";
// docs/certificate.md, "The domain's boundary"): pieces of M that live in the layer of cells
// along the domain's faces (caps cutting a corner, an edge or a face of the box, strips along a
// face, curves ending on a face, an edge or a corner) are meshed with their exact topology, the
// mesh's boundary lies on the domain's faces, every vertex belongs to a simplex, and a manifold
// tangent to a face of the domain, or through a corner of it, is never certified.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Problem;
using ndc::RunResult;
using ndc::Settings;

/// A problem in x, y, z (or x, y for n = 2) on [-1, 1]^n.
Problem boxProblem(const std::string& name, int n, const std::vector<std::string>& equations) {
  std::ostringstream text;
  text << "name = \"" << name << "\"\nvariables = [\"x\", \"y\"" << (n == 3 ? ", \"z\"" : "")
       << "]\ndomain = [[-1, 1], [-1, 1]" << (n == 3 ? ", [-1, 1]" : "") << "]\nequations = [";
  for (std::size_t i = 0; i < equations.size(); ++i)
    text << (i ? ", " : "") << '"' << equations[i] << '"';
  text << "]\n";
  return ndc::parseProblem(text.str(), name + ".toml");
}

template <class S>
RunResult solve(const Problem& problem, int depth, int maxDepth = 0) {
  ndc::test::PrecisionScope<S> scope(128);
  Settings s;
  s.depth = depth;
  s.maxDepth = maxDepth;
  if constexpr (std::is_same_v<S, double>) {
    s.scalar = "double";
    s.precisionBits = 53;
  } else {
    s.scalar = "mpfr";
    s.precisionBits = 128;
  }
  return ndc::runPipeline(problem, s);
}

std::string describe(const RunResult& r) {
  const auto& s = r.summary;
  const auto& m = s.mesh;
  std::ostringstream out;
  out << s.problem << " depth " << s.settings.depth << " " << s.settings.scalar << ": V "
      << m.vertices << " E " << m.edges << " T " << m.triangles << " components " << m.components
      << " chi " << m.eulerCharacteristic << " boundary loops " << m.boundaryComponents
      << " open ends " << m.openEnds << " nonmanifold " << m.nonmanifoldEdges << " certified "
      << s.topology.certified << " (" << s.topology.reason << ")";
  return out.str();
}

/// The (k-1)-faces of the mesh on one simplex only: boundary edges (k = 2) or open ends (k = 1).
std::vector<std::vector<std::int32_t>> boundaryFaces(const RunResult& r) {
  std::map<std::vector<std::int32_t>, int> count;
  const int width = r.k + 1;
  for (std::size_t s = 0; s + width <= r.simplices.size(); s += width) {
    for (int skip = 0; skip < width; ++skip) {
      std::vector<std::int32_t> face;
      for (int i = 0; i < width; ++i)
        if (i != skip) face.push_back(r.simplices[s + i]);
      std::sort(face.begin(), face.end());
      ++count[face];
    }
  }
  std::vector<std::vector<std::int32_t>> out;
  for (const auto& [face, c] : count)
    if (c == 1) out.push_back(face);
  return out;
}

/// Whether vertex v lies on a face of the domain (within rounding).
bool onDomainFace(const RunResult& r, const Problem& p, std::int32_t v) {
  for (int j = 0; j < r.n; ++j) {
    const double x = r.vertices[std::size_t(v) * r.n + j];
    if (std::abs(x - p.domain.lo[j]) <= 1e-12 || std::abs(x - p.domain.hi[j]) <= 1e-12) return true;
  }
  return false;
}

/// The mesh of a manifold with boundary: every vertex on a simplex, the boundary on the
/// domain's faces, the topology (components, Euler characteristic, boundary loops or open
/// ends) as given, and certified.
template <class S>
void checkBounded(const Problem& p, int depth, long components, long euler, long boundary) {
  const RunResult r = solve<S>(p, depth);
  INFO(describe(r));
  const auto& m = r.summary.mesh;
  std::set<std::int32_t> used(r.simplices.begin(), r.simplices.end());
  CHECK(long(used.size()) == m.vertices);  // no stray vertex
  long off = 0;
  for (const auto& face : boundaryFaces(r))
    for (std::int32_t v : face) off += !onDomainFace(r, p, v);
  CHECK(off == 0);  // the mesh's boundary lies on the domain's boundary
  CHECK(m.components == components);
  CHECK(m.eulerCharacteristic == euler);
  if (r.k == 2) {
    CHECK(m.boundaryComponents == boundary);
    CHECK(m.nonmanifoldEdges == 0);
  } else {
    CHECK(m.openEnds == boundary);
    CHECK(m.branchVertices == 0);
  }
  CHECK(m.maxResidual <= (std::is_same_v<S, double> ? 1e-10 : 1e-30));
  CHECK(r.summary.topology.certified);
}

}  // namespace

TEMPLATE_TEST_CASE("boundary: caps cutting a corner, an edge and a face of the box", "[boundary]",
                   NDC_SCALARS) {
  // Spheres centred on a corner, an edge and beyond a face: M ∩ D is one disk, which crosses
  // no interior face of a coarse grid at all.
  const Problem corner = boxProblem("cap-corner", 3, {"(x-1)^2 + (y-1)^2 + (z-1)^2 - 0.25"});
  const Problem edge = boxProblem("cap-edge", 3, {"(x-1)^2 + (y-1)^2 + z^2 - 0.16"});
  const Problem face = boxProblem("cap-face", 3, {"(x-1.1)^2 + (y-0.1)^2 + (z-0.2)^2 - 0.09"});
  for (int depth : {2, 3, 4, 5}) {
    if (!std::is_same_v<TestType, double> && depth > 3) continue;
    DYNAMIC_SECTION("depth " << depth) {
      checkBounded<TestType>(corner, depth, 1, 1, 1);
      checkBounded<TestType>(edge, depth, 1, 1, 1);
      checkBounded<TestType>(face, depth, 1, 1, 1);
    }
  }
}

TEMPLATE_TEST_CASE("boundary: a thin strip along a face, a band through two faces", "[boundary]",
                   NDC_SCALARS) {
  // A cylinder whose axis lies beyond the face x = 1: inside the box, a strip 0.05 wide along
  // the face (a disk). A cylinder through the box along y: an annulus with its two circles on
  // the faces y = -1 and y = 1.
  const Problem strip = boxProblem("strip", 3, {"(x-1.15)^2 + (z-0.1)^2 - 0.04"});
  // (A dyadic extent, such as radius 0.5, 0.55 or 0.6, puts a line of the cylinder in a grid line
  // or a grid plane tangent to it along a line: the grid degeneracy docs/certificate.md lists as
  // not certified.)
  const Problem band = boxProblem("band", 3, {"(x-0.1)^2 + (z+0.2)^2 - 0.3"});
  for (int depth : {3, 4, 5}) {
    if (!std::is_same_v<TestType, double> && depth > 3) continue;
    DYNAMIC_SECTION("depth " << depth) {
      checkBounded<TestType>(strip, depth, 1, 1, 1);
      checkBounded<TestType>(band, depth, 1, 0, 2);
    }
  }
}

TEMPLATE_TEST_CASE("boundary: curves ending on faces and edges of the box", "[boundary]",
                   NDC_SCALARS) {
  // An arc of a circle in the plane z = 0.3 around the edge x = y = 1: from the face x = 1 to
  // the face y = 1. A curve in R^2 cutting a corner of the square. Two arcs of a hyperbola.
  const Problem arc = boxProblem("arc-edge", 3, {"(x-1)^2 + (y-1)^2 - 0.36", "z - 0.3"});
  const Problem corner2 = boxProblem("arc-corner", 2, {"(x+1)^2 + (y-1)^2 - 0.2"});
  const Problem hyperbola = boxProblem("hyperbola", 2, {"x^2 - y^2 - 0.1"});
  for (int depth : {2, 3, 4, 5}) {
    if (!std::is_same_v<TestType, double> && depth > 3) continue;
    DYNAMIC_SECTION("depth " << depth) {
      checkBounded<TestType>(arc, depth, 1, 1, 2);
      checkBounded<TestType>(corner2, depth, 1, 1, 2);
      checkBounded<TestType>(hyperbola, depth, 2, 2, 4);
    }
  }
}

TEMPLATE_TEST_CASE("boundary: tangency with the domain's faces is never certified", "[boundary]",
                   NDC_SCALARS) {
  // The unit sphere touches the six faces of [-1, 1]^3 at one point each; the unit cylinder
  // touches four faces along lines; a circle in R^2 touches the square's sides; the diagonal
  // line passes through two corners of the cube. M ∩ D differs from every nearby level set's,
  // so no run may claim its topology (refinement is bounded to keep the test short).
  const std::vector<Problem> tangent = {
      boxProblem("sphere-touching", 3, {"x^2 + y^2 + z^2 - 1"}),
      boxProblem("cylinder-touching", 3, {"x^2 + y^2 - 1"}),
      boxProblem("circle-touching", 2, {"x^2 + y^2 - 1"}),
      boxProblem("diagonal", 3, {"x - y", "y - z"}),
      boxProblem("circle-outside-touching", 2, {"(x-2)^2 + y^2 - 1"}),
  };
  for (const Problem& p : tangent) {
    for (int depth : {3, 4}) {
      if (!std::is_same_v<TestType, double> && depth > 3) continue;
      const RunResult r = solve<TestType>(p, depth, depth + 3);
      INFO(describe(r));
      CHECK_FALSE(r.summary.topology.certified);
      CHECK(r.summary.topology.reason.find("domain-boundary") != std::string::npos);
    }
  }
}

TEMPLATE_TEST_CASE("boundary: a crossing of a domain edge at a grid vertex", "[boundary]",
                   NDC_SCALARS) {
  // The sphere around the box edge x = y = 1 centred at z = 0.1 meets the edge at z = 0.5, a
  // vertex of the grid from depth 2 on, within rounding: neither edge segment's crossing can
  // be proven, and no block is tried across the domain's boundary (docs/certificate.md,
  // "The domain's boundary"). The topology must still be right, and a run that is not
  // certified must say that crossings are the cause.
  const Problem p = boxProblem("cap-edge-vertex", 3, {"(x-1)^2 + (y-1)^2 + (z-0.1)^2 - 0.16"});
  for (int depth : {2, 3}) {
    const RunResult r = solve<TestType>(p, depth, depth + 3);
    INFO(describe(r));
    const auto& m = r.summary.mesh;
    CHECK(m.components == 1);
    CHECK(m.eulerCharacteristic == 1);
    CHECK(m.boundaryComponents == 1);
    if (!r.summary.topology.certified)
      CHECK(r.summary.topology.reason.find("crossing") != std::string::npos);
  }
}

TEMPLATE_TEST_CASE("boundary: a band through the box along a grid line", "[boundary]",
                   NDC_SCALARS) {
  // The natural radius 0.5 puts the line x = 0.5, z = -0.5 of the cylinder in a grid line: the
  // known limit of tangency with the grid along a curve (docs/certificate.md, "Status"). The
  // annulus must still come out right, its boundary on the faces y = -1 and y = 1, and a run
  // that is not certified must say that crossings are the cause.
  const Problem p = boxProblem("band-grid-line", 3, {"(x-0.1)^2 + (z+0.2)^2 - 0.25"});
  const RunResult r = solve<TestType>(p, 3, 5);
  INFO(describe(r));
  const auto& m = r.summary.mesh;
  CHECK(m.components == 1);
  CHECK(m.eulerCharacteristic == 0);
  CHECK(m.boundaryComponents == 2);
  if (!r.summary.topology.certified)
    CHECK(r.summary.topology.reason.find("crossing") != std::string::npos);
}
