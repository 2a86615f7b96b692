// Freeform input: piecewise Bernstein leaves, Bezier and B-spline surfaces (Bezier extraction),
// motions, B-spline patches in the pipeline, and application problem files.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <set>

#include "applications/freeform.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/cell_forms.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_support.hpp"

using namespace ndc;
using ndc::test::PrecisionScope;
using ndc::test::relativeTolerance;

namespace {

/// A bicubic B-spline surface with 5 x 5 control points (2 x 2 spans), clamped knots, wavy.
SurfaceSpec wavyBspline(bool rational) {
  SurfaceSpec s;
  s.name = "wavy";
  s.degreeU = 3;
  s.degreeV = 3;
  s.countU = 5;
  s.countV = 5;
  s.knotsU = {0, 0, 0, 0, 0.4, 1, 1, 1, 1};
  s.knotsV = {0, 0, 0, 0, 0.55, 1, 1, 1, 1};
  for (int j = 0; j < s.countV; ++j)
    for (int i = 0; i < s.countU; ++i) {
      s.points.push_back({i / 4.0, j / 4.0, 0.3 * std::sin(2.0 * i + j) + 0.1 * j});
      if (rational) s.weights.push_back(1.0 + 0.25 * ((i + 2 * j) % 3));
    }
  return s;
}

/// Cox-de Boor basis function N_{i,p}(t) (right-open spans, closed at the end of the range).
double basis(const std::vector<double>& k, int i, int p, double t) {
  if (p == 0) {
    const double end = k[k.size() - 1];
    if (t == end) return k[i] < t && t <= k[i + 1] ? 1 : 0;
    return k[i] <= t && t < k[i + 1] ? 1 : 0;
  }
  double value = 0;
  if (k[i + p] > k[i]) value += (t - k[i]) / (k[i + p] - k[i]) * basis(k, i, p - 1, t);
  if (k[i + p + 1] > k[i + 1])
    value += (k[i + p + 1] - t) / (k[i + p + 1] - k[i + 1]) * basis(k, i + 1, p - 1, t);
  return value;
}

/// The surface point by the B-spline definition (independent of Bezier extraction).
std::array<double, 3> deBoorPoint(const SurfaceSpec& s, double u, double v) {
  double h[4] = {0, 0, 0, 0};
  for (int j = 0; j < s.countV; ++j)
    for (int i = 0; i < s.countU; ++i) {
      const double b = basis(s.knotsU, i, s.degreeU, u) * basis(s.knotsV, j, s.degreeV, v);
      const std::size_t at = static_cast<std::size_t>(j * s.countU + i);
      const double w = s.rational() ? s.weights[at] : 1.0;
      for (int c = 0; c < 3; ++c) h[c] += b * w * s.points[at][c];
      h[3] += b * w;
    }
  return {h[0] / h[3], h[1] / h[3], h[2] / h[3]};
}

/// Span coordinate of parameter value x along direction d of `s`.
double spanCoordinate(const SurfaceSpec& s, int d, double x) {
  const std::vector<double> k = distinctKnots(s, d);
  std::size_t i = 0;
  while (i + 2 < k.size() && x >= k[i + 1]) ++i;
  return static_cast<double>(i) + (x - k[i]) / (k[i + 1] - k[i]);
}

/// The surface point at (u, v) by SurfaceSpec::evaluate and by the built expressions (on span
/// coordinates) against the B-spline definition, to within `tolerance`.
void checkAgainstDefinition(const SurfaceSpec& s, const SurfaceExpr& e, double u, double v,
                            double tolerance) {
  const auto truth = deBoorPoint(s, u, v);
  const auto point = s.evaluate(u, v);
  const double x[2] = {spanCoordinate(s, 0, u), spanCoordinate(s, 1, v)};
  const double w = e.W.evaluate<double>(std::span<const double>(x, 2));
  for (int c = 0; c < 3; ++c) {
    CHECK(std::abs(point[c] - truth[c]) < tolerance);
    CHECK(std::abs(e.P[c].evaluate<double>(std::span<const double>(x, 2)) / w - truth[c]) <
          tolerance);
  }
}

/// A plane section of a surface: z(u, v) = c, i.e. Z - c W = 0, a curve in (u, v).
Problem sectionProblem(const SurfaceSpec& s, double c) {
  Problem p;
  p.name = "section";
  p.variables = {"u", "v"};
  const SurfaceExpr e = makeSurface(s, 2, 0, 1);
  for (int d = 0; d < 2; ++d) {
    const auto r = variableRange(s, d);
    p.domain.lo.push_back(r[0]);
    p.domain.hi.push_back(r[1]);
  }
  p.equations.push_back(e.P[2] - Expression::constant(2, c) * e.W);
  setPatches(p);
  return p;
}

}  // namespace

