// Connection strategies (paper Sec. 4.1, 4.2, Algorithm 1) on hand-built solution cells: the
// cells are found by brute force from dense samples of a known manifold, projected with a
// minimum-norm Newton, classified with the paper's rule, connected, and the complex's topology
// is checked against the ground truth.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <unordered_map>
#include <variant>
#include <vector>

#include "applications/load.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "strategies/connection/connection.hpp"
#include "tests/test_support.hpp"

namespace {

using namespace ndc;
using Point = std::vector<double>;

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.17g)", v);
  return buf;
}

/// A problem from its equations on [-1, 1]^n.
Problem makeProblem(int n, const std::vector<std::string>& equations) {
  std::string text = "name = \"test\"\nvariables = [";
  for (int i = 0; i < n; ++i) text += (i ? ", \"x" : "\"x") + std::to_string(i) + "\"";
  text += "]\ndomain = [";
  for (int i = 0; i < n; ++i) text += i ? ", [-1, 1]" : "[-1, 1]";
  text += "]\nequations = [";
  for (std::size_t i = 0; i < equations.size(); ++i)
    text += (i ? ", \"" : "\"") + equations[i] + "\"";
  text += "]\n";
  return parseProblem(text, "test_connection.toml");
}

/// Minimum-norm Newton x <- x - J^T (J J^T)^{-1} F(x) (a test-local projection).
template <class S>
ProjectedPoint<S> newton(const System<S>& system, std::span<S> x) {
  using std::abs;
  const int n = system.n(), m = system.m();
  const double tol = std::is_same_v<S, double> ? 1e-13 : 1e-30;
  std::vector<S> f(m), jac(std::size_t(m) * n), a(std::size_t(m) * m), y(m);
  ProjectedPoint<S> result;
  for (int it = 0; it < 60; ++it) {
    system.evaluate(std::span<const S>(x.data(), x.size()), f, jac);
    S worst = 0;
    for (int i = 0; i < m; ++i) worst = std::max<S>(worst, abs(f[i]));
    if (worst <= S(tol)) {
      result.converged = true;
      result.iterations = it;
      return result;
    }
    // J J^T y = F by Gaussian elimination with partial pivoting.
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        S s = 0;
        for (int t = 0; t < n; ++t) s += jac[std::size_t(i) * n + t] * jac[std::size_t(j) * n + t];
        a[std::size_t(i) * m + j] = s;
      }
    y = f;
    for (int c = 0; c < m; ++c) {
      int p = c;
      for (int r = c + 1; r < m; ++r)
        if (abs(a[std::size_t(r) * m + c]) > abs(a[std::size_t(p) * m + c])) p = r;
      if (a[std::size_t(p) * m + c] == 0) return result;
      for (int j = 0; j < m; ++j) std::swap(a[std::size_t(c) * m + j], a[std::size_t(p) * m + j]);
      std::swap(y[c], y[p]);
      for (int r = c + 1; r < m; ++r) {
        const S q = a[std::size_t(r) * m + c] / a[std::size_t(c) * m + c];
        for (int j = c; j < m; ++j) a[std::size_t(r) * m + j] -= q * a[std::size_t(c) * m + j];
        y[r] -= q * y[c];
      }
    }
    for (int c = m - 1; c >= 0; --c) {
      for (int j = c + 1; j < m; ++j) y[c] -= a[std::size_t(c) * m + j] * y[j];
      y[c] /= a[std::size_t(c) * m + c];
    }
    for (int t = 0; t < n; ++t) {
      S step = 0;
      for (int i = 0; i < m; ++i) step += jac[std::size_t(i) * n + t] * y[i];
      x[t] -= step;
      if (!(abs(x[t]) < S(1e3))) return result;
    }
  }
  return result;
}

/// Everything a connection needs, built without the subdivision stage.
template <class S>
struct Scene {
  Problem problem;
  System<S> system;
  SolutionCells cells;
  Projections<S> projections;
  std::vector<CellClass> classes;
  int k;

  Scene(Problem p, int depth) : problem(std::move(p)), system(problem), k(problem.k()) {
    cells.grid.n = problem.n();
    cells.grid.depth = depth;
    cells.grid.domain = problem.domain;
  }

  double h() const { return cells.grid.cellWidth(0); }

