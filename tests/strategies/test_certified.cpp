// Per-cell topology certificates and adaptive refinement in the crossing connection
// (`summary.topology`, ndc::Settings::maxDepth) through the whole pipeline (ndc::runPipeline,
// default settings but the depth, the refinement limit and the scalar).
//
// A certificate is a claim about the answer, so every test here is built to catch a false one:
//  - Thin features (genus2, thin-torus, two-spheres-close, flat-top-torus, curve-pair-close in
//    experiments/problems/), and the R^6 torus on a coarse grid, at a base depth where the
//    uniform grid is too coarse: with the default refinement limit the run must be certified
//    and right (components, Euler characteristic, no non-manifold or boundary edge); with
//    refinement off (maxDepth = depth) it may fail, but if it says certified it must be right.
//  - A falsification corpus: seeded random similarity embeddings (rotation, scaling, offset)
//    of circles, 2-spheres, ellipsoids, ring tori and Clifford tori in R^3..R^7, on boxes not
//    aligned to them. Every certified run must be right; false certificates must be 0; the
//    share certified is printed (WARN). 40 seeds here, all 200 under [slow].
//  - Surfaces that leave the domain (a cylinder, a spherical cap, a plane, an annulus in R^4):
//    certified, with the true boundary loops.
// In every run the topology record must be consistent with itself (certified means nothing
// uncertified and no reason; refinement happened iff a leaf is deeper than the base level).
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <span>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "applications/load.hpp"
#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

using ndc::Problem;
using ndc::RunResult;
using ndc::Settings;

// --- Running and checking ------------------------------------------------------------------------

/// The true topology of M in the domain.
struct Truth {
  long components = 1;
  long euler = 0;
  /// 0 for a closed M; for a surface cut by the domain, the number of its boundary loops.
  long boundaryLoops = 0;
};

/// Default settings but the depth, the refinement limit (0: the default) and the scalar (MPFR
/// at 128 bits).
template <class S>
Settings settingsFor(int depth, int maxDepth) {
  Settings s;
  s.depth = depth;
  s.maxDepth = maxDepth;
  if constexpr (!std::is_same_v<S, double>) {
    s.scalar = "mpfr";
    s.precisionBits = 128;
  }
  return s;
}

template <class S>
RunResult solve(const Problem& problem, int depth, int maxDepth = 0) {
  ndc::test::PrecisionScope<S> scope(128);
  return ndc::runPipeline(problem, settingsFor<S>(depth, maxDepth));
}

template <class S>
double residualBound() {
  return std::is_same_v<S, double> ? 1e-9 : 1e-25;
}

Problem example(const std::string& name) {
  return ndc::loadProblem(fs::path(ndc::test::sourceDir()) / "experiments" / "problems" /
                          (name + ".toml"));
}

std::string describe(const RunResult& r) {
  const auto& s = r.summary;
  const auto& m = s.mesh;
  const auto& t = s.topology;
  std::ostringstream out;
  out << s.problem << " n " << s.n << " k " << s.k << " depth " << s.settings.depth << " "
      << s.settings.scalar << ": V " << m.vertices << " E " << m.edges << " T " << m.triangles
      << " components " << m.components << " chi " << m.eulerCharacteristic << " boundary "
      << m.boundaryEdges << " (" << m.boundaryComponents << " loops) nonmanifold "
      << m.nonmanifoldEdges << " open " << m.openEnds << " branch " << m.branchVertices
      << " residual " << m.maxResidual << " ambiguous " << s.ambiguousCells << " singular "
      << s.singularCells << " | topology: certified " << t.certified << " reason '" << t.reason
      << "' cells certified " << t.certifiedCells << " refined " << t.refinedCells
      << " uncertified " << t.uncertifiedCells << " levels " << t.baseLevel << ".." << t.maxLevel
      << " (max " << t.maxDepth << ")";
  return out.str();
}

/// Whether the mesh has the true topology: the components and Euler characteristic, and no
/// defect (k = 1: no open end or branch vertex; k = 2: no non-manifold edge, and boundary edges
/// only as the true boundary loops). `why` gets what differs.
bool rightTopology(const RunResult& r, const Truth& truth, std::string& why) {
  const auto& m = r.summary.mesh;
  std::ostringstream out;
  if (m.vertices == 0) out << "empty mesh; ";
  if (m.components != truth.components) out << "components " << m.components << "; ";
  if (m.eulerCharacteristic != truth.euler) out << "chi " << m.eulerCharacteristic << "; ";
  if (r.k == 1) {
    if (m.openEnds != 0) out << "open ends " << m.openEnds << "; ";
    if (m.branchVertices != 0) out << "branch vertices " << m.branchVertices << "; ";
  } else {
    if (m.nonmanifoldEdges != 0) out << "non-manifold edges " << m.nonmanifoldEdges << "; ";
    if (truth.boundaryLoops == 0 && m.boundaryEdges != 0)
      out << "boundary edges " << m.boundaryEdges << "; ";
    if (m.boundaryComponents != truth.boundaryLoops)
      out << "boundary loops " << m.boundaryComponents << "; ";
  }
  why = out.str();
  return why.empty();
}

