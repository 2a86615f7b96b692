// The sweep applications (paper Sec. 3.2 and 3.4) against ground truth computed independently of
// the builders: the envelope of a translated exact sphere patch lies on a cylinder, the envelope of
// a rotating patch satisfies det[A'(t)S, A S_u, A S_v] = 0 by finite differences, silhouette
// vertices satisfy (4) and (5) by finite differences, the example files solve, and bad sweep files
// exit 2 via the command-line tool.
//
// Finite differences use only SurfaceSpec::evaluate and MotionSpec::apply (double), never the
// builders' expressions: X(u, v, t) = A(t)[S(u, v)], so A'(t)[S] = X_t, A(t)[S_u] = X_u and
// A(t)[S_v] = X_v (A is affine in x), and A(t)[N] is parallel to X_u x X_v.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "applications/freeform.hpp"
#include "applications/load.hpp"
#include "applications/sweep_common.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

using Vec3 = std::array<double, 3>;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 crossP(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dotP(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dotP(a, a)); }

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string vec(const Vec3& p) {
  return "[" + num(p[0]) + ", " + num(p[1]) + ", " + num(p[2]) + "]";
}

/// The `[[surfaces]]` table of a Bezier patch.
std::string surfaceToml(const ndc::SurfaceSpec& s) {
  std::string t = "[[surfaces]]\nname = \"" + s.name + "\"\npoints = [";
  for (int j = 0; j < s.countV; ++j) {
    t += j ? ",\n  [" : "\n  [";
    for (int i = 0; i < s.countU; ++i) t += (i ? ", " : "") + vec(s.points[j * s.countU + i]);
    t += "]";
  }
  t += "]\n";
  if (s.rational()) {
    t += "weights = [";
    for (int j = 0; j < s.countV; ++j) {
      t += j ? ", [" : "[";
      for (int i = 0; i < s.countU; ++i) t += (i ? ", " : "") + num(s.weights[j * s.countU + i]);
      t += "]";
    }
    t += "]\n";
  }
  return t;
}

/// The `[motion]` table.
std::string motionToml(const ndc::MotionSpec& m) {
  std::string t = "[motion]\ntranslation = [";
  for (std::size_t i = 0; i < m.translation.size(); ++i)
    t += (i ? ", " : "") + vec(m.translation[i]);
  t += "]\nrotation = [";
  for (std::size_t i = 0; i < m.rotation.size(); ++i) {
    const auto& q = m.rotation[i];
    t += (i ? ", [" : "[") + num(q[0]) + ", " + num(q[1]) + ", " + num(q[2]) + ", " + num(q[3]) +
         "]";
  }
  t += "]\ntime = [" + num(m.time[0]) + ", " + num(m.time[1]) + "]\n";
  return t;
}

std::string problemToml(const std::string& application, const ndc::SurfaceSpec& s,
                        const ndc::MotionSpec& m, const Vec3* eye = nullptr) {
  std::string t = "name = \"test\"\napplication = \"" + application + "\"\n";
  if (eye) t += "eye = " + vec(*eye) + "\n";
  return t + surfaceToml(s) + motionToml(m);
}

/// An exact piece of the sphere of radius r about c: the tensor product of two rational quadratic
/// 90-degree arcs (longitude and latitude in [-45, 45] degrees about +x), scaled along the axes by
/// `stretch` (an ellipsoid piece when not all 1).
ndc::SurfaceSpec spherePatch(double r, const Vec3& c, const Vec3& stretch = {1, 1, 1}) {
  const double h = std::sqrt(0.5);
  // Arc control points (x, y) and weights: from -45 to 45 degrees, middle at the tangents' meet.
  const double ax[3] = {h, std::sqrt(2.0), h}, ay[3] = {-h, 0, h}, aw[3] = {1, h, 1};
  ndc::SurfaceSpec s;
  s.name = "sphere";
  s.degreeU = s.degreeV = 2;
  s.countU = s.countV = 3;
  for (int j = 0; j < 3; ++j)      // latitude: (cos, sin) = (ax[j], ay[j])
    for (int i = 0; i < 3; ++i) {  // longitude
      const Vec3 unit{ax[j] * ax[i], ax[j] * ay[i], ay[j]};
      s.points.push_back({c[0] + r * stretch[0] * unit[0], c[1] + r * stretch[1] * unit[1],
                          c[2] + r * stretch[2] * unit[2]});
      s.weights.push_back(aw[i] * aw[j]);
    }
  return s;
}