  /// Adds every cell whose closed box lies within `delta` of a sample (conservative, like
  /// the subdivision: no cell the manifold crosses is missed when delta covers the gaps).
  void addNear(const std::vector<Point>& samples, double delta) {
    const int n = cells.grid.n;
    const auto per = static_cast<std::int32_t>(cells.grid.cellsPerAxis());
    std::vector<std::int32_t> base(n), idx(n);
    int offsets = 1;
    for (int j = 0; j < n; ++j) offsets *= 3;
    for (const Point& y : samples) {
      for (int j = 0; j < n; ++j) {
        const double t = (y[j] - cells.grid.domain.lo[j]) / cells.grid.cellWidth(j);
        base[j] = static_cast<std::int32_t>(std::floor(t));
      }
      for (int o = 0; o < offsets; ++o) {
        int code = o;
        double d2 = 0;
        bool inside = true;
        for (int j = 0; j < n; ++j) {
          idx[j] = base[j] + code % 3 - 1;
          code /= 3;
          if (idx[j] < 0 || idx[j] >= per) {
            inside = false;
            break;
          }
          const double lo = cells.grid.cellLower(j, idx[j]);
          const double hi = lo + cells.grid.cellWidth(j);
          const double e = y[j] < lo ? lo - y[j] : (y[j] > hi ? y[j] - hi : 0.0);
          d2 += e * e;
        }
        if (!inside || d2 > delta * delta) continue;
        if (cells.find(cells.grid.pack(idx)) < 0) cells.add(idx);
      }
    }
  }

  /// Alg. 1: project every cell's centroid and classify it (normal: converged inside the
  /// closed cell; abnormal: converged outside; failed: no convergence).
  void projectAndClassify() {
    const int n = cells.grid.n;
    Box<S> domain{std::vector<S>(n), std::vector<S>(n)};
    for (int j = 0; j < n; ++j) {
      domain.lo[j] = S(cells.grid.domain.lo[j]);
      domain.hi[j] = S(cells.grid.domain.hi[j]);
    }
    projections.n = n;
    projections.point.assign(cells.size() * n, S(0));
    projections.converged.assign(cells.size(), 0);
    projections.iterations.assign(cells.size(), 0);
    classes.assign(cells.size(), CellClass::kFailed);
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const Box<S> box = cellBox<S>(cells.grid, domain, cells.cell(c));
      std::span<S> x(projections.point.data() + c * n, n);
      for (int j = 0; j < n; ++j) x[j] = (box.lo[j] + box.hi[j]) / 2;
      const auto r = newton<S>(system, x);
      projections.converged[c] = r.converged;
      projections.iterations[c] = r.iterations;
      if (!r.converged) continue;
      bool in = true;
      for (int j = 0; j < n; ++j) in = in && box.lo[j] <= x[j] && x[j] <= box.hi[j];
      classes[c] = in ? CellClass::kNormal : CellClass::kAbnormal;
    }
  }

  ConnectionInput<S> input() const {
    const System<S>* sys = &system;
    Projector<S> project = [sys](std::span<S> x) { return newton<S>(*sys, x); };
    return ConnectionInput<S>{problem, system, cells, projections, classes, project, k};
  }

  long count(CellClass c) const { return std::count(classes.begin(), classes.end(), c); }
};

/// Topology of a complex, computed here (independent of framework/analysis).
struct Topology {
  long vertices = 0, edges = 0, triangles = 0, components = 0;
  long openEnds = 0, branches = 0, boundaryEdges = 0, nonmanifoldEdges = 0;
  long euler() const { return vertices - edges + triangles; }
};

template <class S>
Topology topology(const Complex<S>& cx) {
  Topology t;
  const std::size_t nv = cx.vertexCount();
  std::vector<std::int32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::map<std::pair<int, int>, int> edges;
  std::vector<int> used(nv, 0);
  const int kk = cx.k;
  for (std::size_t s = 0; s < cx.simplexCount(); ++s) {
    const std::int32_t* v = cx.simplices.data() + s * (kk + 1);
    for (int i = 0; i <= kk; ++i) used[v[i]] = 1;
    for (int i = 0; i <= kk; ++i)
      for (int j = i + 1; j <= kk; ++j) {
        edges[{std::min(v[i], v[j]), std::max(v[i], v[j])}]++;
        parent[find(v[i])] = find(v[j]);
      }
  }
  t.triangles = kk == 2 ? static_cast<long>(cx.simplexCount()) : 0;
  t.edges = static_cast<long>(edges.size());
  std::vector<int> degree(nv, 0);
  for (const auto& [e, count] : edges) {
    ++degree[e.first];
    ++degree[e.second];
    if (count == 1) ++t.boundaryEdges;
    if (count >= 3) ++t.nonmanifoldEdges;
  }
  for (std::size_t v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    ++t.vertices;
    if (find(static_cast<std::int32_t>(v)) == static_cast<std::int32_t>(v)) ++t.components;
    if (kk == 1 && degree[v] == 1) ++t.openEnds;
    if (kk == 1 && degree[v] >= 3) ++t.branches;
  }
  return t;
}

