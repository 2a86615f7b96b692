// Grid-degenerate inputs through the whole pipeline with default settings (issue 10, item 5):
// generated corpora of manifolds with known topology whose zero sets pass through grid
// vertices, edges and faces at every depth, solved by ndc::runPipeline with Settings{} (only
// the depth and the scalar set: the default bounding and the `crossing` connection, no jitter).
//
//  - Corpus A: circles, spheres, tori, lifted curves, planes and graph surfaces in R^2..R^7 on
//    [-1, 1]^n with dyadic or decimal coefficients, axis-aligned, so that M lies in grid planes
//    (x_j = 0), through grid vertices (x = 0.5) or along grid lines.
//  - Corpus B: the same manifolds rotated by seeded random orthogonal matrices (x -> Q x written
//    into the equations).
//  - Corpus C: B-spline application input (bisectors of planes) whose zero set passes through
//    the knot planes, which are grid planes at every depth.
//
// Every case states its truth: components and Euler characteristic; a closed manifold has no
// boundary, non-manifold edges, open ends or branch vertices; an open one has its boundary
// (edges of one triangle, or polyline ends) within one cell width of the domain boundary. All
// vertices lie on M (max_residual at working precision).
//
// The hidden test "[.corpus-dump]" writes every case as a problem file with its [expect], and a
// list `cases.txt` of `file depth k closed components euler` lines, into $NDC_CORPUS_DIR
// (default: <temp>/corpus), for runs of the command-line tool on the corpus.
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <string>
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

// --- The generator: a manifold spec becomes problem text -----------------------------------------

/// A manifold of known topology, its equations written in the names y0..y{n-1} (one digit), on
/// the domain [-half, half]^n.
struct Manifold {
  std::string name;                    ///< [a-z0-9.-]+, unique in the corpus
  int n = 0;                           ///< ambient dimension
  std::vector<std::string> equations;  ///< m = n - k polynomials in y0..y{n-1}
  double half = 1;                     ///< the domain is [-half, half]^n
  double reach = 0;                    ///< max |y| over M (closed M); the rotated domain holds it
  long components = 1, euler = 0;
  bool closed = true;  ///< false: M leaves the domain (boundary on the domain boundary only)
  int k() const { return n - static_cast<int>(equations.size()); }
};

/// Shortest decimal text that reads back as the same double.
std::string number(double v) {
  char buffer[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
    if (std::strtod(buffer, nullptr) == v) break;
  }
  return buffer;
}

/// `equation` with every name y<i> replaced by coordinate[i].
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

/// The problem file of a manifold, y_i replaced by coordinate[i] (a text in x0..x{n-1}), on
/// [-half, half]^n, with the truth as [expect].
std::string problemText(const Manifold& m, const std::string& name,
                        const std::vector<std::string>& coordinate, double half,
                        const std::string& description) {
  std::string text = "name = \"" + name + "\"\ndescription = \"" + description + "\"\n";
  text += "variables = [";
  for (int j = 0; j < m.n; ++j) text += (j ? ", \"x" : "\"x") + std::to_string(j) + "\"";
  text += "]\ndomain = [";
  const std::string range = "[" + number(-half) + ", " + number(half) + "]";
  for (int j = 0; j < m.n; ++j) text += (j ? ", " : "") + range;
  text += "]\nequations = [\n";
  for (const std::string& e : m.equations) text += "  \"" + substitute(e, coordinate) + "\",\n";
  text += "]\n\n[expect]\ncomponents = " + std::to_string(m.components) +
          "\neuler_characteristic = " + std::to_string(m.euler) + "\n";
  if (m.closed && m.k() == 1) text += "open_ends = 0\nbranch_vertices = 0\n";
  if (m.closed && m.k() == 2) text += "boundary_edges = 0\nnonmanifold_edges = 0\n";
  if (!m.closed && m.k() == 1) text += "branch_vertices = 0\n";
  if (!m.closed && m.k() == 2) text += "nonmanifold_edges = 0\n";
  return text;
}

/// The manifold as written, y_i = x_i (corpus A).
std::string axisAligned(const Manifold& m) {
  std::vector<std::string> x;
  for (int j = 0; j < m.n; ++j) x.push_back(std::string(1, 'x').append(std::to_string(j)));
  std::string eqs;
  for (const std::string& e : m.equations) eqs += (eqs.empty() ? "" : ", ") + e;
  return problemText(m, m.name, x, m.half, "Grid-degenerate corpus A: " + eqs);
}