/// The same as CHECKs, one per statistic (so that a failure names it).
void checkTopology(const RunResult& r, const Truth& truth) {
  const auto& m = r.summary.mesh;
  CHECK(m.vertices > 0);
  CHECK(m.components == truth.components);
  CHECK(m.eulerCharacteristic == truth.euler);
  if (r.k == 1) {
    CHECK(m.openEnds == 0);
    CHECK(m.branchVertices == 0);
  } else {
    CHECK(m.nonmanifoldEdges == 0);
    CHECK(m.boundaryComponents == truth.boundaryLoops);
    if (truth.boundaryLoops == 0) CHECK(m.boundaryEdges == 0);
    if (truth.boundaryLoops > 0) CHECK(m.boundaryEdges > 0);
  }
}

/// The topology record must be consistent with the settings and with itself, certified or not.
void checkRecord(const RunResult& r, const Problem& problem, int depth, int maxDepth) {
  const auto& t = r.summary.topology;
  CHECK(t.baseLevel == depth);
  if (maxDepth > 0) {
    CHECK(t.maxDepth == maxDepth);
  } else {
    // The default (ndc::defaultMaxDepth).
    CHECK(t.maxDepth == ndc::defaultMaxDepth(problem.n(), depth));
  }
  CHECK(t.maxLevel >= t.baseLevel);
  CHECK(t.maxLevel <= t.maxDepth);
  // Refinement happened iff some leaf is deeper than the base grid.
  CHECK((t.refinedCells > 0) == (t.maxLevel > t.baseLevel));
  CHECK(t.certifiedCells >= 0);
  CHECK(t.refinedCells >= 0);
  CHECK(t.uncertifiedCells >= 0);
  CHECK(t.uncertified.size() <= static_cast<std::size_t>(t.uncertifiedCells));
  if (t.certified) {
    CHECK(t.reason.empty());
    CHECK(t.uncertifiedCells == 0);
    CHECK(t.uncertified.empty());
    CHECK(t.certifiedCells > 0);  // M is not empty in any problem here
  } else {
    CHECK(!t.reason.empty());  // an uncertified run says why
  }
  // Every uncertified cell is a cell of the 2^n-tree: a box of the domain as wide as its level
  // says, at a level the run reached.
  const int n = problem.n();
  for (const auto& cell : t.uncertified) {
    CHECK(!cell.reason.empty());
    CHECK(cell.level >= t.baseLevel);
    CHECK(cell.level <= t.maxLevel);
    REQUIRE(cell.lo.size() == static_cast<std::size_t>(n));
    REQUIRE(cell.hi.size() == static_cast<std::size_t>(n));
    for (int j = 0; j < n; ++j) {
      const double slack = 1e-9 * problem.domain.width(j);
      const double width = std::ldexp(problem.domain.width(j), -cell.level);
      CHECK(std::abs((cell.hi[j] - cell.lo[j]) - width) <= 1e-9 * width);
      CHECK(cell.lo[j] >= problem.domain.lo[j] - slack);
      CHECK(cell.hi[j] <= problem.domain.hi[j] + slack);
    }
  }
}

/// Edges of a triangle mesh with the number of triangles on each.
std::map<std::pair<std::int32_t, std::int32_t>, int> edgeCounts(const RunResult& r) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> edges;
  for (std::size_t t = 0; t + 2 < r.simplices.size(); t += 3) {
    for (int i = 0; i < 3; ++i) {
      std::int32_t a = r.simplices[t + i], b = r.simplices[t + (i + 1) % 3];
      if (a > b) std::swap(a, b);
      ++edges[{a, b}];
    }
  }
  return edges;
}

// --- Thin features -------------------------------------------------------------------------------

/// An example problem with a thin feature at a base depth where the uniform grid is too coarse
/// for it. The truth is repeated here and compared with the file's [expect].
struct ThinCase {
  const char* problem;
  int depth;
  Truth truth;
  bool mpfr;  ///< also run in MPFR (5-10x slower: small depths only)
};