/// A wavy polynomial bicubic patch.
ndc::SurfaceSpec wavyPatch() {
  const double z[4][4] = {
      {0.2, -0.3, 0.4, 0.1}, {0.5, 0.9, -0.2, 0.3}, {-0.1, 0.2, 0.8, 0.4}, {0.3, -0.2, 0.1, 0.6}};
  ndc::SurfaceSpec s;
  s.name = "wavy";
  s.degreeU = s.degreeV = 3;
  s.countU = s.countV = 4;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) s.points.push_back({-1 + 2.0 * i / 3, -1 + 2.0 * j / 3, z[j][i]});
  return s;
}

/// W(u, v) of a rational Bezier patch on [0, 1]^2 (1 when polynomial), by de Casteljau.
double weightAt(const ndc::SurfaceSpec& s, double u, double v) {
  if (!s.rational()) return 1;
  auto casteljau = [](std::vector<double> c, double x) {
    for (std::size_t r = 1; r < c.size(); ++r)
      for (std::size_t i = 0; i + r < c.size(); ++i) c[i] += x * (c[i + 1] - c[i]);
    return c[0];
  };
  std::vector<double> column;
  for (int j = 0; j < s.countV; ++j)
    column.push_back(casteljau(std::vector<double>(s.weights.begin() + j * s.countU,
                                                   s.weights.begin() + (j + 1) * s.countU),
                               u));
  return casteljau(column, v);
}

/// w(t) = |q(t)|^2 of the motion.
double quaternionNorm2(const ndc::MotionSpec& m, double t) {
  const double s = (t - m.time[0]) / (m.time[1] - m.time[0]);
  std::vector<std::array<double, 4>> q = m.rotation;
  for (std::size_t r = 1; r < q.size(); ++r)
    for (std::size_t i = 0; i + r < q.size(); ++i)
      for (int c = 0; c < 4; ++c) q[i][c] += s * (q[i + 1][c] - q[i][c]);
  return q[0][0] * q[0][0] + q[0][1] * q[0][1] + q[0][2] * q[0][2] + q[0][3] * q[0][3];
}

/// X(u, v, t) = A(t)[S(u, v)] and its central differences in double.
struct Sweep {
  const ndc::SurfaceSpec& spec;
  const ndc::MotionSpec& motion;
  Vec3 X(double u, double v, double t) const { return motion.apply(t, spec.evaluate(u, v)); }
  /// Central difference along axis a (0 = u, 1 = v, 2 = t) with step h.
  Vec3 D(const std::array<double, 3>& x, int a, double h) const {
    std::array<double, 3> p = x, m = x;
    p[a] += h;
    m[a] -= h;
    const Vec3 xp = X(p[0], p[1], p[2]), xm = X(m[0], m[1], m[2]);
    return {(xp[0] - xm[0]) / (2 * h), (xp[1] - xm[1]) / (2 * h), (xp[2] - xm[2]) / (2 * h)};
  }
};

// Finite-difference step and the error budget of a normalised determinant or triple product.
// Central differences of X (a rational function of moderate degree with derivatives of the order of
// its first derivatives times at most ~10 per order on these inputs) have truncation error h^2 / 6
// |X'''| <= 1e-10 * 100 / 6 |X'| ~ 2e-9 |X'| relative at h = 1e-5, and rounding error ~ eps |X| / h
// ~ 1e-11 |X| / |X'|; a normalised 3 x 3 determinant of three such columns is off by at most the
// sum of their relative errors, ~ 6e-9: 1e-8 bounds it.
constexpr double kStep = 1e-5;
constexpr double kDifferenceError = 1e-8;