/// A random orthogonal n x n matrix from a seeded std::mt19937: the orthogonal factor of a
/// Gaussian matrix (Box-Muller on our own uniforms rather than the implementation-defined
/// std::normal_distribution, so every standard library draws the same), columns signed by
/// diag(R).
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

/// The manifold rotated: y = Q x, i.e. M becomes Q^T M (corpus B), on a domain that holds the
/// ball of radius `reach` (closed M) with a margin.
std::pair<std::string, std::string> rotated(const Manifold& m, std::uint32_t seed) {
  const Eigen::MatrixXd q = randomRotation(m.n, seed);
  std::vector<std::string> y;
  for (int i = 0; i < m.n; ++i) {
    std::string form = "(";
    for (int j = 0; j < m.n; ++j) {
      const double a = q(i, j);
      form += (j == 0 ? (a < 0 ? "-" : "") : (a < 0 ? " - " : " + ")) + number(std::abs(a)) + "*x" +
              std::to_string(j);
    }
    y.push_back(form + ")");
  }
  const std::string name = m.name + "-rot" + std::to_string(seed);
  const double half = m.closed ? std::max(m.half, std::ceil(m.reach * 1.15 * 4) / 4) : m.half;
  const std::string description = "Grid-degenerate corpus B: " + m.name +
                                  " rotated by a random orthogonal Q (std::mt19937 seed " +
                                  std::to_string(seed) + ")";
  return {name, problemText(m, name, y, half, description)};
}

// --- The families --------------------------------------------------------------------------------

/// The name y<i> (appended, not `"y" + ...`, which GCC 12 warns about falsely).
std::string y(int i) { return std::string(1, 'y').append(std::to_string(i)); }

/// The circle (y0 - c)^2 + y1^2 = r^2 in the plane y2 = ... = 0 (`plane[i]` instead of 0 when
/// given: the hyperplane y_{i+2} = plane[i]).
Manifold circle(int n, const std::string& r, double radius, const std::string& centre = "",
                const std::vector<std::string>& plane = {}) {
  Manifold m;
  m.n = n;
  m.name = "circle-n" + std::to_string(n) + "-r" + r + (centre.empty() ? "" : "-c" + centre);
  m.equations.push_back((centre.empty() ? "y0^2" : "(y0 - " + centre + ")^2") + " + y1^2 - " + r +
                        "^2");
  for (int i = 2; i < n; ++i) {
    const std::size_t p = static_cast<std::size_t>(i - 2);
    m.equations.push_back(p < plane.size() ? y(i) + " - " + plane[p] : y(i));
    if (p < plane.size()) m.name += "-p" + plane[p];
  }
  m.reach = radius + (centre.empty() ? 0 : std::abs(std::stod(centre)));
  return m;
}

/// The circle y0^2 + y1^2 = 0.25 lifted into R^n by graph equations with round coefficients.
Manifold liftedCircle(int n) {
  static const std::vector<std::string> kLifts = {"y2 - y0*y1", "y3 - 0.5*y0", "y4 - y2 - y1",
                                                  "y5 - y0^2", "y6 + 0.5*y3 - y1"};
  Manifold m;
  m.n = n;
  m.name = "lifted-circle-n" + std::to_string(n);
  m.equations = {"y0^2 + y1^2 - 0.25"};
  for (int i = 0; i < n - 2; ++i) m.equations.push_back(kLifts[i]);
  m.reach = 1.1;  // |y|^2 <= 0.25 + 1/64 + 1/16 + 0.39 + 1/16 + 0.39
  return m;
}

/// The segment y1 = 0.5 y0 (and y2 = y0, y3 = -0.25 y0 ...) through the origin and grid vertices.
Manifold segment(int n) {
  static const std::vector<std::string> kLines = {"y1 - 0.5*y0", "y2 - y0", "y3 + 0.25*y0"};
  Manifold m;
  m.n = n;
  m.name = "segment-n" + std::to_string(n);
  for (int i = 0; i < n - 1; ++i) m.equations.push_back(kLines[i]);
  m.closed = false;
  m.euler = 1;
  return m;
}