/// The depths: each one where the uniform grid is too coarse for the feature (the geometry is in
/// each file's description).
const std::vector<ThinCase> kThinCases = {
    // 16 non-manifold edges on the uniform grid (README, "Known limits").
    {"genus2", 5, {1, -2, 0}, false},
    // The tube (0.3 across) against x, y cells of 0.31 and 0.16, and a cap 0.025 thick above
    // the grid plane z = 0.125.
    {"thin-torus", 3, {1, 0, 0}, true},
    {"thin-torus", 4, {1, 0, 0}, false},
    // Both near points of the gap of 0.05 in one column of cells.
    {"two-spheres-close", 3, {2, 4, 0}, true},
    {"two-spheres-close", 4, {2, 4, 0}, false},
    // The tube (0.4 across) against x, y cells of 0.375 and 0.19, and flat caps a third of a z
    // cell thick above and below grid planes.
    {"flat-top-torus", 3, {1, 0, 0}, false},
    {"flat-top-torus", 4, {1, 0, 0}, false},
    // The curves pass 0.001 apart, 1/14 of an x cell at depth 8 (curves are cheap there); the
    // first grid plane between them is at level 11, within the default limit (depth + 4).
    {"curve-pair-close", 8, {2, 0, 0}, false},
    // A coarse grid in R^6: 1,704 of the base cells fail, and one round of refinement makes 2^6
    // children of each (109,056 leaves), which the leaves' budget must allow (2^(n-k) per
    // solution leaf; at 2 per solution leaf, 65,920, nothing was refined and 4 edges were
    // non-manifold).
    {"torus-r6", 3, {1, 0, 0}, false},
};

}  // namespace

TEMPLATE_TEST_CASE("certified: thin features come out certified and right after refinement",
                   "[certified]", NDC_SCALARS) {
  const bool mpfr = !std::is_same_v<TestType, double>;
  long runs = 0, uniformWrong = 0;
  std::ostringstream log;
  for (const ThinCase& c : kThinCases) {
    if (mpfr && !c.mpfr) continue;
    ++runs;
    INFO(c.problem << " at depth " << c.depth);
    const Problem problem = example(c.problem);
    // The truth of the table is the file's [expect] (a changed file must change both).
    REQUIRE(problem.expect.components == c.truth.components);
    REQUIRE(problem.expect.eulerCharacteristic == c.truth.euler);

    // Refinement off: the uniform grid. It may be wrong (that is why these depths were chosen),
    // but then it must not be certified: a certified wrong mesh is the failure this catches.
    const RunResult uniform = solve<TestType>(problem, c.depth, c.depth);
    std::string uniformWhy;
    const bool uniformRight = rightTopology(uniform, c.truth, uniformWhy);
    {
      INFO("uniform grid: " << describe(uniform) << "\nwrong: " << uniformWhy);
      checkRecord(uniform, problem, c.depth, c.depth);
      CHECK(uniform.summary.topology.refinedCells == 0);
      CHECK(uniform.summary.topology.maxLevel == c.depth);
      if (uniform.summary.topology.certified) CHECK(uniformRight);
    }
    uniformWrong += !uniformRight;

    // Default settings (refinement down to depth + 10): certified, and the true topology.
    const RunResult refined = solve<TestType>(problem, c.depth);
    {
      std::string why;
      rightTopology(refined, c.truth, why);
      INFO("refined: " << describe(refined) << "\nwrong: " << why);
      checkRecord(refined, problem, c.depth, 0);
      CHECK(refined.summary.topology.certified);
      checkTopology(refined, c.truth);
      CHECK(refined.summary.mesh.maxResidual <= residualBound<TestType>());
      // The uniform grid was wrong, so a right mesh needed finer cells than the base grid.
      if (!uniformRight) {
        CHECK(refined.summary.topology.refinedCells > 0);
        CHECK(refined.summary.topology.maxLevel > c.depth);
      }
    }
    log << c.problem << " depth " << c.depth << ": uniform " << (uniformRight ? "right" : "wrong")
        << (uniform.summary.topology.certified ? ", certified" : ", not certified")
        << "; refined to level " << refined.summary.topology.maxLevel << ", "
        << (refined.summary.topology.certified ? "certified" : "not certified") << "\n";
  }
  WARN(log.str());
  CHECK(runs > 0);
  // The cases must exercise the refinement: genus2 at depth 5 is wrong on the uniform grid (16
  // non-manifold edges, README), so at least that one is.
  if (!mpfr) CHECK(uniformWrong >= 1);
}

// --- The chord tolerance ------------------------------------------------------------------------