/// An orthonormal basis of R^n (columns of a random rotation), fixed by `seed`.
std::vector<Point> rotation(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Point> q;
  while (static_cast<int>(q.size()) < n) {
    Point v(n);
    for (double& x : v) x = g(rng);
    for (const Point& u : q) {
      const double d = std::inner_product(v.begin(), v.end(), u.begin(), 0.0);
      for (int i = 0; i < n; ++i) v[i] -= d * u[i];
    }
    const double norm = std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0));
    if (norm < 1e-3) continue;
    for (double& x : v) x /= norm;
    q.push_back(v);
  }
  return q;
}

/// Circles of radius r in R^n: the plane through `centre` spanned by q[0], q[1] (rotated so
/// that it is not axis-aligned for n >= 3), intersected with the spheres around the centres
/// `centre + s q[0]` for the shifts s. Equations: the product of the sphere equations and the
/// n - 2 hyperplanes (x - centre) . q[j] = 0, j >= 2.
struct Circles {
  int n;
  Point centre;
  std::vector<Point> q;
  double r;
  std::vector<double> shifts;

  Problem problem() const {
    std::string spheres;
    for (double s : shifts) {
      std::string sphere;
      for (int i = 0; i < n; ++i)
        sphere +=
            (i ? " + (x" : "(x") + std::to_string(i) + " - " + num(centre[i] + s * q[0][i]) + ")^2";
      spheres += (spheres.empty() ? "(" : " * (") + sphere + " - " + num(r * r) + ")";
    }
    std::vector<std::string> eqs{spheres};
    for (int j = 2; j < n; ++j) {
      std::string plane;
      for (int i = 0; i < n; ++i)
        plane += (i ? " + " : "") + num(q[j][i]) + " * (x" + std::to_string(i) + " - " +
                 num(centre[i]) + ")";
      eqs.push_back(plane);
    }
    return makeProblem(n, eqs);
  }

  std::vector<Point> samples(double ds) const {
    std::vector<Point> out;
    const int count = static_cast<int>(std::ceil(2 * std::numbers::pi * r / ds));
    for (double s : shifts)
      for (int t = 0; t < count; ++t) {
        const double a = 2 * std::numbers::pi * t / count;
        Point p(n);
        for (int i = 0; i < n; ++i)
          p[i] = centre[i] + s * q[0][i] + r * (std::cos(a) * q[0][i] + std::sin(a) * q[1][i]);
        out.push_back(p);
      }
    return out;
  }
};

Circles circleIn(int n, unsigned seed, double r, std::vector<double> shifts = {0.0}) {
  Circles c{n, Point(n), n >= 3 ? rotation(n, seed) : rotation(2, 1), r, std::move(shifts)};
  if (n == 2) c.q = {{1, 0}, {0, 1}};
  std::mt19937 rng(seed + 100);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  for (double& x : c.centre) x = u(rng);
  return c;
}

/// Builds, projects and classifies the scene of a set of circles at grid depth L.
template <class S>
Scene<S> circleScene(const Circles& circles, int depth) {
  Scene<S> scene(circles.problem(), depth);
  const double ds = scene.h() / 16;
  scene.addNear(circles.samples(ds), 0.51 * ds);
  scene.projectAndClassify();
  return scene;
}

}  // namespace

//! [connection-names]
TEST_CASE("createConnection names and errors", "[connection]") {
  CHECK(std::holds_alternative<PaperConnection>(createConnection("paper")));
  CHECK(std::holds_alternative<NaiveConnection>(createConnection("naive")));
  CHECK(std::holds_alternative<CrossingConnection>(createConnection("crossing")));
  CHECK_THROWS_WITH(createConnection("x"),
                    "unknown connection strategy 'x' (known: paper, naive, crossing)");
  CHECK(connectionRegistry().names() == std::vector<std::string>{"paper", "naive", "crossing"});
  // Parameters reach the model.
  const Connection paper = createConnection("paper:extra_layers=2,thin_thick_normal=false");
  REQUIRE(std::holds_alternative<PaperConnection>(paper));
  CHECK(std::get<PaperConnection>(paper).options().extraLayers == 2);
  CHECK_FALSE(std::get<PaperConnection>(paper).options().thinThickNormal);
  CHECK(std::get<CrossingConnection>(createConnection("crossing:max_face_depth=16")).maxFaceDepth ==
        16);
  CHECK(std::get<CrossingConnection>(createConnection("crossing")).maxFaceDepth == 20);
}
//! [connection-names]