/// The 2-sphere (y0 - c0)^2 + y1^2 + (y2 - c2)^2 = r^2, in R^n by `rest` (equations in y3..);
/// `radius` is its reach, max |y| over M.
Manifold sphere(int n, const std::string& r, double radius, const std::vector<std::string>& rest,
                const std::string& tag = "", const std::string& c0 = "",
                const std::string& c2 = "") {
  Manifold m;
  m.n = n;
  m.name = "sphere-n" + std::to_string(n) + "-r" + r + tag;
  const auto shifted = [](const std::string& v, const std::string& c) {
    if (c.empty()) return v + "^2";
    return "(" + v + (c[0] == '-' ? " + " + c.substr(1) : " - " + c) + ")^2";
  };
  m.equations = {shifted("y0", c0) + " + y1^2 + " + shifted("y2", c2) + " - " + r + "^2"};
  m.equations.insert(m.equations.end(), rest.begin(), rest.end());
  m.reach = radius;
  m.euler = 2;
  return m;
}

/// The ring torus (|y|^2 + R^2 - r^2)^2 = 4 R^2 (y0^2 + y1^2) in R^3 (and `lift` in R^4).
Manifold ringTorus(const std::string& bigR, const std::string& r, double reach,
                   const std::vector<std::string>& lift = {}, const std::string& tag = "") {
  Manifold m;
  m.n = 3 + static_cast<int>(lift.size());
  m.name = "torus-n" + std::to_string(m.n) + "-" + bigR + "-" + r + tag;
  m.equations = {"(y0^2 + y1^2 + y2^2 + " + bigR + "^2 - " + r + "^2)^2 - 4*" + bigR +
                 "^2*(y0^2 + y1^2)"};
  m.equations.insert(m.equations.end(), lift.begin(), lift.end());
  m.reach = reach;
  return m;
}

/// The Clifford-type torus y0^2 + y1^2 = a, y2^2 + y3^2 = b in R^4.
Manifold clifford(const std::string& a, const std::string& b, double reach) {
  Manifold m;
  m.n = 4;
  m.name = "clifford-n4-" + a + "-" + b;
  m.equations = {"y0^2 + y1^2 - " + a, "y2^2 + y3^2 - " + b};
  m.reach = reach;
  return m;
}

/// The flat torus y0^2 + y1^2 = 0.25, y2^2 + y3^2 = 0.25 in R^6 with two affine graph equations.
Manifold flatTorus6() {
  Manifold m;
  m.n = 6;
  m.name = "flat-torus-n6";
  m.equations = {"y0^2 + y1^2 - 0.25", "y2^2 + y3^2 - 0.25", "y4 - y0 - 0.5*y2",
                 "y5 - 0.5*y1 + y3"};
  m.reach = 1.3;  // |y|^2 <= 0.5 + 0.5625 + 0.5625
  return m;
}

/// An affine 2-plane through the origin (n = 3: a hypersurface): a convex polygon in the domain.
Manifold plane(int n) {
  static const std::vector<std::string> kRows = {"y2 - y0 + y1", "y3 - 0.5*y0 - y1",
                                                 "y4 - y1 + 0.25*y0"};
  Manifold m;
  m.n = n;
  m.name = "plane-n" + std::to_string(n);
  for (int i = 0; i < n - 2; ++i) m.equations.push_back(kRows[i]);
  m.closed = false;
  m.euler = 1;
  return m;
}

/// The saddle y2 = y0 y1 over the domain (and y3 = 0.5 y0 - 0.25 y1 in R^4): contains the grid
/// lines y0 = y2 = 0 and y1 = y2 = 0.
Manifold saddle(int n) {
  Manifold m;
  m.n = n;
  m.name = "saddle-n" + std::to_string(n);
  m.equations = {"y2 - y0*y1"};
  if (n >= 4) m.equations.push_back("y3 - 0.5*y0 + 0.25*y1");
  m.closed = false;
  m.euler = 1;
  return m;
}

// --- The corpora ---------------------------------------------------------------------------------

/// One problem of a corpus and how it is run.
struct Case {
  Manifold manifold;
  std::string name, text;
  std::vector<int> depths;       ///< double runs
  std::optional<int> mpfrDepth;  ///< an MPFR (128 bits) run
  bool slow = false;             ///< "[slow]": the double runs (MPFR runs of slow cases too)
  bool known = false;            ///< a known failure of the current code ("[!mayfail]")
};

/// Cases the crossing connection gets wrong, kept with their true expectations: their runs are
/// the "[!mayfail]" tests below, so that they pass once it is fixed. Before the level
/// perturbation (a3e7a58) 45 of the 101 double runs were wrong. The last one, the rotated ring
/// torus torus-n3-0.5-0.25-rot9 (2 non-manifold edges at depths 4 and 5 on the uniform grid:
/// two sheets in a cell near the inner equator), is right since the certificate's refinement
/// became the default.
const std::vector<std::string> kKnownFailures = {};