TEMPLATE_TEST_CASE("certified: --tolerance refines until the chord error is below it",
                   "[certified]", NDC_SCALARS) {
  const bool mpfr = !std::is_same_v<TestType, double>;
  struct ChordCase {
    const char* problem;
    int depth;
    double tolerance;
    bool mpfr;
  };
  const std::vector<ChordCase> cases = {{"sphere", 3, 2e-3, true},
                                        {"circle-3d", 3, 1e-4, true},
                                        {"space-curve-r4", 3, 2e-3, false},
                                        {"clifford-torus", 3, 2e-3, false},
                                        {"torus", 4, 1e-3, false}};
  for (const ChordCase& c : cases) {
    if (mpfr && !c.mpfr) continue;
    INFO(c.problem << " at depth " << c.depth << ", tolerance " << c.tolerance);
    const Problem problem = example(c.problem);
    Settings settings = settingsFor<TestType>(c.depth, 0);
    const RunResult base = solve<TestType>(problem, c.depth);
    settings.tolerance = c.tolerance;
    ndc::test::PrecisionScope<TestType> scope(128);
    const RunResult fine = ndc::runPipeline(problem, settings);
    INFO("base: " << describe(base) << "\nwith the tolerance: " << describe(fine));
    // The base grid misses the tolerance, so the test needs the refinement it checks.
    REQUIRE(base.summary.mesh.maxChordError > c.tolerance);
    const auto& m = fine.summary.mesh;
    CHECK(m.maxChordError <= c.tolerance);
    CHECK(m.chordFailures == 0);
    CHECK(fine.summary.topology.certified);
    CHECK(m.components == *problem.expect.components);
    CHECK(m.eulerCharacteristic == *problem.expect.eulerCharacteristic);
    CHECK(m.maxResidual <= residualBound<TestType>());
    CHECK(fine.summary.settings.depth == c.depth);
    CHECK(fine.summary.topology.maxLevel > c.depth);
  }
}

// --- Surfaces that leave the domain --------------------------------------------------------------

namespace {

/// The cylinder of radius 0.5 cut by z = -1 and z = 1: an annulus, two boundary loops. On
/// [-1, 1]^3 it contains the grid lines x = +-0.5, y = 0 and x = 0, y = +-0.5 at every depth >= 2
/// and is tangent there to the grid planes through them.
const char* const kCylinder = R"toml(name = "cylinder-r0.5"
variables = ["x", "y", "z"]
domain = [[-1, 1], [-1, 1], [-1, 1]]
equations = ["x^2 + y^2 - 0.25"]
)toml";

/// The sphere of radius 0.7 about (0, 0, -0.6) cut by z = -1 in a circle of radius 0.57: a disk
/// (the sphere minus a cap), one boundary loop; |x|, |y| <= 0.7 and z <= 0.1 inside.
const char* const kSphericalCap = R"toml(name = "spherical-cap"
variables = ["x", "y", "z"]
domain = [[-1, 1], [-1, 1], [-1, 1]]
equations = ["x^2 + y^2 + (z + 0.6)^2 - 0.49"]
)toml";

/// A plane through (0.5, 0, 0) cut by the cube: a convex polygon, one boundary loop.
const char* const kPlane = R"toml(name = "plane"
variables = ["x", "y", "z"]
domain = [[-1, 1], [-1, 1], [-1, 1]]
equations = ["x + 2*y + 3*z - 0.5"]
)toml";

/// In R^4 (two equations: the level perturbation is on): the circle x^2 + y^2 = 0.3 times the
/// line w = 0.5 z + 0.1 (|w| <= 0.6 inside), cut by z = -1 and z = 1: an annulus.
const char* const kAnnulusR4 = R"toml(name = "annulus-r4"
variables = ["x", "y", "z", "w"]
domain = [[-1, 1], [-1, 1], [-1, 1], [-1, 1]]
equations = ["x^2 + y^2 - 0.3", "w - 0.5*z - 0.1"]
)toml";

/// A surface cut by the domain boundary, with its boundary loops.
struct OpenCase {
  const char* label;
  const char* text;
  int depth;
  std::optional<int> mpfrDepth;
  Truth truth;
};

const std::vector<OpenCase> kOpenCases = {
    {"cylinder", kCylinder, 4, 3, {1, 0, 2}},
    {"spherical cap", kSphericalCap, 4, 3, {1, 1, 1}},
    {"plane", kPlane, 4, {}, {1, 1, 1}},
    {"annulus in R^4", kAnnulusR4, 4, {}, {1, 0, 2}},
};

}  // namespace