//! [paper-circle]
TEMPLATE_TEST_CASE("paper connection closes a circle in R^n", "[connection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const int n = GENERATE(2, 3, 4, 5, 6);
  const int depth = 5;
  const auto scene = circleScene<TestType>(circleIn(n, 7 + n, 0.62), depth);
  const auto out = connect(createConnection("paper"), scene.input());
  const Topology t = topology(out.complex);
  INFO("n = " << n << ", cells " << scene.cells.size() << " (normal "
              << scene.count(CellClass::kNormal) << ", abnormal "
              << scene.count(CellClass::kAbnormal) << ", failed " << scene.count(CellClass::kFailed)
              << "), V " << t.vertices << ", E " << t.edges << ", thick " << out.ambiguousCells);
  CHECK(scene.count(CellClass::kNormal) > 20);
  CHECK(t.components == 1);
  CHECK(t.openEnds == 0);
  CHECK(t.branches == 0);
  CHECK(t.vertices == t.edges);
  // Every vertex is a normal cell's point or a cluster centroid on M.
  for (std::size_t v = 0; v < out.complex.vertexCount(); ++v) {
    const auto cell = out.complex.vertexCell[v];
    if (cell >= 0) CHECK(scene.classes[cell] == CellClass::kNormal);
    CHECK(toDouble(scene.system.maxResidual(out.complex.vertex(v))) < 1e-10);
  }
}
//! [paper-circle]

TEMPLATE_TEST_CASE("paper connection keeps two circles apart", "[connection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const int n = GENERATE(2, 4);
  const auto scene = circleScene<TestType>(circleIn(n, 3 + n, 0.3, {-0.45, 0.45}), 5);
  const auto out = connect(createConnection("paper"), scene.input());
  const Topology t = topology(out.complex);
  INFO("n = " << n << ", abnormal " << scene.count(CellClass::kAbnormal));
  CHECK(t.components == 2);
  CHECK(t.openEnds == 0);
  CHECK(t.branches == 0);
  CHECK(t.vertices == t.edges);
}

//! [naive-thick]
TEMPLATE_TEST_CASE("naive connection is a thick volume", "[connection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  long thick = 0;
  for (int n : {2, 3, 4}) {
    const auto scene = circleScene<TestType>(circleIn(n, 7 + n, 0.62), 5);
    const auto out = connect(createConnection("naive"), scene.input());
    const Topology t = topology(out.complex);
    INFO("n = " << n << ": V " << t.vertices << ", E " << t.edges << ", branches " << t.branches);
    // Every solution cell is a vertex, normal or not.
    CHECK(out.complex.vertexCount() == scene.cells.size());
    if (t.branches > 0 || t.edges > t.vertices) ++thick;
  }
  CHECK(thick > 0);
}
//! [naive-thick]

//! [paper-grid-vertex]
TEMPLATE_TEST_CASE("paper connection bridges a circle through a grid vertex", "[connection]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  // (x - 0.05)^2 + (y + 0.1)^2 = 0.325 passes exactly through the grid vertex (0.5, 0.25) of
  // the 16 x 16 grid on [-1, 1]^2, crossing it diagonally: the two cells that only touch the
  // circle at that vertex are solution cells whose points land outside them (abnormal).
  Scene<TestType> scene(makeProblem(2, {"(x0 - 0.05)^2 + (x1 + 0.1)^2 - 0.325"}), 4);
  const double cx = 0.05, cy = -0.1, r2 = 0.325, eps = 1e-12;
  for (std::int32_t i = 0; i < 16; ++i)
    for (std::int32_t j = 0; j < 16; ++j) {
      const double lo[2] = {scene.cells.grid.cellLower(0, i), scene.cells.grid.cellLower(1, j)};
      const double hi[2] = {lo[0] + 0.125, lo[1] + 0.125};
      const double c[2] = {cx, cy};
      double dmin = 0, dmax = 0;
      for (int a = 0; a < 2; ++a) {
        const double e = c[a] < lo[a] ? lo[a] - c[a] : (c[a] > hi[a] ? c[a] - hi[a] : 0.0);
        const double f = std::max(std::abs(c[a] - lo[a]), std::abs(c[a] - hi[a]));
        dmin += e * e;
        dmax += f * f;
      }
      if (dmin <= r2 + eps && dmax >= r2 - eps) {
        const std::int32_t idx[2] = {i, j};
        scene.cells.add(idx);
      }
    }
  scene.projectAndClassify();
  // The cells (11, 9) and (12, 10) touch the circle only at the vertex (0.5, 0.25).
  const std::int32_t touchLow[2] = {11, 9}, touchHigh[2] = {12, 10};
  const auto low = scene.cells.find(scene.cells.grid.pack(touchLow));
  const auto high = scene.cells.find(scene.cells.grid.pack(touchHigh));
  REQUIRE(low >= 0);
  REQUIRE(high >= 0);
  CHECK(scene.classes[low] == CellClass::kAbnormal);
  CHECK(scene.classes[high] == CellClass::kAbnormal);

  const auto out = connect(createConnection("paper"), scene.input());
  const Topology t = topology(out.complex);
  INFO("abnormal " << scene.count(CellClass::kAbnormal) << ", V " << t.vertices << ", E "
                   << t.edges);
  CHECK(t.components == 1);
  CHECK(t.openEnds == 0);
  CHECK(t.branches == 0);
  CHECK(t.vertices == t.edges);
  // The bridge's centroid is a new vertex near the grid vertex.
  bool bridged = false;
  for (std::size_t v = 0; v < out.complex.vertexCount(); ++v) {
    if (out.complex.vertexCell[v] >= 0) continue;
    const auto p = out.complex.vertex(v);
    bridged = bridged || std::hypot(toDouble(p[0]) - 0.5, toDouble(p[1]) - 0.25) < 0.05;
  }
  CHECK(bridged);

  // Without classification the two touching cells make a 4-cycle: branch vertices.
  const Topology naive = topology(connect(createConnection("naive"), scene.input()).complex);
  CHECK(naive.branches > 0);
}
//! [paper-grid-vertex]