ndc::Settings settingsAt(int depth, const char* connection = "crossing") {
  ndc::Settings s;
  s.depth = depth;
  s.connection = connection;
  return s;
}

/// Vertex i of a run, (u, v, t).
std::array<double, 3> vertex(const ndc::RunResult& r, std::size_t i) {
  return {r.vertices[3 * i], r.vertices[3 * i + 1], r.vertices[3 * i + 2]};
}

// ---- the command-line tool as a process (as in test_cli.cpp) -------------------------------

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("sweep");
  return dir.path();
}

using ndc::test::quoted;
using ndc::test::slurp;
using Run = ndc::test::CliRun;

/// Runs `ndcontour ARGS` (ARGS already shell-quoted) and captures status, stdout and stderr.
Run ndcontour(const std::string& args) { return ndc::test::runNdcontour(args, scratch()); }

fs::path problemsDir() { return fs::path(ndc::test::sourceDir()) / "experiments" / "problems"; }

}  // namespace

TEST_CASE("sweep: the quaternion norm check of the motion", "[applications]") {
  ndc::MotionSpec m;
  m.translation = {{0, 0, 0}};
  // A half turn per linear piece: q0 perpendicular to q1, a zero middle coefficient of w, but w =
  // (1 - t)^2 + t^2 > 0.
  m.rotation = {{1, 0, 0, 0}, {0, 1, 0, 0}};
  CHECK(ndc::quaternionNeverZero(m));
  // q(t) = 1 - 2t vanishes at t = 1/2.
  m.rotation = {{1, 0, 0, 0}, {-1, 0, 0, 0}};
  CHECK_FALSE(ndc::quaternionNeverZero(m));
  m.rotation = {{0, 0, 0, 0}};
  CHECK_FALSE(ndc::quaternionNeverZero(m));
  // Vanishes at an end of the time range.
  m.rotation = {{0, 0, 0, 0}, {1, 2, 0, 0}};
  CHECK_FALSE(ndc::quaternionNeverZero(m));
  // Close to zero in the interior, but not zero: |q(1/2)|^2 = 1e-6.
  m.rotation = {{1, 0, 0, 0}, {-1, 0, 0, 0.002}};
  CHECK(ndc::quaternionNeverZero(m));
  // A full turn as a quartic (q goes from 1 to -1 through k).
  m.rotation = {{1, 0, 0, 0}, {1, 0, 0, 1}, {0, 0, 0, 2}, {-1, 0, 0, 1}, {-1, 0, 0, 0}};
  CHECK(ndc::quaternionNeverZero(m));
}