TEMPLATE_TEST_CASE("piecewise leaves: value, enclosure, Bernstein form and derivative",
                   "[geometry]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> precision;
  // Two pieces along x (breaks 0, 1, 3), one along y: degrees (2, 1).
  auto leaf = std::make_shared<PiecewiseBernstein>();
  leaf->name = "f";
  leaf->axes = {1, 0};  // local axis 0 is variable 1, local axis 1 is variable 0
  leaf->breaks = {{0, 1, 3}, {-1, 1}};
  std::mt19937 rng(7);
  for (int piece = 0; piece < 2; ++piece) {
    Bernstein<double> b(Box<double>{{piece == 0 ? 0.0 : 1.0, -1.0}, {piece == 0 ? 1.0 : 3.0, 1.0}},
                        {2, 1});
    for (double& c : b.coefficients()) c = std::uniform_real_distribution<double>(-1, 1)(rng);
    leaf->pieces.push_back(b);
  }
  const Expression e = Expression::polynomial(2, leaf);
  for (int trial = 0; trial < 50; ++trial) {
    const S y = ndc::test::uniform<S>(rng, 0, 3), x = ndc::test::uniform<S>(rng, -1, 1);
    const int piece = y < 1 ? 0 : 1;
    const S local[2] = {y, x};
    // The piece's own evaluation, converted to S.
    const Bernstein<double>& b = leaf->pieces[piece];
    Bernstein<S> bs(Box<S>{{S(b.domain().lo[0]), S(b.domain().lo[1])},
                           {S(b.domain().hi[0]), S(b.domain().hi[1])}},
                    b.degrees());
    for (std::size_t i = 0; i < b.size(); ++i) bs.coefficients()[i] = S(b.coefficients()[i]);
    const S truth = bs.evaluate(std::span<const S>(local, 2));
    const S point[2] = {x, y};
    const S value = e.evaluate<S>(std::span<const S>(point, 2));
    CHECK(toDouble(S(abs(value - truth))) <= 10 * relativeTolerance<S>());
    // The gradient matches the derivative pieces.
    S gradient[2];
    e.evaluate<S>(std::span<const S>(point, 2), std::span<S>(gradient, 2));
    // The partials are leaves of their own whose coefficients are rounded to double once
    // (PiecewiseBernstein::derivative); the gradient evaluates exactly those.
    const auto inS = [](const Bernstein<double>& d) {
      Bernstein<S> out(Box<S>{{S(d.domain().lo[0]), S(d.domain().lo[1])},
                              {S(d.domain().hi[0]), S(d.domain().hi[1])}},
                       d.degrees());
      for (std::size_t i = 0; i < d.size(); ++i) out.coefficients()[i] = S(d.coefficients()[i]);
      return out;
    };
    const S dy = inS(b.derivative(0)).evaluate(std::span<const S>(local, 2));
    const S dx = inS(b.derivative(1)).evaluate(std::span<const S>(local, 2));
    CHECK(toDouble(S(abs(gradient[1] - dy))) <= 100 * relativeTolerance<S>());
    CHECK(toDouble(S(abs(gradient[0] - dx))) <= 100 * relativeTolerance<S>());
  }
  // The interval enclosure over a box across the break holds sampled values.
  const Interval<S> box[2] = {Interval<S>(S(-0.5), S(0.25)), Interval<S>(S(0.5), S(2.5))};
  const Interval<S> range = e.evaluate<S>(std::span<const Interval<S>>(box, 2));
  for (int trial = 0; trial < 200; ++trial) {
    const S point[2] = {ndc::test::uniform<S>(rng, -0.5, 0.25),
                        ndc::test::uniform<S>(rng, 0.5, 2.5)};
    CHECK(range.contains(e.evaluate<S>(std::span<const S>(point, 2))));
  }
  // The Bernstein form on a box inside one piece is exact; across the break it is refused.
  const Box<S> inside{{S(-0.5), S(1.5)}, {S(0.5), S(2.75)}};
  const Bernstein<S> form = e.toBernstein<S>(inside);
  for (int trial = 0; trial < 20; ++trial) {
    const S point[2] = {ndc::test::uniform<S>(rng, -0.5, 0.5),
                        ndc::test::uniform<S>(rng, 1.5, 2.75)};
    const S a = form.evaluate(std::span<const S>(point, 2));
    const S b = e.evaluate<S>(std::span<const S>(point, 2));
    CHECK(toDouble(S(abs(a - b))) <= 100 * relativeTolerance<S>());
  }
  const Box<S> across{{S(-0.5), S(0.5)}, {S(0.5), S(1.5)}};
  CHECK_THROWS_AS(e.toBernstein<S>(across), std::domain_error);
  CHECK(e.breaks(1) == std::vector<double>{0, 1, 3});
  CHECK(e.degrees() == std::vector<int>{1, 2});
}