TEMPLATE_TEST_CASE("certified: surfaces that leave the domain are certified with their boundary",
                   "[certified]", NDC_SCALARS) {
  const bool mpfr = !std::is_same_v<TestType, double>;
  long runs = 0;
  for (const OpenCase& c : kOpenCases) {
    if (mpfr && !c.mpfrDepth) continue;
    const int depth = mpfr ? *c.mpfrDepth : c.depth;
    ++runs;
    const Problem problem = ndc::parseProblem(c.text, std::string(c.label) + ".toml");
    const RunResult r = solve<TestType>(problem, depth);
    INFO(c.label << ": " << describe(r));
    REQUIRE(r.k == 2);
    checkRecord(r, problem, depth, 0);
    CHECK(r.summary.topology.certified);
    checkTopology(r, c.truth);
    CHECK(r.summary.mesh.maxResidual <= residualBound<TestType>());

    // The boundary is where M leaves the domain: every boundary vertex lies within one cell of
    // the base grid of the domain boundary (refined cells are smaller still).
    const int n = r.n;
    const auto nearBoundary = [&](std::int32_t v) {
      for (int j = 0; j < n; ++j) {
        const double x = r.vertices[std::size_t(v) * n + j];
        const double width = problem.domain.width(j) / double(1 << depth) * (1 + 1e-6);
        if (x - problem.domain.lo[j] <= width || problem.domain.hi[j] - x <= width) return true;
      }
      return false;
    };
    long boundary = 0, far = 0;
    for (const auto& [edge, triangles] : edgeCounts(r)) {
      if (triangles != 1) continue;
      ++boundary;
      far += !nearBoundary(edge.first) || !nearBoundary(edge.second);
    }
    CHECK(boundary == r.summary.mesh.boundaryEdges);
    CHECK(far == 0);
  }
  CHECK(runs > 0);
}

// --- The falsification corpus --------------------------------------------------------------------

namespace {

/// Shortest decimal text that reads back as the same double.
std::string number(double v) {
  char buffer[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
    if (std::strtod(buffer, nullptr) == v) break;
  }
  return buffer;
}

/// `equation` with every name y<i> (one digit) replaced by coordinate[i].
std::string substitute(const std::string& equation, const std::vector<std::string>& coordinate) {
  std::string out;
  for (std::size_t i = 0; i < equation.size(); ++i) {
    if (equation[i] == 'y' && i + 1 < equation.size() &&
        std::isdigit(static_cast<unsigned char>(equation[i + 1]))) {
      out += coordinate.at(static_cast<std::size_t>(equation[++i] - '0'));
    } else {
      out += equation[i];
    }
  }
  return out;
}

/// A random orthogonal n x n matrix from a seeded std::mt19937, as in test_degenerate.cpp: the
/// orthogonal factor of a Gaussian matrix (Box-Muller on our own uniforms, so that every
/// standard library draws the same), columns signed by diag(R).
Eigen::MatrixXd randomRotation(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const auto unit = [&] { return (double(rng()) + 0.5) * 0x1.0p-32; };
  Eigen::MatrixXd g(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double u = unit(), v = unit();  // in this order (not two calls in one expression)
      g(i, j) = std::sqrt(-2 * std::log(u)) * std::cos(2 * std::numbers::pi * v);
    }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd r = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int j = 0; j < n; ++j)
    if (r(j, j) < 0) q.col(j) *= -1;
  return q;
}

enum class Family { circle, sphere, ellipsoid, torus, clifford };

const char* familyName(Family f) {
  switch (f) {
    case Family::circle:
      return "circle";
    case Family::sphere:
      return "sphere";
    case Family::ellipsoid:
      return "ellipsoid";
    case Family::torus:
      return "torus";
    case Family::clifford:
      return "clifford";
  }
  return "?";
}

/// What a seed builds: a family, the ambient dimension and the base depth.
struct Slot {
  Family family;
  int n;
  int depth;
};

/// Seeds cycle through these 20 slots (seed s uses slot (s - 1) % 20), so that the first 40
/// seeds are two rounds of the mix: circles (k = 1) in R^3..R^7, surfaces in R^3..R^5 at depth
/// 3 or 4. Slot 20 is a surface in R^6 or R^7 (expensive: depth 3, one seed in 20), from
/// kHighSlots in turn.
const std::array<Slot, 20> kSlots = {{
    {Family::circle, 3, 4},    {Family::sphere, 3, 4},   {Family::torus, 3, 4},
    {Family::ellipsoid, 3, 4}, {Family::circle, 4, 4},   {Family::clifford, 4, 3},
    {Family::sphere, 4, 3},    {Family::torus, 4, 3},    {Family::circle, 5, 4},
    {Family::ellipsoid, 4, 3}, {Family::circle, 6, 4},   {Family::sphere, 5, 3},
    {Family::circle, 7, 4},    {Family::clifford, 5, 3}, {Family::ellipsoid, 5, 3},
    {Family::torus, 5, 3},     {Family::torus, 3, 3},    {Family::ellipsoid, 3, 3},
    {Family::clifford, 4, 4},  {Family::sphere, 6, 3},  // slot 20: replaced from kHighSlots
}};