bool isKnownFailure(const std::string& name) {
  return std::find(kKnownFailures.begin(), kKnownFailures.end(), name) != kKnownFailures.end();
}

/// Closed manifolds whose runs at these depths (double, and MPFR where it runs that depth) are
/// right but not certified at default settings (docs/certificate.md, "Status"); every other
/// closed run must be certified. (The ring tori with their top circle in a grid plane are
/// certified since the curve blocks.)
/// - Tangency along a curve that also meets grid lines or vertices: the torus graph in R^4
///   and the flat torus in R^6 touch grid planes along circles through grid vertices.
/// - The refinement budget: the sphere in R^6 at depth 3 (12 leaves at the maximum level fail
///   the face graph test) and the rotated curve in R^7 at depth 4 (graph tests that need two
///   more levels on every cell: 2^7 children each, about 4e5 leaves, over the budget). The
///   rotated curve in R^5 and the rotated torus graph in R^4 are certified since the budget
///   counts solution leaves apart from the children the bounding excludes.
/// - In MPFR only, the ring torus at depth 4: its bottom circle touches the grid line
///   x = -0.5, y = 0 in the plane z = -0.25, where F vanishes to fourth order along the grid
///   edge; the curve blocks next to it do not stand (in double they do, the leaves come in
///   another order).
const std::vector<std::pair<std::string, int>> kUncertifiedMpfr = {{"torus-n3-0.5-0.25", 4}};
const std::vector<std::pair<std::string, int>> kUncertified = {
    {"torus-n4-0.5-0.25-graph", 4}, {"torus-n4-0.5-0.25-graph", 5}, {"flat-torus-n6", 3},
    {"flat-torus-n6", 4},           {"sphere-n6-r0.5-lift", 3},     {"lifted-circle-n7-rot6", 4}};

bool listed(const std::vector<std::pair<std::string, int>>& list, const std::string& name,
            int depth) {
  return std::find(list.begin(), list.end(), std::pair{name, depth}) != list.end();
}

template <class S>
bool knownUncertified(const std::string& name, int depth) {
  return listed(kUncertified, name, depth) ||
         (!std::is_same_v<S, double> && listed(kUncertifiedMpfr, name, depth));
}

Case caseA(Manifold m, std::vector<int> depths, std::optional<int> mpfr = {}, bool slow = false) {
  Case c;
  c.name = m.name;
  c.text = axisAligned(m);
  c.manifold = std::move(m);
  c.depths = std::move(depths);
  c.mpfrDepth = mpfr;
  c.slow = slow;
  c.known = isKnownFailure(c.name);
  return c;
}

Case caseB(const Manifold& m, std::uint32_t seed, std::vector<int> depths, bool slow = false) {
  Case c;
  c.manifold = m;
  std::tie(c.name, c.text) = rotated(m, seed);
  c.depths = std::move(depths);
  c.slow = slow;
  c.known = isKnownFailure(c.name);
  return c;
}

