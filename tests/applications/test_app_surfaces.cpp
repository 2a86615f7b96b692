// The two-surface applications of the paper's Sec. 3 (convex hull 3.1, bisector 3.3, blending
// 3.5) against geometric ground truth at every mesh vertex, and their bad input (exit 2).
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "applications/freeform.hpp"
#include "applications/load.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

using Vec = std::array<double, 3>;

Vec operator-(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec operator+(const Vec& a, const Vec& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec operator*(double s, const Vec& a) { return {s * a[0], s * a[1], s * a[2]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
/// |<a, b>| / (|a| |b|): the cosine of the angle between a and b (0 when orthogonal).
double cosine(const Vec& a, const Vec& b) { return std::abs(dot(a, b)) / (norm(a) * norm(b)); }

/// A polynomial Bezier surface of degree (du, dv) from its control points, u fastest.
ndc::SurfaceSpec bezier(const std::string& name, int du, int dv, std::vector<Vec> points) {
  ndc::SurfaceSpec s;
  s.name = name;
  s.degreeU = du;
  s.degreeV = dv;
  s.countU = du + 1;
  s.countV = dv + 1;
  s.points = std::move(points);
  return s;
}

/// A bilinear patch: the parallelogram `origin + u a + v b`, (u, v) in [0, 1]^2.
ndc::SurfaceSpec planar(const std::string& name, const Vec& origin, const Vec& a, const Vec& b) {
  return bezier(name, 1, 1, {origin, origin + a, origin + b, origin + a + b});
}

/// A rational quadratic arc of the unit circle from angle lo to hi (< pi): control points
/// (cos, sin) and weights.
void arc(double lo, double hi, double (&p)[3][2], double (&w)[3]) {
  const double half = (hi - lo) / 2, mid = (hi + lo) / 2, c = std::cos(half);
  p[0][0] = std::cos(lo), p[0][1] = std::sin(lo);
  p[1][0] = std::cos(mid) / c, p[1][1] = std::sin(mid) / c;
  p[2][0] = std::cos(hi), p[2][1] = std::sin(hi);
  w[0] = w[2] = 1;
  w[1] = c;
}

/// The exact piece of the sphere (centre, radius) of longitude in `lon` and latitude in `lat`
/// about the pole direction `pole` (+z or -z) as a rational biquadratic surface of revolution:
/// the tensor product of two rational quadratic circular arcs.
ndc::SurfaceSpec spherePatch(const std::string& name, const Vec& centre, double radius,
                             std::array<double, 2> lon, std::array<double, 2> lat, double pole) {
  double a[3][2], b[3][2], wa[3], wb[3];
  arc(lon[0], lon[1], a, wa);
  arc(lat[0], lat[1], b, wb);
  ndc::SurfaceSpec s = bezier(name, 2, 2, {});
  for (int j = 0; j < 3; ++j)      // v: latitude
    for (int i = 0; i < 3; ++i) {  // u: longitude
      // On the unit sphere about the x axis, then rotated so that x goes to the pole.
      const double x = b[j][0] * a[i][0], y = b[j][0] * a[i][1], z = b[j][1];
      s.points.push_back(centre + radius * Vec{y, pole * z, pole * x});
      s.weights.push_back(wa[i] * wb[j]);
    }
  return s;
}

std::string number(double x) {
  std::ostringstream o;
  o.precision(17);
  o << x;
  return o.str();
}

/// The `[[surfaces]]` table of a surface (Bezier, optionally rational, B-spline or boxed).
std::string toml(const ndc::SurfaceSpec& s) {
  std::string t = "[[surfaces]]\nname = \"" + s.name + "\"\ndegree = [" +
                  std::to_string(s.degreeU) + ", " + std::to_string(s.degreeV) + "]\npoints = [";
  std::string w = "weights = [";
  for (int j = 0; j < s.countV; ++j) {
    t += j ? ", [" : "[";
    w += j ? ", [" : "[";
    for (int i = 0; i < s.countU; ++i) {
      const Vec& p = s.points[j * s.countU + i];
      t += (i ? ", [" : "[") + number(p[0]) + ", " + number(p[1]) + ", " + number(p[2]) + "]";
      if (s.rational()) w += (i ? ", " : "") + number(s.weights[j * s.countU + i]);
    }
    t += "]";
    w += "]";
  }
  t += "]\n";
  if (s.rational()) t += w + "]\n";
  const auto list = [](const std::vector<double>& k) {
    std::string l = "[";
    for (std::size_t i = 0; i < k.size(); ++i) l += (i ? ", " : "") + number(k[i]);
    return l + "]";
  };
  if (!s.knotsU.empty()) t += "knots_u = " + list(s.knotsU) + "\n";
  if (!s.knotsV.empty()) t += "knots_v = " + list(s.knotsV) + "\n";
  if (s.box != std::array<double, 4>{0, 1, 0, 1}) {
    t += "box = [[" + number(s.box[0]) + ", " + number(s.box[1]) + "], [" + number(s.box[2]) +
         ", " + number(s.box[3]) + "]]\n";
  }
  return t;
}

/// An application problem file's text.
std::string problemText(const std::string& application, const std::vector<ndc::SurfaceSpec>& s,
                        const std::string& extra = "") {
  std::string t =
      "name = \"test-" + application + "\"\napplication = \"" + application + "\"\n" + extra + "\n";
  for (const auto& spec : s) t += toml(spec) + "\n";
  return t;
}

/// Default settings (no jitter) at a depth, in double or MPFR (128 bits).
ndc::RunResult solve(const ndc::Problem& problem, int depth, const std::string& scalar = "double") {
  ndc::Settings settings;
  settings.depth = depth;
  settings.scalar = scalar;
  settings.precisionBits = scalar == "double" ? 53 : 128;
  return ndc::runPipeline(problem, settings);
}

/// The surface parameters of variables (2 i, 2 i + 1) at a mesh vertex (span coordinates of
/// B-spline directions mapped back to knots).
std::array<double, 2> parameters(const ndc::ApplicationData& app, const double* x, int i) {
  return {app.parameter(2 * i, x[2 * i]), app.parameter(2 * i + 1, x[2 * i + 1])};
}

/// S_u (d = 0) or S_v (d = 1) by central differences of SurfaceSpec::evaluate (error ~1e-10).
Vec partial(const ndc::SurfaceSpec& s, double u, double v, int d) {
  const auto r = s.range(d);
  const double h = 1e-5 * (r[1] - r[0]);
  const Vec a = d == 0 ? s.evaluate(u + h, v) : s.evaluate(u, v + h);
  const Vec b = d == 0 ? s.evaluate(u - h, v) : s.evaluate(u, v - h);
  return (1 / (2 * h)) * (a - b);
}

/// Every mesh vertex as a point of R^n.
std::vector<std::vector<double>> vertices(const ndc::RunResult& r) {
  std::vector<std::vector<double>> out;
  for (std::size_t v = 0; v + r.n <= r.vertices.size(); v += r.n)
    out.emplace_back(r.vertices.begin() + v, r.vertices.begin() + v + r.n);
  return out;
}

}  // namespace

TEST_CASE("bisector of two parallel planar patches is the mid-plane", "[applications]") {
  // S1: z = 0 over [0, 1]^2; S2: z = 1 over a larger, shifted square, so that the solution
  // s = (u + 0.1) / 1.3, t = (v + 0.15) / 1.25 is not a grid diagonal.
  const auto s1 = planar("S1", {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const auto s2 = planar("S2", {-0.1, -0.15, 1}, {1.3, 0, 0}, {0, 1.25, 0});
  const ndc::Problem problem = ndc::parseProblem(problemText("bisector", {s1, s2}), "test.toml");
  REQUIRE(problem.n() == 4);
  REQUIRE(problem.k() == 2);
  REQUIRE(problem.application);
  CHECK(problem.application->singularName == "bisector determinant");
  for (const std::string scalar : {"double", "mpfr"}) {
    INFO("scalar " << scalar);
    // An affine 2-plane of R^4 made of two lines, (u, s) and (v, t), through grid faces: one
    // disk on the natural grid (it came out in pieces before the level perturbation).
    const ndc::RunResult r = solve(problem, scalar == "double" ? 4 : 3, scalar);
    REQUIRE(r.summary.mesh.triangles > 0);
    CHECK(r.summary.mesh.components == 1);
    CHECK(r.summary.mesh.eulerCharacteristic == 1);
    CHECK(r.summary.mesh.nonmanifoldEdges == 0);
    for (const auto& x : vertices(r)) {
      bool singular = true;
      const Vec p = problem.application->image(x, &singular);
      REQUIRE_FALSE(singular);
      // The bisector point is over S1(u, v) = (u, v, 0) at height 1/2, and S2(s, t) is the
      // point of S2 over it.
      CHECK(p[2] == Approx(0.5).margin(1e-9));
      CHECK(p[0] == Approx(x[0]).margin(1e-9));
      CHECK(p[1] == Approx(x[1]).margin(1e-9));
      CHECK(s2.evaluate(x[2], x[3])[0] == Approx(x[0]).margin(1e-9));
      CHECK(s2.evaluate(x[2], x[3])[1] == Approx(x[1]).margin(1e-9));
    }
  }
}

TEST_CASE("bisector of a spherical patch and a planar patch is equidistant",
          "[applications][slow]") {
  // S1: the lower cap of the sphere |x - c| = R (exact, rational); S2: the plane z = 0 with a
  // non-uniform parametrisation (biquadratic, control points unevenly spaced).
  const Vec c{0.5, 0.5, 1.2};
  const double radius = 0.8;
  const auto s1 = spherePatch("S1", c, radius, {-M_PI / 4, M_PI / 4}, {-M_PI / 4, M_PI / 4}, -1);
  auto s2 = bezier("S2", 2, 2, {});
  for (double y : {-0.2, 0.1, 1.2})
    for (double x : {-0.2, 0.3, 1.2}) s2.points.push_back({x, y, 0});
  const ndc::Problem problem = ndc::parseProblem(problemText("bisector", {s1, s2}), "test.toml");
  const ndc::RunResult r = solve(problem, 4);
  REQUIRE(r.summary.mesh.triangles > 0);
  CHECK(r.summary.mesh.nonmanifoldEdges == 0);
  // Newton projection leaves vertices on M to ~1e-12 residual; the checks below allow 1e-7.
  CHECK(r.summary.mesh.maxResidual < 1e-9);
  const ndc::ApplicationData& app = *problem.application;
  for (const auto& x : vertices(r)) {
    bool singular = true;
    const Vec p = app.image(x, &singular);
    REQUIRE_FALSE(singular);
    const Vec a = s1.evaluate(x[0], x[1]), b = s2.evaluate(x[2], x[3]);
    // Equidistant, and P - S_i along the normal of S_i (the normal-line conditions).
    CHECK(norm(p - a) == Approx(norm(p - b)).epsilon(1e-7));
    CHECK(cosine(p - a, partial(s1, x[0], x[1], 0)) < 1e-7);
    CHECK(cosine(p - a, partial(s1, x[0], x[1], 1)) < 1e-7);
    CHECK(cosine(p - b, partial(s2, x[2], x[3], 0)) < 1e-7);
    CHECK(cosine(p - b, partial(s2, x[2], x[3], 1)) < 1e-7);
    // Closed form: the bisector of the sphere and the plane z = 0 is z = |P - c| - R (P
    // outside the sphere) or z = |P - c| + R (the untrimmed branch beyond the centre).
    CHECK(std::min(std::abs(p[2] - (norm(p - c) - radius)),
                   std::abs(p[2] - (norm(p - c) + radius))) < 1e-8);
  }
}

TEST_CASE("bitangent planes of two disjoint convex patches touch both", "[applications]") {
  // Two caps of spheres of radii r1 != r2, facing +z: a plane with unit normal n touches both
  // (on the same side) where <c2 - c1, n> = r1 - r2, at S1 = c1 + r1 n and S2 = c2 + r2 n. The
  // latitude range of S2 is not symmetric: otherwise v = t = 1/2 at the same point of the curve
  // (a grid-degenerate input for the crossing connection).
  const Vec c1{0, 0, 0}, c2{2, 0, 0.1};
  const double r1 = 0.6, r2 = 0.8;
  const auto s1 = spherePatch("S1", c1, r1, {-M_PI / 4, M_PI / 4}, {-M_PI / 4, M_PI / 4}, 1);
  const auto s2 = spherePatch("S2", c2, r2, {-0.9, 0.9}, {-0.8, 1.0}, 1);
  const ndc::Problem problem = ndc::parseProblem(problemText("convex-hull", {s1, s2}), "test.toml");
  REQUIRE(problem.k() == 1);
  REQUIRE(problem.application->secondImage);
  const ndc::RunResult r = solve(problem, 5);
  REQUIRE(r.summary.mesh.edges > 10);
  // One contact curve, ending on the boundary of S1.
  CHECK(r.summary.mesh.components == 1);
  CHECK(r.summary.mesh.branchVertices == 0);
  CHECK(r.summary.mesh.maxResidual < 1e-9);
  const ndc::ApplicationData& app = *problem.application;
  for (const auto& x : vertices(r)) {
    const Vec a = s1.evaluate(x[0], x[1]), b = s2.evaluate(x[2], x[3]);
    CHECK(norm(app.image(x) - a) < 1e-9);
    CHECK(norm((*app.secondImage)(x)-b) < 1e-9);
    // The 3-D tangency conditions: the tangent plane of S1 at (u, v) holds S2(s, t) (1) and
    // is tangent to S2 there (2), (3).
    const Vec n1 = cross(partial(s1, x[0], x[1], 0), partial(s1, x[0], x[1], 1));
    CHECK(cosine(b - a, n1) < 1e-7);
    CHECK(cosine(partial(s2, x[2], x[3], 0), n1) < 1e-7);
    CHECK(cosine(partial(s2, x[2], x[3], 1), n1) < 1e-7);
    // Closed form: the common unit normal n = (S1 - c1) / r1 = (S2 - c2) / r2.
    const Vec n = (1 / r1) * (a - c1);
    CHECK(norm(b - (c2 + r2 * n)) < 1e-7);
    CHECK(dot(c2 - c1, n) == Approx(r1 - r2).margin(1e-7));
  }
}

namespace {

/// The blend of S1: z = 0 and S2: x = 0 with constant normals N1 = (0, 0, 1), N2 = (1, 0, 0)
/// (c = 1) lies on the cylinder (x - 1)^2 + (z - 1)^2 = 1, with y in S1's range [0, 0.4].
/// The mesh is also checked to be the annulus (circle (8) times S1's v range).
void checkPerpendicularBlend(const ndc::SurfaceSpec& s1, const ndc::SurfaceSpec& s2) {
  const ndc::Problem problem = ndc::parseProblem(
      problemText("blending", {s1, s2}, "alpha = [[-0.5, 2.5], [-0.5, 2.5]]\n"), "test.toml");
  REQUIRE(problem.n() == 6);
  REQUIRE(problem.k() == 2);
  // The solution is linear in every variable but a1, a2 and lies on grid planes (v = 0, 1):
  // grid-degenerate, on the natural grid (for B-spline input the knots stay on grid planes).
  const ndc::RunResult r = solve(problem, 4, "double");
  INFO("components " << r.summary.mesh.components << " chi " << r.summary.mesh.eulerCharacteristic
                     << " nonmanifold " << r.summary.mesh.nonmanifoldEdges);
  REQUIRE(r.summary.mesh.triangles > 0);
  CHECK(r.summary.mesh.components == 1);
  CHECK(r.summary.mesh.eulerCharacteristic == 0);
  CHECK(r.summary.mesh.nonmanifoldEdges == 0);
  CHECK(r.summary.mesh.maxResidual < 1e-9);
  const ndc::ApplicationData& app = *problem.application;
  for (const auto& x : vertices(r)) {
    const Vec p = app.image(x);
    CHECK((p[0] - 1) * (p[0] - 1) + (p[2] - 1) * (p[2] - 1) == Approx(1).margin(1e-9));
    CHECK(p[1] >= -1e-9);
    CHECK(p[1] <= 0.4 + 1e-9);
    // The image is S1 + a1 N1 = S2 + a2 N2 with the constant normals.
    const auto uv = parameters(app, x.data(), 0), st = parameters(app, x.data(), 1);
    const Vec a = s1.evaluate(uv[0], uv[1]), b = s2.evaluate(st[0], st[1]);
    CHECK(norm(p - (a + x[4] * Vec{0, 0, 1})) < 1e-9);
    CHECK(norm(p - (b + x[5] * Vec{1, 0, 0})) < 1e-9);
  }
}

}  // namespace

TEST_CASE("rolling-ball blend of two perpendicular planes lies on its cylinder", "[applications]") {
  // S1 = (-0.25 + 2.5 u, 0.4 v, 0): N1 = S1_u x S1_v = (0, 0, 1). S2 = (0, -0.1 + 0.6 s,
  // -0.25 + 2.5 t / 1.5) on the box t in [0, 1.5]: N2 = (1, 0, 0). Both surfaces extend past
  // x, z in [0, 2], so the whole circle (8) of alpha is inside.
  const auto s1 = planar("S1", {-0.25, 0, 0}, {2.5, 0, 0}, {0, 0.4, 0});
  auto s2 = planar("S2", {0, -0.1, -0.25}, {0, 0.6, 0}, {0, 0, 2.5});
  s2.box = {0, 1, 0, 1.5};
  SECTION("Bezier") { checkPerpendicularBlend(s1, s2); }
  SECTION("B-spline with unequal knot spans: N1 uses parameter, not span, derivatives") {
    // The same plane as a degree-1 B-spline in u on [0, 4] with spans [0, 1] and [1, 4]
    // (S1_u = 2.5 / 4 on both), and v on one span [0, 0.25] (S1_v = 1.6): N1 = (0, 0, 1).
    auto b1 = bezier("S1", 1, 1, {});
    b1.countU = 3;
    b1.knotsU = {0, 0, 1, 4, 4};
    for (double y : {0.0, 0.4})
      for (double x : {-0.25, -0.25 + 2.5 / 4, 2.25}) b1.points.push_back({x, y, 0});
    b1.knotsV = {0, 0, 0.25, 0.25};
    checkPerpendicularBlend(b1, s2);
  }
}

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("app-surfaces");
  return dir.path();
}

using ndc::test::slurp;

/// Runs `ndcontour info FILE` on `text` written to a scratch file: status and standard error.
std::pair<int, std::string> info(const std::string& text) {
  const fs::path file = scratch() / "problem.toml", err = scratch() / "stderr.txt";
  std::ofstream(file) << text;
  const std::string command = "'" + ndc::test::binaryPath() + "' info '" + file.string() +
                              "' >/dev/null 2>'" + err.string() + "' </dev/null";
  const int raw = std::system(command.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(err)};
}

}  // namespace

TEST_CASE("bad two-surface application files exit 2 with one line", "[applications]") {
  const auto s1 = planar("S1", {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const auto s2 = planar("S2", {0, 0, 1}, {1, 0, 0}, {0, 1, 0});
  struct Case {
    std::string text, part;
  };
  const std::vector<Case> cases = {
      {problemText("bisector", {s1}), "bisector needs exactly 2 [[surfaces]]"},
      {problemText("convex-hull", {s1, s2, s1}), "convex-hull needs exactly 2 [[surfaces]]"},
      {problemText("blending", {s1, s2}), "blending needs alpha"},
      {problemText("bisector", {s1, s2}, "alpha = [[0, 1], [0, 1]]\n"), "bisector takes no alpha"},
      {problemText("convex-hull", {s1, s2}, "eye = [0, 0, 5]\n"), "convex-hull takes no eye"},
  };
  for (const Case& c : cases) {
    const auto [status, err] = info(c.text);
    INFO(c.text << "stderr: " << err);
    CHECK(status == 2);
    CHECK(err.find(c.part) != std::string::npos);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
  }
  // A well-formed file passes `info`.
  CHECK(info(problemText("bisector", {s1, s2})).first == 0);
}