//! [paper-sphere]
TEMPLATE_TEST_CASE("paper connection on a sphere (k = 2)", "[connection]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const int depth = 4;
  const Point c{0.031, -0.017, 0.023};
  const double r = 0.63;
  Scene<TestType> scene(makeProblem(3, {"(x0 - " + num(c[0]) + ")^2 + (x1 - " + num(c[1]) +
                                        ")^2 + (x2 - " + num(c[2]) + ")^2 - " + num(r * r)}),
                        depth);
  // Fibonacci points on the sphere, spacing ~ h / 10.
  const double s = scene.h() / 10;
  const int count = static_cast<int>(4 * std::numbers::pi * r * r / (s * s));
  std::vector<Point> samples;
  for (int i = 0; i < count; ++i) {
    const double z = 1 - 2 * (i + 0.5) / count, rho = std::sqrt(1 - z * z);
    const double a = i * std::numbers::pi * (3 - std::sqrt(5.0));
    samples.push_back({c[0] + r * rho * std::cos(a), c[1] + r * rho * std::sin(a), c[2] + r * z});
  }
  scene.addNear(samples, s);
  scene.projectAndClassify();
  const auto out = connect(createConnection("paper"), scene.input());
  const Topology t = topology(out.complex);
  INFO("cells " << scene.cells.size() << " (normal " << scene.count(CellClass::kNormal)
                << ", abnormal " << scene.count(CellClass::kAbnormal) << "), V " << t.vertices
                << ", E " << t.edges << ", T " << t.triangles << ", chi " << t.euler()
                << ", boundary edges " << t.boundaryEdges << ", non-manifold edges "
                << t.nonmanifoldEdges << ", thick cells " << out.ambiguousCells);
  CHECK(t.components == 1);
  CHECK(t.triangles > 100);
}
//! [paper-sphere]

TEMPLATE_TEST_CASE("paper connection closes many circles", "[connection][slow]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  // Radii 0.35..0.62, n = 2..6, cell sets inflated by 0 or 0.5 cell widths (a more
  // conservative subdivision gives more abnormal cells).
  for (double inflate : {0.0, 0.5})
    for (int n = 2; n <= 6; ++n)
      for (unsigned seed = 0; seed < 10; ++seed) {
        const Circles circle = circleIn(n, 1000 + seed * 7 + n, 0.35 + 0.03 * seed);
        Scene<TestType> scene(circle.problem(), 4);
        const double ds = scene.h() / 16;
        scene.addNear(circle.samples(ds), 0.51 * ds + inflate * scene.h());
        scene.projectAndClassify();
        const Topology t = topology(connect(createConnection("paper"), scene.input()).complex);
        INFO("n = " << n << ", seed " << seed << ", inflate " << inflate << ", abnormal "
                    << scene.count(CellClass::kAbnormal));
        CHECK(t.components == 1);
        CHECK(t.openEnds == 0);
        CHECK(t.branches == 0);
      }
}