/// Corpus A: axis-aligned, through grid vertices, edges and faces.
std::vector<Case> corpusA() {
  const std::vector<std::string> affine4 = {"y3 - y0 - y1"};
  const std::vector<std::string> affine5 = {"y3 - y0 - y1", "y4 - 0.5*y2 + y0"};
  std::vector<Case> cases = {
      // Curves in R^2: through grid vertices (0.5, 0), (0, 0.75), on the grid lines x = 0, y = 0.
      caseA(circle(2, "0.5", 0.5), {5, 6}, 5),
      caseA(circle(2, "0.75", 0.75), {5, 6}, 5),
      caseA(circle(2, "0.3", 0.3, "0.1"), {5, 6}, 5),
      // In R^3..R^7: the circle lies in the grid planes x2 = ... = 0, or x2 = 0.25 (a grid plane
      // from depth 3 on; 0.3 is not one).
      caseA(circle(3, "0.5", 0.5), {4, 5}, 4),
      caseA(circle(3, "0.5", 0.5, "", {"0.25"}), {3, 4}),
      caseA(circle(3, "0.5", 0.5, "", {"0.3"}), {3, 4}),
      caseA(circle(3, "0.75", 0.75, "", {"0.25"}), {4, 5}),
      caseA(circle(4, "0.5", 0.5, "", {"0.25", "0"}), {4, 5}, 4),
      caseA(circle(5, "0.5", 0.5), {4, 5}),
      caseA(circle(6, "0.5", 0.5), {4, 5}),
      caseA(circle(7, "0.5", 0.5), {4, 5}),
      caseA(circle(7, "0.75", 0.75, "0.125"), {4, 5}),
      caseA(liftedCircle(4), {4, 5}, 4),
      caseA(liftedCircle(5), {4, 5}),
      caseA(liftedCircle(6), {4, 5}),
      caseA(liftedCircle(7), {4, 5}),
      // Open curves through the origin, ending on domain edges and vertices.
      caseA(segment(2), {5, 6}, 5),
      caseA(segment(3), {4, 5}),
      caseA(segment(4), {4, 5}),
      // Spheres through grid vertices (r = 0.5, 0.75), with a decimal centre, cut by coordinate
      // hyperplanes (in grid planes) or by affine ones with round coefficients.
      caseA(sphere(3, "0.5", 0.5, {}), {4, 5}, 4),
      caseA(sphere(3, "0.75", 0.75, {}), {4, 5}),
      caseA(sphere(3, "0.6", 0.83, {}, "-c", "0.1", "-0.2"), {4, 5}),
      caseA(sphere(4, "0.5", 0.5, {"y3"}), {4, 5}, 4),
      caseA(sphere(4, "0.5", 0.87, affine4, "-affine"), {4, 5}),
      caseA(sphere(5, "0.5", 0.5, {"y3", "y4"}), {4}),
      caseA(sphere(5, "0.5", 1.03, affine5, "-affine"), {4}),
      // Tori: the ring torus through grid vertices (x = 0.25, 0.75 on the axes), its equator
      // in the grid plane z = 0; the Clifford torus; a graph over the ring torus in R^4.
      caseA(ringTorus("0.5", "0.25", 0.75), {4, 5}, 4),
      caseA(ringTorus("0.625", "0.25", 0.875), {4, 5}),
      caseA(ringTorus("0.5", "0.25", 0.9, {"y3 - y0*y2"}, "-graph"), {4, 5}),
      caseA(clifford("0.5", "0.5", 1.0), {4, 5}),
      caseA(clifford("0.25", "0.25", 0.71), {4, 5}),
      // Open surfaces: planes and saddles through the origin and grid lines.
      caseA(plane(3), {4, 5}, 4),
      caseA(plane(4), {4, 5}),
      caseA(saddle(3), {4, 5}, 4),
      caseA(saddle(4), {4, 5}),
      // Expensive: surfaces in R^5..R^7, the second depth of R^5 spheres, MPFR of R^4 tori.
      caseA(sphere(5, "0.5", 0.5, {"y3", "y4"}), {5}, {}, true),
      caseA(sphere(5, "0.5", 1.03, affine5, "-affine"), {5}, {}, true),
      caseA(plane(5), {4}, {}, true),
      caseA(flatTorus6(), {3, 4}, {}, true),
      caseA(sphere(6, "0.5", 0.88, {"y3", "y4 - y0 - y1", "y5 - y0*y2"}, "-lift"), {3, 4}, {},
            true),
      caseA(sphere(7, "0.5", 0.57, {"y3", "y4", "y5 - 0.5*y1", "y6 - y0*y2"}, "-lift"), {3}, {},
            true),
      caseA(clifford("0.5", "0.5", 1.0), {}, 4, true),
      caseA(ringTorus("0.5", "0.25", 0.9, {"y3 - y0*y2"}, "-graph"), {}, 4, true),
  };
  return cases;
}

/// Corpus B: corpus A manifolds under seeded random rotations.
std::vector<Case> corpusB() {
  return {
      caseB(circle(2, "0.75", 0.75), 1, {5, 6}),
      caseB(circle(3, "0.5", 0.5), 2, {4, 5}),
      caseB(circle(5, "0.5", 0.5), 3, {4, 5}),
      caseB(circle(7, "0.5", 0.5), 4, {4}),
      caseB(liftedCircle(5), 5, {4, 5}),
      caseB(liftedCircle(7), 6, {4}),
      caseB(sphere(3, "0.5", 0.5, {}), 7, {4, 5}),
      caseB(sphere(4, "0.5", 0.87, {"y3 - y0 - y1"}, "-affine"), 8, {4}),
      caseB(ringTorus("0.5", "0.25", 0.75), 9, {4, 5}),
      caseB(clifford("0.25", "0.25", 0.71), 10, {4}),
      caseB(plane(4), 11, {4}),
      caseB(ringTorus("0.5", "0.25", 0.9, {"y3 - y0*y2"}, "-graph"), 12, {4}),
      // Expensive.
      caseB(sphere(5, "0.5", 0.5, {"y3", "y4"}), 13, {4}, true),
      caseB(clifford("0.5", "0.5", 1.0), 14, {4}, true),
      caseB(ringTorus("0.5", "0.25", 0.75), 15, {6}, true),
  };
}