TEST_CASE("sweep-envelope: a translated sphere patch sweeps a cylinder", "[applications]") {
  // An exact rational sphere patch of radius r about c, under a constant (non-unit) quaternion and
  // a straight translation T(t) = t d: its centre moves on the line L = R c + s d, so the envelope
  // A(t)[S] with (4) lies on the cylinder of radius r about L, and at every envelope point the
  // sphere's normal is perpendicular to d.
  const double r = 1.5;
  const Vec3 c{0.2, -0.1, 0.3};
  const ndc::SurfaceSpec sphere = spherePatch(r, c);
  ndc::MotionSpec motion;
  motion.rotation = {{2, 0.5, -1, 0.3}};
  motion.translation = {{0, 0, 0}};
  motion.time = {0, 1};
  // d = R d_body, with d_body oblique to the patch's grid lines (the curve n . d_body = 0 is then
  // in general position on the patch).
  const Vec3 d = motion.apply(0, {0.6, 0.8, 2});
  motion.translation.push_back(d);

  // The patch is on the sphere (a check of the input, not of the builder).
  for (double u : {0.0, 0.3, 0.7, 1.0})
    for (double v : {0.0, 0.4, 1.0}) CHECK(norm(sub(sphere.evaluate(u, v), c)) == Approx(r));

  const ndc::Problem problem =
      ndc::parseProblem(problemToml("sweep-envelope", sphere, motion), "sphere.toml");
  REQUIRE(problem.n() == 3);
  REQUIRE(problem.k() == 2);
  REQUIRE(problem.application);
  const ndc::RunResult run = ndc::runPipeline(problem, settingsAt(5));
  const ndc::Summary& s = run.summary;
  // The envelope in (u, v, t) is (a curve on the patch) x [0, 1]: one disc.
  CHECK(s.mesh.components == 1);
  CHECK(s.mesh.nonmanifoldEdges == 0);
  CHECK(s.mesh.eulerCharacteristic == 1);
  CHECK(s.mesh.maxResidual < 1e-10);
  REQUIRE(s.mesh.vertices > 100);

  const Vec3 centre0 = motion.apply(0, c);  // R c
  const Vec3 axis{d[0] / norm(d), d[1] / norm(d), d[2] / norm(d)};
  double worstDistance = 0, worstNormal = 0;
  for (std::size_t i = 0; i < run.vertices.size() / 3; ++i) {
    const auto x = vertex(run, i);
    const Vec3 X = motion.apply(x[2], sphere.evaluate(x[0], x[1]));
    // The builder's image map is A(t)[S(u, v)].
    const Vec3 image = problem.application->image(x);
    CHECK(norm(sub(image, X)) <= 1e-12 * (1 + norm(X)));
    // Distance from the line L.
    const Vec3 rel = sub(X, centre0);
    const double along = dotP(rel, axis);
    const Vec3 perp{rel[0] - along * axis[0], rel[1] - along * axis[1], rel[2] - along * axis[2]};
    worstDistance = std::max(worstDistance, std::abs(norm(perp) - r));
    // The normal of the moved sphere at X is n = (X - centre(t)) / r; (4) says n . d = 0. With
    // Omega = 0 and M = w R constant, the cleared equation is F = W (M^T d) . N = w W^5 (R^T d) .
    // (S_u x S_v) = w W^5 |S_u x S_v| |d| (n . d^), and |F| <= max_residual at a vertex, so |n .
    // d^| <= max_residual / (w W^5 |S_u x S_v| |d|), W from the weights. nd is computed without
    // differences (X and the centre are exact up to rounding, ~1e-15 |X| / r); the pipeline
    // evaluated F in double, off by rounding of the order of 1e-16 times the sum of the
    // expression's term magnitudes, far below 1e-12 in units of nd; |S_u x S_v| = |X_u x X_v| by
    // differences is off by ~1e-9 relative, inside 1 + 1e-6.
    const Vec3 centre = motion.apply(x[2], c);
    const double nd = dotP(sub(X, centre), axis) / r;
    const Sweep sw{sphere, motion};
    const double area = norm(crossP(sw.D(x, 0, kStep), sw.D(x, 1, kStep)));
    const double W = weightAt(sphere, x[0], x[1]);
    const double w = quaternionNorm2(motion, x[2]);
    const double bound =
        (1 + 1e-6) * s.mesh.maxResidual / (w * std::pow(W, 5) * area * norm(d)) + 1e-12;
    INFO("vertex " << i << " (" << x[0] << ", " << x[1] << ", " << x[2] << ")");
    CHECK(std::abs(nd) <= bound);
    worstNormal = std::max(worstNormal, std::abs(nd));
  }
  // On the cylinder: the distance is r sqrt(1 - (n . d^)^2), off by ~ (n . d^)^2 r / 2.
  CHECK(worstDistance <= 1e-12 * r + r * worstNormal * worstNormal);
  CHECK(worstDistance <= 1e-9);
}