TEMPLATE_TEST_CASE("built expressions equal the parsed polynomial", "[geometry]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> precision;
  const std::vector<std::string> names{"x", "y"};
  const Expression x = Expression::variable(2, 0, "x"), y = Expression::variable(2, 1, "y");
  const Expression built = (x * x - Expression::constant(2, 0.75)) * y + -(x * y);
  const Expression parsed = Expression::parse("(x*x - 0.75)*y - x*y", names);
  const Box<S> box{{S(-1), S(-2)}, {S(2), S(1)}};
  const Bernstein<S> a = built.toBernstein<S>(box), b = parsed.toBernstein<S>(box);
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    CHECK(toDouble(S(abs(a.coefficients()[i] - b.coefficients()[i]))) <= relativeTolerance<S>());
}

TEST_CASE("B-spline surfaces: Bezier extraction matches the B-spline definition", "[geometry]") {
  for (bool rational : {false, true}) {
    const SurfaceSpec s = wavyBspline(rational);
    const SurfaceExpr e = makeSurface(s, 2, 0, 1);
    CHECK(variableRange(s, 0) == std::array<double, 2>{0, 2});
    CHECK(distinctKnots(s, 0) == std::vector<double>{0, 0.4, 1});
    for (double u : {0.0, 0.1, 0.39, 0.4, 0.41, 0.7, 1.0})
      for (double v : {0.0, 0.33, 0.55, 0.8, 1.0}) {
        INFO("rational " << rational << " u " << u << " v " << v);
        checkAgainstDefinition(s, e, u, v, 1e-13);
      }
  }
}

/// A seeded random knot vector the reader accepts: non-decreasing integers in [0, 7], a
/// nonempty parameter range, interior multiplicities at most the degree, any multiplicity at
/// the ends (clamped or not).
std::vector<double> randomKnots(std::mt19937& rng, int degree, int count) {
  std::uniform_int_distribution<int> value(0, 7);
  for (;;) {
    std::vector<double> k(std::size_t(count + degree + 1));
    for (double& x : k) x = value(rng);
    std::sort(k.begin(), k.end());
    const double a = k[degree], b = k[count];
    bool ok = a < b;
    for (double x : k) ok = ok && !(x > a && x < b && std::count(k.begin(), k.end(), x) > degree);
    if (ok) return k;
  }
}