// --- Corpus C: B-spline input, knots on grid planes ----------------------------------------------

/// The bisector of the plane z = 0 (S1, a biquadratic B-spline whose knots lie on grid planes of
/// the span coordinates) and the plane z = 1 (S2, a bilinear Bezier patch on [0, width2] x
/// [0, 2]): the points
/// (u, v, s, t) with S1(u, v) and S2(s, t) over each other, an affine (or, where S1's knot
/// spacing changes, piecewise affine) 2-plane through the grid vertices, meeting the knot planes
/// u = 1, v = 1 in lines that lie in two grid planes at once.
std::string bisectorOfPlanes(const std::string& name, const std::string& knotsU,
                             const std::vector<double>& grevilleU, double width2) {
  // Control points at the Greville abscissae: S1(u, v) = (u, v, 0) in knot parameters.
  const std::vector<double> grevilleV = {0, 0.5, 1.5, 2};
  std::string points = "points = [\n";
  for (std::size_t j = 0; j < grevilleV.size(); ++j) {
    points += "  [";
    for (std::size_t i = 0; i < grevilleU.size(); ++i)
      points += (i ? ", [" : "[") + number(grevilleU[i]) + ", " + number(grevilleV[j]) + ", 0]";
    points += j + 1 < grevilleV.size() ? "],\n" : "]]\n";
  }
  const std::string w = number(width2);
  return "name = \"" + name + "\"\napplication = \"bisector\"\n" +
         "description = \"Grid-degenerate corpus C: the bisector of two parallel planes, S1 a "
         "B-spline with knots on grid planes.\"\n\n[[surfaces]]\nname = \"S1\"\n"
         "degree = [2, 2]\n" +
         points + "knots_u = " + knotsU + "\nknots_v = [0, 0, 0, 1, 2, 2, 2]\n\n" +
         "[[surfaces]]\nname = \"S2\"\ndegree = [1, 1]\n" + "points = [[[0, 0, 1], [" + w +
         ", 0, 1]], [[0, 2, 1], [" + w + ", 2, 1]]]\nbox = [[0, " + w +
         "], [0, 2]]\n\n[expect]\ncomponents = 1\neuler_characteristic = 1\n" +
         "nonmanifold_edges = 0\n";
}

std::vector<Case> corpusC() {
  Manifold disk;
  disk.n = 4;
  disk.equations = {"", ""};
  disk.closed = false;
  disk.euler = 1;
  const auto make = [&](const std::string& name, std::string text, std::vector<int> depths) {
    Case c;
    c.manifold = disk;
    c.manifold.name = c.name = name;
    c.text = std::move(text);
    c.mpfrDepth = depths.front();
    c.depths = std::move(depths);
    c.known = isKnownFailure(name);
    return c;
  };
  return {
      // Uniform knots 0 1 2: S1(u, v) = (u, v, 0) in span coordinates, M = {s = u, t = v}.
      make(
          "bisector-planes-uniform",
          bisectorOfPlanes("bisector-planes-uniform", "[0, 0, 0, 1, 2, 2, 2]", {0, 0.5, 1.5, 2}, 2),
          {3, 4}),
      // Knots 0 1 4 along u: in span coordinates S1 is piecewise linear in u, so M = {s = x(u),
      // t = v} bends along the knot plane u = 1.
      make("bisector-planes-kink",
           bisectorOfPlanes("bisector-planes-kink", "[0, 0, 0, 1, 4, 4, 4]", {0, 0.5, 2.5, 4}, 4),
           {3, 4}),
  };
}

// --- Running and checking ------------------------------------------------------------------------

template <class S>
RunResult solve(const Problem& problem, int depth) {
  ndc::test::PrecisionScope<S> scope(128);
  Settings settings;  // defaults: bounding, subdivision, projection, crossing connection
  settings.depth = depth;
  if constexpr (!std::is_same_v<S, double>) {
    settings.scalar = "mpfr";
    settings.precisionBits = 128;
  }
  return ndc::runPipeline(problem, settings);
}

template <class S>
double residualBound() {
  return std::is_same_v<S, double> ? 1e-9 : 1e-25;
}