const std::array<Slot, 10> kHighSlots = {{
    {Family::sphere, 6, 3},
    {Family::clifford, 6, 3},
    {Family::ellipsoid, 6, 3},
    {Family::sphere, 7, 3},
    {Family::clifford, 7, 3},
    {Family::ellipsoid, 7, 3},
    {Family::torus, 6, 3},
    {Family::clifford, 6, 3},
    {Family::sphere, 6, 3},
    {Family::ellipsoid, 7, 3},
}};

/// One member of the corpus: a model manifold M0 in the first 2 (ellipse), 3 (sphere, ellipsoid,
/// ring torus) or 4 (Clifford torus) coordinates of y in R^n, the other coordinates fixed at 0
/// by linear equations, embedded by
/// x = offset + scale Q^T y (Q a random rotation), i.e. the equations in x are those of M0 in
/// y = Q (x - offset) / scale. The domain is a box around the ball of radius scale * reach
/// about the offset, with a random margin of 10% to 40% on each side.
struct Embedding {
  std::uint32_t seed = 0;
  Slot slot{};
  std::string name, text;
  std::vector<double> params;  ///< the model's sizes (semi-axes, radii)
  double reach = 0;            ///< max |y| over M0
  double scale = 1;
  std::vector<double> offset;
  Eigen::MatrixXd q;
  Truth truth;
  int k() const { return slot.family == Family::circle ? 1 : 2; }
};

Embedding embedding(std::uint32_t seed) {
  Embedding e;
  e.seed = seed;
  const std::size_t index = (seed - 1) % kSlots.size();
  e.slot = index + 1 == kSlots.size() ? kHighSlots[((seed - 1) / kSlots.size()) % kHighSlots.size()]
                                      : kSlots[index];
  const int n = e.slot.n;
  // The sizes, scale and offset from a stream of their own (the rotation uses std::mt19937(seed)).
  std::mt19937 rng(seed * 2654435761u + 12345u);
  const auto unit = [&] { return (double(rng()) + 0.5) * 0x1.0p-32; };
  const auto draw = [&](double lo, double hi) { return lo + (hi - lo) * unit(); };

  // The model M0 in y0..y{n-1} and its truth.
  std::vector<std::string> equations;
  int fixedFrom = 3;  // y_i = 0 for i >= fixedFrom
  switch (e.slot.family) {
    case Family::circle: {  // an ellipse with semi-axes a, b in [0.5, 1]
      const double a = draw(0.5, 1), b = draw(0.5, 1);
      e.params = {a, b};
      equations.push_back(number(1 / (a * a)) + "*y0^2 + " + number(1 / (b * b)) + "*y1^2 - 1");
      e.reach = std::max(a, b);
      e.truth = {1, 0, 0};
      fixedFrom = 2;
      break;
    }
    case Family::sphere: {  // radius in [0.5, 1]
      const double rho = draw(0.5, 1);
      e.params = {rho};
      equations.push_back("y0^2 + y1^2 + y2^2 - " + number(rho * rho));
      e.reach = rho;
      e.truth = {1, 2, 0};
      break;
    }
    case Family::ellipsoid: {  // semi-axes in [0.5, 1]
      const double a = draw(0.5, 1), b = draw(0.5, 1), c = draw(0.5, 1);
      e.params = {a, b, c};
      equations.push_back(number(1 / (a * a)) + "*y0^2 + " + number(1 / (b * b)) + "*y1^2 + " +
                          number(1 / (c * c)) + "*y2^2 - 1");
      e.reach = std::max({a, b, c});
      e.truth = {1, 2, 0};
      break;
    }
    case Family::torus: {  // ring torus, R = 1, r in [0.3, 0.5]
      const double r = draw(0.3, 0.5);
      e.params = {1, r};
      equations.push_back("(y0^2 + y1^2 + y2^2 + " + number(1 - r * r) + ")^2 - 4*(y0^2 + y1^2)");
      e.reach = 1 + r;
      e.truth = {1, 0, 0};
      break;
    }
    case Family::clifford: {  // circles of radii a, b in [0.5, 1] in the (y0, y1), (y2, y3) planes
      const double a = draw(0.5, 1), b = draw(0.5, 1);
      e.params = {a, b};
      equations.push_back("y0^2 + y1^2 - " + number(a * a));
      equations.push_back("y2^2 + y3^2 - " + number(b * b));
      e.reach = std::hypot(a, b);
      e.truth = {1, 0, 0};
      fixedFrom = 4;
      break;
    }
  }
  for (int i = fixedFrom; i < n; ++i)
    equations.push_back(std::string(1, 'y').append(std::to_string(i)));

  // The similarity: y = Q (x - offset) / scale, each y_i an affine form in x.
  e.scale = draw(0.5, 2);
  for (int j = 0; j < n; ++j) e.offset.push_back(draw(-1, 1));
  e.q = randomRotation(n, seed);
  std::vector<std::string> y;
  for (int i = 0; i < n; ++i) {
    std::string form = "(";
    double constant = 0;
    for (int j = 0; j < n; ++j) {
      const double a = e.q(i, j) / e.scale;
      constant -= a * e.offset[j];
      form += (j == 0 ? (a < 0 ? "-" : "") : (a < 0 ? " - " : " + ")) + number(std::abs(a)) + "*x" +
              std::to_string(j);
    }
    form += (constant < 0 ? " - " : " + ") + number(std::abs(constant)) + ")";
    y.push_back(form);
  }

  e.name = std::string("cert-") + familyName(e.slot.family) + "-n" + std::to_string(n) + "-seed" +
           std::to_string(seed);
  std::string text = "name = \"" + e.name + "\"\nvariables = [";
  for (int j = 0; j < n; ++j) text += (j ? ", \"x" : "\"x") + std::to_string(j) + "\"";
  text += "]\ndomain = [";
  const double radius = e.scale * e.reach;
  for (int j = 0; j < n; ++j) {
    // Rounded outwards to 1e-3: the box is not centred on M, and its planes are not M's.
    const double lo = std::floor((e.offset[j] - radius * (1 + draw(0.1, 0.4))) * 1000) / 1000;
    const double hi = std::ceil((e.offset[j] + radius * (1 + draw(0.1, 0.4))) * 1000) / 1000;
    text += (j ? ", [" : "[") + number(lo) + ", " + number(hi) + "]";
  }
  text += "]\nequations = [\n";
  for (const std::string& eq : equations) text += "  \"" + substitute(eq, y) + "\",\n";
  text += "]\n\n[expect]\ncomponents = " + std::to_string(e.truth.components) +
          "\neuler_characteristic = " + std::to_string(e.truth.euler) + "\n";
  e.text = text;
  return e;
}