TEST_CASE("B-spline surfaces: unclamped and random knot vectors match the definition",
          "[geometry]") {
  // Knot insertion at the ends of an unclamped range once read past its arrays.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 60; ++trial) {
    SurfaceSpec s;
    s.name = "random";
    s.degreeU = 1 + trial % 4;
    s.degreeV = 1 + (trial / 4) % 3;
    s.countU = s.degreeU + 1 + int(rng() % 4);
    s.countV = s.degreeV + 1 + int(rng() % 3);
    s.knotsU = randomKnots(rng, s.degreeU, s.countU);
    s.knotsV = randomKnots(rng, s.degreeV, s.countV);
    for (int j = 0; j < s.countV; ++j)
      for (int i = 0; i < s.countU; ++i) s.points.push_back({unit(rng), unit(rng), unit(rng)});
    const SurfaceExpr e = makeSurface(s, 2, 0, 1);
    const std::vector<double> ku = distinctKnots(s, 0), kv = distinctKnots(s, 1);
    for (std::size_t a = 0; a + 1 < ku.size(); ++a)
      for (std::size_t b = 0; b + 1 < kv.size(); ++b)
        for (double t : {0.2, 0.7}) {
          const double u = ku[a] + t * (ku[a + 1] - ku[a]),
                       v = kv[b] + (1 - t) * (kv[b + 1] - kv[b]);
          INFO("trial " << trial << " u " << u << " v " << v);
          checkAgainstDefinition(s, e, u, v, 1e-12);
        }
  }
}

TEMPLATE_TEST_CASE("CellForms: each cell maps to its patch's root forms", "[geometry]",
                   NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> precision;
  // Four B-spline patches (root level 1), asked for from the cells of a depth-4 grid: every
  // cell gets the forms of the patch that contains it, computed once per patch, equal to the
  // equations' Bernstein forms on the patch box.
  const Problem p = sectionProblem(wavyBspline(false), 0.1);
  REQUIRE(p.rootLevel == 1);
  const Grid grid{p.n(), 4, p.domain};
  const Box<S> domain = toScalar<S>(p.domain);
  CellForms<S> forms(p.equations, grid, domain, p.rootLevel);
  std::set<const std::vector<Bernstein<S>>*> distinct;
  for (std::int32_t i = 0; i < 16; ++i)
    for (std::int32_t j = 0; j < 16; ++j) {
      const std::vector<std::int32_t> cell{i, j}, patch{i >> 3, j >> 3};
      const std::vector<Bernstein<S>>& root = forms.root(cell, grid.depth);
      distinct.insert(&root);
      REQUIRE(&forms.root(patch, 1) == &root);
      const Box<S> box = cellBox<S>(Grid{p.n(), 1, p.domain}, domain, patch);
      REQUIRE(root.size() == p.equations.size());
      for (std::size_t e = 0; e < root.size(); ++e) {
        const Bernstein<S> expected = p.equations[e].template toBernstein<S>(box);
        const auto got = root[e].coefficients(), want = expected.coefficients();
        REQUIRE(std::equal(got.begin(), got.end(), want.begin(), want.end()));
      }
    }
  CHECK(distinct.size() == 4);
  // A polynomial on the whole domain (root level 0): one set of forms for every cell.
  const std::vector<std::string> names{"x", "y"};
  const std::vector<Expression> circle{Expression::parse("x^2 + y^2 - 1", names)};
  CellForms<S> whole(circle, grid, domain, 0);
  const std::vector<std::int32_t> a{0, 0}, b{15, 7};
  const std::vector<Bernstein<S>>& root = whole.root(a, 4);
  CHECK(&whole.root(b, 4) == &root);
  const Bernstein<S> expected = circle[0].template toBernstein<S>(domain);
  CHECK(std::equal(root[0].coefficients().begin(), root[0].coefficients().end(),
                   expected.coefficients().begin(), expected.coefficients().end()));
}