std::string describe(const RunResult& r) {
  const auto& s = r.summary;
  const auto& m = s.mesh;
  std::ostringstream out;
  out << s.problem << " n " << s.n << " k " << s.k << " depth " << s.settings.depth << " "
      << s.settings.scalar << ": V " << m.vertices << " E " << m.edges << " T " << m.triangles
      << " components " << m.components << " chi " << m.eulerCharacteristic << " boundary "
      << m.boundaryEdges << " nonmanifold " << m.nonmanifoldEdges << " open " << m.openEnds
      << " branch " << m.branchVertices << " residual " << m.maxResidual << " ambiguous "
      << s.ambiguousCells << " singular " << s.singularCells << " off-manifold "
      << s.offManifoldVertices << " perturbation attempts " << s.perturbation.attempts
      << " degenerate " << s.perturbation.degenerateCrossings;
  return out.str();
}

/// The boundary of the mesh: for k = 2 the edges of one triangle, for k = 1 the vertices of
/// degree 1 (as edges v-v).
std::vector<std::pair<std::int32_t, std::int32_t>> boundaryOf(const RunResult& r) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> count;
  std::vector<std::pair<std::int32_t, std::int32_t>> boundary;
  if (r.k == 2) {
    for (std::size_t t = 0; t + 2 < r.simplices.size(); t += 3)
      for (int i = 0; i < 3; ++i) {
        std::int32_t a = r.simplices[t + i], b = r.simplices[t + (i + 1) % 3];
        ++count[{std::min(a, b), std::max(a, b)}];
      }
  } else {
    for (std::int32_t v : r.simplices) ++count[{v, v}];
  }
  for (const auto& [edge, c] : count)
    if (c == 1) boundary.push_back(edge);
  return boundary;
}

/// The checks of one run against the truth of its manifold.
template <class S>
void check(const Case& c, const Problem& problem, const RunResult& r) {
  const Manifold& t = c.manifold;
  const auto& m = r.summary.mesh;
  INFO(describe(r));
  REQUIRE(r.k == t.k());
  CHECK(m.vertices > 0);
  CHECK(m.components == t.components);
  CHECK(m.eulerCharacteristic == t.euler);
  CHECK(m.maxResidual <= residualBound<S>());
  if (r.k == 1) {
    CHECK(m.branchVertices == 0);
    if (t.closed) CHECK(m.openEnds == 0);
  } else {
    CHECK(m.nonmanifoldEdges == 0);
    if (t.closed) CHECK(m.boundaryEdges == 0);
  }
  // Deliverable of the certificate: every closed manifold of the corpus certified at default
  // settings, but the runs listed with their cause.
  if (t.closed && !knownUncertified<S>(c.name, r.summary.settings.depth))
    CHECK(r.summary.topology.certified);
  if (t.closed) return;

  // Open M: its boundary lies on the domain boundary, so every boundary vertex is within one
  // cell width of it, or two where the certificate merged cells into blocks of 2 x ... x 2
  // cells (one vertex per block: docs/certificate.md, "Blocks"). A boundary cell's vertex may
  // sit on the cell's inner face, and the crossings there are those of the perturbed level set
  // F = c (|c| about 1e-9 of the scale of F), so allow 1e-6 of a width beyond the face.
  const int n = r.n;
  const double cells = r.summary.topology.blockCells > 0 ? 2 : 1;
  std::vector<double> width(n);
  for (int j = 0; j < n; ++j)
    width[j] = cells * (problem.domain.hi[j] - problem.domain.lo[j]) /
               double(1 << r.summary.settings.depth) * (1 + 1e-6);
  const auto nearBoundary = [&](std::int32_t v) {
    for (int j = 0; j < n; ++j) {
      const double x = r.vertices[std::size_t(v) * n + j];
      if (x - problem.domain.lo[j] <= width[j] || problem.domain.hi[j] - x <= width[j]) return true;
    }
    return false;
  };
  long far = 0;
  const auto boundary = boundaryOf(r);
  for (const auto& [a, b] : boundary) far += !nearBoundary(a) || !nearBoundary(b);
  CHECK(!boundary.empty());
  CHECK(long(boundary.size()) == (r.k == 2 ? m.boundaryEdges : m.openEnds));
  CHECK(far == 0);
}