TEST_CASE("sweep-envelope: a rotating patch satisfies (4) by finite differences",
          "[applications]") {
  // Rotation only (a constant translation) with a quadratic, non-unit quaternion curve whose axis
  // turns: the characteristic curve moves on the patch with t.
  const ndc::SurfaceSpec wavy = wavyPatch();
  ndc::MotionSpec motion;
  motion.translation = {{0.5, 0, 0}};
  motion.rotation = {{1, 0, 0, 0}, {1, 0.3, 0.2, 0.6}, {0.2, 0.5, 0.1, 1}};
  motion.time = {0, 1};
  const ndc::Problem problem =
      ndc::parseProblem(problemToml("sweep-envelope", wavy, motion), "rotate.toml");
  const ndc::RunResult run = ndc::runPipeline(problem, settingsAt(5));
  const ndc::Summary& s = run.summary;
  CHECK(s.mesh.nonmanifoldEdges == 0);
  CHECK(s.mesh.maxResidual < 1e-9);
  REQUIRE(s.mesh.vertices > 100);

  const Sweep sw{wavy, motion};
  // det[X_t, X_u, X_v] / (|X_t| |X_u| |X_v|), the normalised (4).
  auto normalised = [&](const std::array<double, 3>& x) {
    const Vec3 Xt = sw.D(x, 2, kStep), Xu = sw.D(x, 0, kStep), Xv = sw.D(x, 1, kStep);
    return std::array<double, 2>{dotP(Xt, crossP(Xu, Xv)), norm(Xt) * norm(Xu) * norm(Xv)};
  };
  double offM = 0;
  for (std::size_t i = 0; i < run.vertices.size() / 3; ++i) {
    const auto x = vertex(run, i);
    const auto [det, scale] = normalised(x);
    // The cleared F is w W^5 det (W = 1 here) and |F| <= max_residual at a vertex.
    const double bound =
        s.mesh.maxResidual / (quaternionNorm2(motion, x[2]) * scale) + kDifferenceError;
    INFO("vertex " << i << " (" << x[0] << ", " << x[1] << ", " << x[2] << ") det " << det / scale);
    CHECK(std::abs(det) / scale <= bound);
    // The same measure 0.02 away in t, off M: the check can fail.
    const auto [detOff, scaleOff] = normalised({x[0], x[1], x[2] + 0.02});
    offM = std::max(offM, std::abs(detOff) / scaleOff);
  }
  CHECK(offM > 1e3 * kDifferenceError);
}

TEST_CASE("sweep-silhouette: vertices satisfy (4) and (5) by finite differences",
          "[applications]") {
  // An exact ellipsoid piece (rational) translated along a parabola and turning, seen from E.
  const ndc::SurfaceSpec body = spherePatch(1, {0, 0, 0}, {1.5, 1, 0.7});
  ndc::MotionSpec motion;
  motion.translation = {{0, 0, 0}, {1, 1, 0.5}, {2, 0, 1}};
  motion.rotation = {{1, 0, 0, 0}, {1, 0.2, 0, 0.5}};
  motion.time = {0, 1};
  const Vec3 eye{1, -6, 3};
  const ndc::Problem problem =
      ndc::parseProblem(problemToml("sweep-silhouette", body, motion, &eye), "silhouette.toml");
  REQUIRE(problem.k() == 1);
  for (const char* connection : {"crossing", "paper"}) {
    INFO("connection " << connection);
    const ndc::RunResult run = ndc::runPipeline(problem, settingsAt(6, connection));
    const ndc::Summary& s = run.summary;
    CHECK(s.mesh.branchVertices == 0);
    CHECK(s.mesh.maxResidual < 1e-9);
    REQUIRE(s.mesh.vertices > 20);

    const Sweep sw{body, motion};
    for (std::size_t i = 0; i < run.vertices.size() / 3; ++i) {
      const auto x = vertex(run, i);
      const Vec3 X = sw.X(x[0], x[1], x[2]);
      const Vec3 Xt = sw.D(x, 2, kStep), Xu = sw.D(x, 0, kStep), Xv = sw.D(x, 1, kStep);
      const Vec3 normal = crossP(Xu, Xv);  // A(t)[N] up to a positive factor
      // Both cleared equations are w W^5 times the unnormalised measures below (sweep_common.cpp)
      // and each is at most max_residual at a vertex.
      const double factor = quaternionNorm2(motion, x[2]) * std::pow(weightAt(body, x[0], x[1]), 5);
      const double scale4 = norm(Xt) * norm(normal), scale5 = norm(sub(X, eye)) * norm(normal);
      const double f4 = dotP(Xt, normal), f5 = dotP(sub(X, eye), normal);
      INFO("vertex " << i << " (" << x[0] << ", " << x[1] << ", " << x[2] << ")");
      CHECK(std::abs(f4) / scale4 <= s.mesh.maxResidual / (factor * scale4) + kDifferenceError);
      CHECK(std::abs(f5) / scale5 <= s.mesh.maxResidual / (factor * scale5) + kDifferenceError);
    }
  }
}