TEST_CASE("B-spline input gives the same cells and vertices as its Bezier pieces", "[geometry]") {
  // The plane section z = 0.1 of a 2-span B-spline surface, solved once across both patches,
  // against each Bezier piece solved as its own problem on the same grid cells.
  const SurfaceSpec s = wavyBspline(false);
  const Problem whole = sectionProblem(s, 0.1);
  REQUIRE(whole.rootLevel == 1);
  // The spans are [0, 1] and [1, 2] in u and in v: four root boxes, the level-1 cells.
  REQUIRE(whole.roots.size() == 4);
  Settings settings;
  settings.depth = 6;
  const RunResult all = runPipeline(whole, settings);
  CHECK(all.summary.mesh.maxResidual < 1e-12);
  std::set<std::pair<long long, long long>> allVertices;
  for (std::size_t v = 0; v < all.vertices.size() / 2; ++v)
    allVertices.insert(
        {std::llround(all.vertices[2 * v] * 1e9), std::llround(all.vertices[2 * v + 1] * 1e9)});
  std::size_t pieceVertices = 0;
  for (int piece = 0; piece < 4; ++piece) {
    // The Bezier piece of spans (piece % 2, piece / 2), a unit square in span coordinates: a
    // grid of depth 5 there has the cells of the whole's depth 6 grid.
    Problem part = whole;
    part.roots.clear();
    part.rootLevel = 0;
    const double u0 = piece % 2, v0 = piece / 2;
    part.domain = Box<double>{{u0, v0}, {u0 + 1, v0 + 1}};
    Settings pieceSettings = settings;
    pieceSettings.depth = 5;
    pieceSettings.connection = "paper";  // only the vertices are compared
    const RunResult r = runPipeline(part, pieceSettings);
    // Every projected cell point of the piece is a projected cell point of the whole.
    std::set<std::pair<long long, long long>> wholePoints;
    for (std::size_t c = 0; c < all.cellPoint.size() / 2; ++c)
      wholePoints.insert(
          {std::llround(all.cellPoint[2 * c] * 1e9), std::llround(all.cellPoint[2 * c + 1] * 1e9)});
    for (std::size_t c = 0; c < r.cellPoint.size() / 2; ++c)
      CHECK(wholePoints.count({std::llround(r.cellPoint[2 * c] * 1e9),
                               std::llround(r.cellPoint[2 * c + 1] * 1e9)}) == 1);
    pieceVertices += r.cellPoint.size() / 2;
  }
  // Each solution cell of the whole lies in exactly one piece.
  CHECK(pieceVertices == all.cellPoint.size() / 2);
  // And the whole is one closed or domain-bounded polyline across the patch boundary u = 1.
  CHECK(all.summary.mesh.branchVertices == 0);
  bool crosses = false;
  for (std::size_t e = 0; e < all.simplices.size() / 2; ++e) {
    const double a = all.vertices[2 * all.simplices[2 * e]];
    const double b = all.vertices[2 * all.simplices[2 * e + 1]];
    crosses = crosses || (a < 1) != (b < 1);
  }
  CHECK(crosses);
  // The jitter would move the knots off the grid planes: refused.
  settings.jitter = 1;
  CHECK_THROWS_AS(runPipeline(whole, settings), InputError);
}