/// A point of M0 (in y, n coordinates) at parameters (t, u) in [0, 2 pi)^2.
std::vector<double> modelPoint(const Embedding& e, double t, double u) {
  std::vector<double> y(static_cast<std::size_t>(e.slot.n), 0.0);
  const auto& p = e.params;
  switch (e.slot.family) {
    case Family::circle:
      y[0] = p[0] * std::cos(t);
      y[1] = p[1] * std::sin(t);
      break;
    case Family::sphere:
    case Family::ellipsoid: {
      const bool round = e.slot.family == Family::sphere;  // one radius, or three semi-axes
      const double a = p[0], b = round ? p[0] : p[1], c = round ? p[0] : p[2];
      const double phi = u / 2;  // polar angle in [0, pi)
      y[0] = a * std::sin(phi) * std::cos(t);
      y[1] = b * std::sin(phi) * std::sin(t);
      y[2] = c * std::cos(phi);
      break;
    }
    case Family::torus:
      y[0] = (p[0] + p[1] * std::cos(u)) * std::cos(t);
      y[1] = (p[0] + p[1] * std::cos(u)) * std::sin(t);
      y[2] = p[1] * std::sin(u);
      break;
    case Family::clifford:
      y[0] = p[0] * std::cos(t);
      y[1] = p[0] * std::sin(t);
      y[2] = p[1] * std::cos(u);
      y[3] = p[1] * std::sin(u);
      break;
  }
  return y;
}