/// Runs the cases of a corpus selected by `slow` and `known`, in scalar S: double at every depth
/// of the case, MPFR at its MPFR depth.
template <class S>
void runCorpus(const std::vector<Case>& cases, bool slow, bool known) {
  for (const Case& c : cases) {
    if (c.slow != slow || c.known != known) continue;
    std::vector<int> depths = c.depths;
    if (!std::is_same_v<S, double>)
      depths = c.mpfrDepth ? std::vector<int>{*c.mpfrDepth} : std::vector<int>{};
    for (int depth : depths) {
      DYNAMIC_SECTION(c.name << " depth " << depth) {
        const Problem problem = ndc::parseProblem(c.text, c.name + ".toml");
        CAPTURE(c.text);
        check<S>(c, problem, solve<S>(problem, depth));
      }
    }
  }
}

}  // namespace

// --- Corpus A: axis-aligned ----------------------------------------------------------------------

TEMPLATE_TEST_CASE("degenerate: corpus A, manifolds through grid vertices, edges and faces",
                   "[degenerate]", NDC_SCALARS) {
  runCorpus<TestType>(corpusA(), false, false);
}

TEMPLATE_TEST_CASE("degenerate: corpus A, surfaces in R^5..R^7 and deeper grids",
                   "[degenerate][slow]", NDC_SCALARS) {
  runCorpus<TestType>(corpusA(), true, false);
}

// --- Corpus B: rotated ---------------------------------------------------------------------------

TEST_CASE("degenerate: corpus B, seeded random rotations", "[degenerate]") {
  runCorpus<double>(corpusB(), false, false);
}

TEST_CASE("degenerate: corpus B, seeded random rotations, expensive", "[degenerate][slow]") {
  runCorpus<double>(corpusB(), true, false);
}

// --- Corpus C: B-spline input --------------------------------------------------------------------

TEMPLATE_TEST_CASE("degenerate: corpus C, B-spline bisectors through knot planes", "[degenerate]",
                   NDC_SCALARS) {
  runCorpus<TestType>(corpusC(), false, false);
}

// --- Known failures (kKnownFailures), with their true expectations -------------------------------

TEMPLATE_TEST_CASE("degenerate: known failures", "[degenerate][!mayfail]", NDC_SCALARS) {
  for (const auto& corpus : {corpusA(), corpusB(), corpusC()})
    runCorpus<TestType>(corpus, false, true);
}

TEMPLATE_TEST_CASE("degenerate: known failures, expensive", "[degenerate][slow][!mayfail]",
                   NDC_SCALARS) {
  for (const auto& corpus : {corpusA(), corpusB(), corpusC()})
    runCorpus<TestType>(corpus, true, true);
}

// --- The corpus itself --------------------------------------------------------------------------

TEST_CASE("degenerate: the corpus is well formed", "[degenerate]") {
  std::map<std::string, std::string> texts;
  long runs = 0, known = 0;
  for (const auto& corpus : {corpusA(), corpusB(), corpusC()}) {
    for (const Case& c : corpus) {
      INFO(c.name);
      // A name may repeat only for the same problem (run at other depths or scalars).
      const auto [it, fresh] = texts.emplace(c.name, c.text);
      CHECK((fresh || it->second == c.text));
      const Problem problem = ndc::parseProblem(c.text, c.name + ".toml");
      CHECK(problem.name == c.name);
      CHECK(problem.k() == c.manifold.k());
      CHECK(problem.expect.components == c.manifold.components);
      CHECK(problem.expect.eulerCharacteristic == c.manifold.euler);
      CHECK(!(c.depths.empty() && !c.mpfrDepth));
      runs += static_cast<long>(c.depths.size()) + (c.mpfrDepth ? 1 : 0);
      known += c.known;
    }
  }
  // Every known failure names a case of the corpus.
  for (const std::string& name : kKnownFailures) CHECK(texts.count(name) == 1);
  CHECK(texts.size() >= 50);
  CHECK(runs >= 100);
}

TEST_CASE("degenerate: write the corpus as problem files", "[.corpus-dump]") {
  const char* env = std::getenv("NDC_CORPUS_DIR");
  const fs::path dir = env && *env ? fs::path(env) : fs::temp_directory_path() / "corpus";
  fs::create_directories(dir);
  std::ofstream list(dir / "cases.txt");
  long runs = 0;
  for (const auto& corpus : {corpusA(), corpusB(), corpusC()}) {
    for (const Case& c : corpus) {
      std::ofstream(dir / (c.name + ".toml")) << c.text;
      REQUIRE_NOTHROW(ndc::parseProblem(c.text, c.name + ".toml"));
      for (int depth : c.depths) {
        list << c.name << ".toml " << depth << " " << c.manifold.k() << " " << c.manifold.closed
             << " " << c.manifold.components << " " << c.manifold.euler << "\n";
        ++runs;
      }
    }
  }
  CHECK(runs > 0);
}