TEST_CASE("motions: the rational rotation and the body angular velocity", "[geometry]") {
  MotionSpec m;
  m.translation = {{0, 0, 0}, {1, 2, 0}, {3, 0, 1}};
  m.rotation = {{1, 0, 0, 0}, {0.8, 0.3, -0.2, 0.5}, {0.6, -0.4, 0.7, 0.1}};
  m.time = {0, 2};
  const MotionExpr e = makeMotion(m, 1, 0);
  const std::array<double, 3> x{0.3, -0.7, 1.1};
  for (double t : {0.0, 0.5, 1.3, 2.0}) {
    const double tt[1] = {t};
    const std::span<const double> at(tt, 1);
    const double w = e.w.evaluate<double>(at);
    // A(t)[x] from the expressions against MotionSpec::apply.
    const auto y = m.apply(t, x);
    for (int r = 0; r < 3; ++r) {
      double value = e.T[r].evaluate<double>(at);
      for (int c = 0; c < 3; ++c) value += e.M[r][c].evaluate<double>(at) * x[c] / w;
      CHECK(std::abs(value - y[r]) < 1e-13);
    }
    // R^T R' x = (Omega / w) x x, R' by central differences.
    const double h = 1e-6;
    const auto yp = m.apply(t + h, x), ym = m.apply(t - h, x);
    const auto tp = m.apply(t + h, {0, 0, 0}), tm = m.apply(t - h, {0, 0, 0});
    double rdot[3], rows[3][3];
    for (int r = 0; r < 3; ++r) {
      rdot[r] = ((yp[r] - tp[r]) - (ym[r] - tm[r])) / (2 * h);
      for (int c = 0; c < 3; ++c) rows[r][c] = e.M[r][c].evaluate<double>(at) / w;
    }
    double body[3];
    for (int c = 0; c < 3; ++c)
      body[c] = rows[0][c] * rdot[0] + rows[1][c] * rdot[1] + rows[2][c] * rdot[2];
    const auto omega = e.bodyAngularVelocity();
    double o[3];
    for (int c = 0; c < 3; ++c) o[c] = omega[c].evaluate<double>(at) / w;
    const double expected[3] = {o[1] * x[2] - o[2] * x[1], o[2] * x[0] - o[0] * x[2],
                                o[0] * x[1] - o[1] * x[0]};
    for (int c = 0; c < 3; ++c) CHECK(std::abs(body[c] - expected[c]) < 1e-6);
  }
}

TEST_CASE("application files: bad freeform input exits 2 with one line", "[geometry][cli]") {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("ndc-test-geometry-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string head = "name = \"bad\"\napplication = \"bisector\"\n";
  const std::string patch = "[[surfaces]]\npoints = [[[0,0,0],[1,0,0]],[[0,1,0],[1,1,0]]]\n";
  const std::pair<std::string, std::string> cases[] = {
      {head + "[[surfaces]]\npoints = [[[0,0,0],[1,0,0]],[[0,1,0]]]\n", "same number of points"},
      {head + "[[surfaces]]\npoints = [[[0,0,0],[1,0,0]],[[0,1,0],[1,1]]]\n", "[x, y, z]"},
      {head + patch + "weights = [[1, 1], [1, -1]]\n", "weights must be positive"},
      {head + patch + "colour = 3\n", "unknown key 'colour'"},
      {head + "[[surfaces]]\ndegree = [1, 1]\n", "missing required key 'points'"},
      {head + patch + "degree = [2, 1]\n", "needs degree + 1 = 3 points per row"},
      {head + patch + "degree = [1, 1]\nknots_u = [0, 0, 1]\n", "needs count + degree + 1 = 4"},
      {head + patch + "degree = [1, 1]\nknots_u = [0, 1, 0.5, 1]\n", "non-decreasing"},
      {head + patch + "box = [[1, 0], [0, 1]]\n", "empty or inverted"},
      {head + "[motion]\ntranslation = [[0,0,0]]\n", "missing required key 'rotation'"},
      {head + "eye = [0, 0]\n", "[x, y, z]"},
      {"name = \"bad\"\napplication = \"smoothing\"\n", "unknown application 'smoothing'"},
      {"name = \"Bad Name\"\napplication = \"bisector\"\n", "must match [a-z0-9._-]+"},
  };
  int index = 0;
  for (const auto& [text, message] : cases) {
    const fs::path file = dir / ("case" + std::to_string(index++) + ".toml");
    std::ofstream(file) << text;
    const fs::path err = dir / "stderr.txt";
    const std::string command = "'" + ndc::test::binaryPath() + "' info '" + file.string() +
                                "' >/dev/null 2>'" + err.string() + "'";
    const int raw = std::system(command.c_str());
    std::ifstream in(err);
    const std::string line((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    INFO(text << "\nstderr: " << line);
    CHECK(WIFEXITED(raw));
    CHECK(WEXITSTATUS(raw) == 2);
    CHECK(line.find(message) != std::string::npos);
    CHECK(std::count(line.begin(), line.end(), '\n') == 1);
  }
  fs::remove_all(dir);
}