TEST_CASE("sweep: the example files solve with the paper and crossing connections",
          "[applications][slow]") {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(problemsDir())) {
    const std::string name = entry.path().stem().string();
    if (name.rfind("sweep-", 0) != 0) continue;
    ++count;
    const ndc::Problem problem = ndc::loadProblem(entry.path());
    for (const char* connection : {"paper", "crossing"}) {
      INFO(name << " " << connection);
      const ndc::RunResult run = ndc::runPipeline(problem, settingsAt(5, connection));
      const ndc::Summary& s = run.summary;
      CHECK(s.normal + s.abnormal + s.failed == s.solution);
      CHECK(s.mesh.vertices > 50);
      CHECK(s.mesh.maxResidual < 1e-8);
      // [expect] holds what crossing gives (at depths 5 and 6; paper may differ).
      if (std::string(connection) == "crossing" && problem.expect.components)
        CHECK(s.mesh.components == *problem.expect.components);
    }
  }
  CHECK(count >= 4);
}

TEST_CASE("sweep: bad sweep files exit 2 with one line", "[applications][cli]") {
  const ndc::SurfaceSpec sphere = spherePatch(1, {0, 0, 0});
  ndc::MotionSpec motion;
  motion.translation = {{0, 0, 0}, {1, 0, 0}};
  motion.rotation = {{1, 0, 0, 0}};
  const Vec3 eye{0, 0, 10};
  const std::string head = "name = \"bad\"\napplication = \"sweep-envelope\"\n";
  const std::string silhouetteHead = "name = \"bad\"\napplication = \"sweep-silhouette\"\n";
  ndc::MotionSpec vanishing = motion;
  vanishing.rotation = {{1, 0, 0, 0}, {-1, 0, 0, 0}};
  struct Case {
    const char* what;
    std::string text;
    const char* message;
  };
  const Case cases[] = {
      {"two surfaces", head + surfaceToml(sphere) + surfaceToml(sphere) + motionToml(motion),
       "exactly one [[surfaces]]"},
      {"no surface", head + motionToml(motion), "exactly one [[surfaces]]"},
      {"no motion", head + surfaceToml(sphere), "needs a [motion]"},
      {"zero quaternion", head + surfaceToml(sphere) + motionToml(vanishing), "vanishes"},
      {"eye missing", silhouetteHead + surfaceToml(sphere) + motionToml(motion), "eye point"},
      {"eye for envelope",
       head + "eye = " + vec(eye) + "\n" + surfaceToml(sphere) + motionToml(motion),
       "eye is only used by sweep-silhouette"},
  };
  for (const Case& c : cases) {
    INFO(c.what << ":\n" << c.text);
    const fs::path file = scratch() / "bad.toml";
    std::ofstream(file) << c.text;
    const Run run = ndcontour("solve " + quoted(file.string()) + " --depth 2");
    INFO("stderr: " << run.err);
    CHECK(run.status == 2);
    CHECK(run.out.empty());
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    CHECK(run.err.find(c.message) != std::string::npos);
    CHECK(run.err.find("bad.toml") != std::string::npos);
  }
}