/// Runs seeds first..last (those of ambient dimension <= maxN) in scalar S with the default
/// refinement limit. Every certified run must have the true topology; the share certified is
/// printed.
template <class S>
void runCorpus(std::uint32_t first, std::uint32_t last, int maxN) {
  long runs = 0, certified = 0, falseCertificates = 0, uncertifiedButRight = 0;
  std::ostringstream uncertified;
  for (std::uint32_t seed = first; seed <= last; ++seed) {
    const Embedding e = embedding(seed);
    if (e.slot.n > maxN) continue;
    const Problem problem = ndc::parseProblem(e.text, e.name + ".toml");
    const RunResult r = solve<S>(problem, e.slot.depth);
    ++runs;
    std::string why;
    const bool right = rightTopology(r, e.truth, why);
    INFO(e.text << "\n" << describe(r) << "\nwrong: " << why);
    REQUIRE(r.k == e.k());
    checkRecord(r, problem, e.slot.depth, 0);
    if (!r.summary.topology.certified) {
      uncertified << "  " << e.name << " (depth " << e.slot.depth << ", "
                  << (right ? "right" : "wrong") << "): " << r.summary.topology.reason << "\n";
      uncertifiedButRight += right;
      continue;
    }
    ++certified;
    CHECK(right);  // a false certificate
    falseCertificates += !right;
  }
  std::ostringstream share;
  share << "certified " << certified << " of " << runs << " runs ("
        << (runs ? 100.0 * double(certified) / double(runs) : 0.0) << "%, "
        << (std::is_same_v<S, double> ? "double" : "mpfr") << ", seeds " << first << ".." << last
        << "); uncertified but right " << uncertifiedButRight << "; false certificates "
        << falseCertificates;
  if (!uncertified.str().empty()) share << "\nuncertified:\n" << uncertified.str();
  WARN(share.str());
  REQUIRE(falseCertificates == 0);
  // The corpus only tests certificates that are given: it must get some.
  CHECK(certified > 0);
}

}  // namespace

TEST_CASE("certified: the falsification corpus is well formed", "[certified]") {
  // The generator's truth is that of the text it writes: points of M0 mapped by the similarity
  // satisfy the problem's equations and lie inside its domain with the margin; every family
  // and dimension of the plan is there.
  std::set<std::string> names;
  std::map<std::string, int> families;
  std::map<int, int> dimensions;
  long highSurfaces = 0;
  for (std::uint32_t seed = 1; seed <= 200; ++seed) {
    const Embedding e = embedding(seed);
    INFO(e.text);
    CHECK(names.insert(e.name).second);
    ++families[familyName(e.slot.family)];
    ++dimensions[e.slot.n];
    highSurfaces += e.k() == 2 && e.slot.n >= 6;
    Problem problem;
    REQUIRE_NOTHROW(problem = ndc::parseProblem(e.text, e.name + ".toml"));
    REQUIRE(problem.n() == e.slot.n);
    REQUIRE(problem.k() == e.k());
    CHECK((e.slot.depth == 3 || e.slot.depth == 4));
    CHECK(e.scale >= 0.5);
    CHECK(e.scale <= 2);
    const int n = e.slot.n;
    for (int a = 0; a < 12; ++a) {
      for (int b = 0; b < 12; ++b) {
        const double t = 2 * std::numbers::pi * (a + 0.37) / 12;
        const double u = 2 * std::numbers::pi * (b + 0.61) / 12;
        const std::vector<double> y = modelPoint(e, t, u);
        std::vector<double> x(static_cast<std::size_t>(n));
        for (int j = 0; j < n; ++j) {
          x[j] = e.offset[j];
          for (int i = 0; i < n; ++i) x[j] += e.scale * e.q(i, j) * y[i];
        }
        for (const auto& equation : problem.equations)
          CHECK(std::abs(equation.evaluate<double>(std::span<const double>(x))) <= 1e-9);
        for (int j = 0; j < n; ++j) {
          const double margin = 0.09 * e.scale * e.reach;
          CHECK(x[j] >= problem.domain.lo[j] + margin);
          CHECK(x[j] <= problem.domain.hi[j] - margin);
        }
      }
    }
  }
  CHECK(names.size() == 200);
  for (const char* f : {"circle", "sphere", "ellipsoid", "torus", "clifford"})
    CHECK(families[f] >= 30);
  for (int n = 3; n <= 7; ++n) CHECK(dimensions[n] > 0);
  CHECK(highSurfaces == 10);
}

TEST_CASE("certified: no false certificate on the first 40 seeds of the corpus", "[certified]") {
  runCorpus<double>(1, 40, 7);
}

// All 200 seeds take about 20 minutes on one core (the surfaces in R^6 and R^7 at depth 3 refine
// to hundreds of thousands of leaves), past the test suite's budget: run on demand with
//   build/bin/ndcontour_tests "[corpus200]"
// (docs/certificate.md gives the last measured share). The first 40 seeds run in every suite.
TEST_CASE("certified: no false certificate on 200 seeded random embeddings",
          "[certified][.corpus200]") {
  runCorpus<double>(1, 200, 7);
}

TEST_CASE("certified: no false certificate in MPFR on the R^3 seeds of the first 20",
          "[certified][slow][mpfr]") {
  runCorpus<ndc::Mpfr>(1, 20, 3);
}
