// The subdivision stage (ZeroSetSubdiv, Alg. 1 step (1)) with the three bounding strategies and
// both subdivision strategies, against manifolds whose points are known in closed form.
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "applications/load.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/problem.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/subdivision/subdivision.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::CellKey;
using ndc::Grid;
using ndc::Problem;
using ndc::SolutionCells;

constexpr double kPi = 3.14159265358979323846;

/// A test manifold: its problem and a sampler of points exactly on it (up to double rounding).
struct Manifold {
  std::string name;
  Problem problem;
  std::function<std::vector<double>(std::mt19937&)> sample;
};

std::string tomlProblem(const std::string& name, int n, const std::vector<double>& lo,
                        const std::vector<double>& hi, const std::vector<std::string>& equations) {
  std::ostringstream s;
  s.precision(17);
  s << "name = \"" << name << "\"\nvariables = [";
  for (int j = 0; j < n; ++j) s << (j ? ", " : "") << "\"x" << j << "\"";
  s << "]\ndomain = [";
  for (int j = 0; j < n; ++j) s << (j ? ", " : "") << "[" << lo[j] << ", " << hi[j] << "]";
  s << "]\nequations = [";
  for (std::size_t i = 0; i < equations.size(); ++i)
    s << (i ? ", " : "") << "\"" << equations[i] << "\"";
  s << "]\n";
  return s.str();
}

double angle(std::mt19937& rng) { return std::uniform_real_distribution<double>(0, 2 * kPi)(rng); }

/// The unit circle in R^2 on an asymmetric domain (so no grid line is a symmetry axis).
Manifold circle2() {
  return {
      "circle2",
      ndc::parseProblem(tomlProblem("circle2", 2, {-1.25, -1.5}, {1.5, 1.375}, {"x0^2 + x1^2 - 1"}),
                        "circle2"),
      [](std::mt19937& rng) {
        const double t = angle(rng);
        return std::vector<double>{std::cos(t), std::sin(t)};
      }};
}

/// The unit sphere of R^n cut by the affine hyperplanes `a_i . x = d_i` (integer a_i, dyadic
/// d_i, so the problem text is exact): a circle with center c = A^T (A A^T)^-1 d in the plane
/// spanned by an orthonormal basis u, v of ker A, radius sqrt(1 - |c|^2).
Manifold sphereCut(const std::string& name, int n, const std::vector<std::vector<int>>& a,
                   const std::vector<double>& d, double lo, double hi) {
  const int planes = static_cast<int>(a.size());
  std::vector<std::string> equations;
  std::string sphere;
  for (int j = 0; j < n; ++j) sphere += (j ? " + x" : "x") + std::to_string(j) + "^2";
  equations.push_back(sphere + " - 1");
  Eigen::MatrixXd A(planes, n);
  Eigen::VectorXd D(planes);
  for (int i = 0; i < planes; ++i) {
    std::ostringstream e;
    e.precision(17);
    for (int j = 0; j < n; ++j) {
      A(i, j) = a[i][j];
      if (a[i][j] != 0) e << (a[i][j] < 0 ? " - " : " + ") << std::abs(a[i][j]) << "*x" << j;
    }
    D(i) = d[i];
    e << " - " << d[i];
    equations.push_back(e.str());
  }
  const Eigen::VectorXd c = A.transpose() * (A * A.transpose()).ldlt().solve(D);
  const Eigen::MatrixXd kernel = Eigen::FullPivLU<Eigen::MatrixXd>(A).kernel();
  REQUIRE(kernel.cols() == 2);
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(kernel).householderQ() *
                            Eigen::MatrixXd::Identity(n, 2);
  REQUIRE(c.norm() < 0.95);
  const double r = std::sqrt(1 - c.squaredNorm());
  std::vector<double> vlo(n, lo), vhi(n, hi);
  return {name, ndc::parseProblem(tomlProblem(name, n, vlo, vhi, equations), name),
          [c, q, r, n](std::mt19937& rng) {
            const double t = angle(rng);
            const Eigen::VectorXd p = c + r * (std::cos(t) * q.col(0) + std::sin(t) * q.col(1));
            return std::vector<double>(p.data(), p.data() + n);
          }};
}

Manifold circle3() { return sphereCut("circle3", 3, {{1, 1, 1}}, {0.5}, -1.25, 1.25); }

Manifold circle6() {
  return sphereCut(
      "circle6", 6,
      {{1, 1, 1, 1, 1, 1}, {1, -1, 2, 0, -1, 1}, {0, 1, -1, 2, 1, -2}, {2, 0, 1, -1, 0, 1}},
      {0.25, 0, 0.125, -0.25}, -1.125, 1.125);
}

Manifold circle8() {
  return sphereCut("circle8", 8,
                   {{1, 1, 1, 1, 1, 1, 1, 1},
                    {1, -1, 2, 0, -1, 1, 0, 1},
                    {0, 1, -1, 2, 1, -2, 1, 0},
                    {2, 0, 1, -1, 0, 1, -1, 1},
                    {1, 2, 0, 0, -1, -1, 2, -2},
                    {0, 0, 1, 1, 2, -1, -1, 1}},
                   {0.25, 0, 0.125, -0.25, 0.125, 0}, -1.125, 1.125);
}

/// The torus R = 1, r = 0.4: (x^2+y^2+z^2+0.84)^2 - 4(x^2+y^2) = 0.
Manifold torus() {
  return {"torus",
          ndc::parseProblem(tomlProblem("torus", 3, {-1.5, -1.5, -0.5}, {1.5, 1.5, 0.5},
                                        {"(x0^2 + x1^2 + x2^2 + 0.84)^2 - 4*(x0^2 + x1^2)"}),
                            "torus"),
          [](std::mt19937& rng) {
            const double u = angle(rng), v = angle(rng);
            const double rho = 1 + 0.4 * std::cos(v);
            return std::vector<double>{rho * std::cos(u), rho * std::sin(u), 0.4 * std::sin(v)};
          }};
}

/// The Clifford torus in R^4: x^2 + y^2 = z^2 + w^2 = 1/2.
Manifold clifford() {
  return {"clifford",
          ndc::parseProblem(
              tomlProblem("clifford", 4, std::vector<double>(4, -1), std::vector<double>(4, 1),
                          {"x0^2 + x1^2 - 0.5", "x2^2 + x3^2 - 0.5"}),
              "clifford"),
          [](std::mt19937& rng) {
            const double u = angle(rng), v = angle(rng), s = std::sqrt(0.5);
            return std::vector<double>{s * std::cos(u), s * std::sin(u), s * std::cos(v),
                                       s * std::sin(v)};
          }};
}

//! [subdivide-by-name]
template <class S>
SolutionCells solve(const Problem& problem, std::string_view bounding, std::string_view subdivision,
                    int depth, const ndc::Progress& progress = {}) {
  const ndc::Box<S> domain = problem.domainAs<S>();
  const Grid grid{problem.n(), depth, problem.domain};
  const ndc::Bounding<S> b = ndc::createBounding<S>(bounding, problem, domain);
  return ndc::subdivide<S>(b, ndc::createSubdivision(subdivision), grid, progress);
}
//! [subdivide-by-name]

std::set<CellKey> keys(const SolutionCells& cells) {
  std::set<CellKey> out;
  for (std::size_t c = 0; c < cells.size(); ++c) out.insert(cells.grid.pack(cells.cell(c)));
  return out;
}

/// Keys of every grid cell whose closed box contains p (several when p lies on a face).
std::vector<CellKey> containingCells(const Grid& grid, const std::vector<double>& p) {
  std::vector<std::vector<std::int32_t>> axes(grid.n);
  for (int j = 0; j < grid.n; ++j) {
    const auto i0 =
        static_cast<std::int32_t>(std::floor((p[j] - grid.domain.lo[j]) / grid.cellWidth(j)));
    for (std::int32_t i = i0 - 1; i <= i0 + 1; ++i)
      if (i >= 0 && i < grid.cellsPerAxis() && grid.cellLower(j, i) <= p[j] &&
          p[j] <= grid.cellLower(j, i + 1))
        axes[j].push_back(i);
  }
  std::vector<CellKey> out;
  std::vector<std::int32_t> index(grid.n);
  std::function<void(int)> product = [&](int j) {
    if (j == grid.n) {
      out.push_back(grid.pack(index));
      return;
    }
    for (std::int32_t i : axes[j]) {
      index[j] = i;
      product(j + 1);
    }
  };
  product(0);
  return out;
}

/// Cells hit by `samples` points of the manifold: a lower bound of the true cells.
std::set<CellKey> sampledCells(const Manifold& m, const Grid& grid, int samples) {
  std::mt19937 rng(7);
  std::set<CellKey> out;
  for (int s = 0; s < samples; ++s)
    for (CellKey key : containingCells(grid, m.sample(rng))) out.insert(key);
  return out;
}

/// Every sampled point of the manifold lies in solution cells only (conservativeness).
void checkConservative(const Manifold& m, const SolutionCells& cells, int samples) {
  std::mt19937 rng(2024);
  int missed = 0;
  for (int s = 0; s < samples; ++s) {
    const std::vector<double> p = m.sample(rng);
    for (CellKey key : containingCells(cells.grid, p))
      if (cells.find(key) < 0) ++missed;
  }
  CHECK(missed == 0);
}

/// Depths at which the generic tests run each manifold (kept small for Mpfr).
/// `loose` bounds the ratio of solution cells to the cells dense samples hit: the bounding
/// tests each F_i on its own, so in high codimension many boxes meet every zero set F_i = 0 but
/// not their intersection (circle6 at depth 3: about 60 times the true cells).
struct Case {
  Manifold manifold;
  int depth;
  double loose = 4;
};

template <class S>
std::vector<Case> cases() {
  // Mpfr is 10 to 50 times slower: one level less where it costs.
  const int less = std::is_same_v<S, double> ? 0 : 1;
  return {{circle2(), 6},
          {circle3(), 5},
          {torus(), 5 - less},
          {clifford(), 4},
          {circle6(), 3 - less, 100}};
}

}  // namespace

//! [subdivision-conservative]
TEMPLATE_TEST_CASE("subdivision keeps every cell the manifold meets", "[subdivision]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  for (const Case& c : cases<TestType>()) {
    for (const std::string& bounding : ndc::boundingRegistry().names()) {
      DYNAMIC_SECTION(c.manifold.name << " " << bounding) {
        const SolutionCells cells =
            solve<TestType>(c.manifold.problem, bounding, "binary", c.depth);
        CHECK(cells.grid.n == c.manifold.problem.n());
        CHECK(cells.grid.depth == c.depth);
        checkConservative(c.manifold, cells, 2000);
        // Not uselessly loose either: a bounded multiple of the cells dense samples hit.
        const std::size_t hit = sampledCells(c.manifold, cells.grid, 20000).size();
        INFO("solution cells " << cells.size() << ", cells hit by samples " << hit << ", visited "
                               << cells.visited);
        CHECK(cells.size() >= hit);
        CHECK(double(cells.size()) <= c.loose * double(hit));
      }
    }
  }
}
//! [subdivision-conservative]

namespace {

/// ZeroSetSubdiv as a plain recursion (the reference for subdivide's staged parallel
/// traversal): the solution cells' indices in depth-first order, lower child first, and the
/// count of bounded boxes.
template <class B, class D>
void referenceTraversal(const B& bounding, const D& subdivision, int n, int depth,
                        const typename B::State& state, int d, std::vector<std::int32_t>& index,
                        std::vector<std::int32_t>& cells, std::int64_t& visited) {
  if (subdivision.boundsAfter(d, n)) {
    ++visited;
    if (!bounding.mayContainZero(state)) return;
  }
  if (d == n * depth) {
    cells.insert(cells.end(), index.begin(), index.end());
    return;
  }
  const int axis = d % n;
  typename B::State lower, upper;
  bounding.halve(state, axis, lower, upper);
  index[axis] *= 2;
  referenceTraversal(bounding, subdivision, n, depth, lower, d + 1, index, cells, visited);
  ++index[axis];
  referenceTraversal(bounding, subdivision, n, depth, upper, d + 1, index, cells, visited);
  index[axis] /= 2;
}

}  // namespace

TEMPLATE_TEST_CASE(
    "the parallel traversal gives the depth-first traversal's cells, order and "
    "visited count",
    "[subdivision]", NDC_SCALARS) {
  // subdivide hands the top 3n halvings to tasks in stages of n (depth >= 4 has two stages or
  // more); on any number of threads the output must be the plain recursion's.
  ndc::test::PrecisionScope<TestType> scope(128);
  for (const Case& c : cases<TestType>()) {
    for (const char* bounding : {"bernstein", "linearized"}) {
      for (const char* subdivision : {"binary", "uniform"}) {
        DYNAMIC_SECTION(c.manifold.name << " " << bounding << " " << subdivision) {
          const Problem& problem = c.manifold.problem;
          const int n = problem.n();
          const ndc::Bounding<TestType> b =
              ndc::createBounding<TestType>(bounding, problem, problem.domainAs<TestType>());
          std::vector<std::int32_t> cells, index(static_cast<std::size_t>(n), 0);
          std::int64_t visited = 0;
          std::visit(
              [&](const auto& model, const auto& d) {
                typename std::decay_t<decltype(model)>::State root;
                model.root(root);
                referenceTraversal(model, d, n, c.depth, root, 0, index, cells, visited);
              },
              b, ndc::createSubdivision(subdivision));
          for (int threads : {1, 2, 3}) {
            const SolutionCells found = ndc::withThreads(
                threads, [&] { return solve<TestType>(problem, bounding, subdivision, c.depth); });
            INFO(threads << " threads: " << found.size() << " cells, visited " << found.visited
                         << "; reference " << cells.size() / n << ", " << visited);
            CHECK(found.index == cells);
            CHECK(found.visited == visited);
          }
        }
      }
    }
  }
}

//! [uniform-vs-binary]
TEMPLATE_TEST_CASE("uniform and binary subdivision give the same solution cells", "[subdivision]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  for (const Case& c : cases<TestType>()) {
    for (const char* bounding : {"bernstein", "interval"}) {
      DYNAMIC_SECTION(c.manifold.name << " " << bounding) {
        const SolutionCells uniform =
            solve<TestType>(c.manifold.problem, bounding, "uniform", c.depth);
        const SolutionCells binary =
            solve<TestType>(c.manifold.problem, bounding, "binary", c.depth);
        const int n = c.manifold.problem.n();
        INFO("cells " << uniform.size() << ", visited: uniform " << uniform.visited << ", binary "
                      << binary.visited);
        // Both bound the root and the final depth; binary also bounds every box in between, so
        // it can only discard more. For the Bernstein hull (a sub-box's coefficients are convex
        // combinations of its parent's) and the interval enclosures here they agree exactly.
        CHECK(keys(uniform) == keys(binary));
        // Uniform bounds the 2^n descendants of every surviving box of a round, binary the 2
        // children of every surviving box.
        CHECK((uniform.visited - 1) % (std::int64_t{1} << n) == 0);
        CHECK((binary.visited - 1) % 2 == 0);
        CHECK(static_cast<std::int64_t>(uniform.size()) <= uniform.visited);
        CHECK(static_cast<std::int64_t>(binary.size()) <= binary.visited);
      }
    }
  }
}
//! [uniform-vs-binary]

TEMPLATE_TEST_CASE("bernstein and interval bounding are both supersets of the true cells",
                   "[subdivision]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  for (const Case& c : cases<TestType>()) {
    DYNAMIC_SECTION(c.manifold.name) {
      const SolutionCells bernstein =
          solve<TestType>(c.manifold.problem, "bernstein", "binary", c.depth);
      const SolutionCells interval =
          solve<TestType>(c.manifold.problem, "interval", "binary", c.depth);
      const std::set<CellKey> hit = sampledCells(c.manifold, bernstein.grid, 20000);
      const std::set<CellKey> b = keys(bernstein), i = keys(interval);
      INFO("cells hit by samples " << hit.size() << ", bernstein " << b.size() << " (visited "
                                   << bernstein.visited << "), interval " << i.size()
                                   << " (visited " << interval.visited << ")");
      CHECK(std::includes(b.begin(), b.end(), hit.begin(), hit.end()));
      CHECK(std::includes(i.begin(), i.end(), hit.begin(), hit.end()));
    }
  }
}

TEMPLATE_TEST_CASE("no zeros in the domain gives no solution cells", "[subdivision]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  // x^2 + y^2 + 1 has no real zero; the unit circle misses [1.25, 2] x [0.5, 2]; the unit sphere
  // and the plane x + y + z = 2.5 (distance 1.44 from the origin) both cross the domain but
  // have no common zero.
  const std::vector<Problem> problems{
      ndc::parseProblem(tomlProblem("none", 2, {-1, -1}, {1, 1}, {"x0^2 + x1^2 + 1"}), "none"),
      ndc::parseProblem(tomlProblem("outside", 2, {1.25, 0.5}, {2, 2}, {"x0^2 + x1^2 - 1"}),
                        "outside"),
      ndc::parseProblem(tomlProblem("apart", 3, {-1.25, -1.25, -1.25}, {1.25, 1.25, 1.25},
                                    {"x0^2 + x1^2 + x2^2 - 1", "x0 + x1 + x2 - 2.5"}),
                        "apart")};
  for (const Problem& p : problems) {
    for (const std::string& bounding : ndc::boundingRegistry().names()) {
      for (const std::string& subdivision : ndc::subdivisionRegistry().names()) {
        DYNAMIC_SECTION(p.name << " " << bounding << " " << subdivision) {
          const SolutionCells cells = solve<TestType>(p, bounding, subdivision, 5);
          CHECK(cells.size() == 0);
          CHECK(cells.lookup.empty());
          CHECK(cells.visited >= 1);
          // The root is discarded where the enclosure on the domain is tight enough (the
          // Bernstein hull of x^2 + y^2 + 1 on [-1, 1]^2 is [-1, 3]).
          if (p.name == "outside" || (p.name == "none" && std::string(bounding) == "interval"))
            CHECK(cells.visited == 1);
        }
      }
    }
  }
}

TEMPLATE_TEST_CASE("solution cells scale like 2^(k L)", "[subdivision]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const bool mpfr = !std::is_same_v<TestType, double>;
  struct Scaling {
    Manifold manifold;
    int k, from, to;
  };
  // From depth 4 on: coarser grids are dominated by the overestimation of the bounds (interval
  // keeps all 512 cells of the torus at depth 3).
  const std::vector<Scaling> scalings{{circle2(), 1, 4, mpfr ? 7 : 9},
                                      {torus(), 2, 4, mpfr ? 5 : 6}};
  for (const Scaling& s : scalings) {
    for (const char* bounding : {"bernstein", "interval"}) {
      DYNAMIC_SECTION(s.manifold.name << " " << bounding) {
        std::size_t previous = 0;
        for (int depth = s.from; depth <= s.to; ++depth) {
          const std::size_t count =
              solve<TestType>(s.manifold.problem, bounding, "binary", depth).size();
          INFO("depth " << depth << ": " << count << " cells, previous " << previous);
          CHECK(count > 0);
          if (previous) {
            const double ratio = double(count) / double(previous), expected = std::ldexp(1.0, s.k);
            CHECK(ratio >= 0.7 * expected);
            CHECK(ratio <= 1.3 * expected);
          }
          previous = count;
        }
      }
    }
  }
}

TEST_CASE("double and mpfr give the same solution cells", "[subdivision][mpfr]") {
  ndc::test::PrecisionScope<ndc::Mpfr> scope(128);
  for (const Case& c : {Case{circle2(), 7}, Case{torus(), 4}, Case{clifford(), 4}}) {
    for (const char* bounding : {"bernstein", "interval"}) {
      for (const std::string& subdivision : ndc::subdivisionRegistry().names()) {
        DYNAMIC_SECTION(c.manifold.name << " " << bounding << " " << subdivision) {
          const SolutionCells d = solve<double>(c.manifold.problem, bounding, subdivision, c.depth);
          const SolutionCells m =
              solve<ndc::Mpfr>(c.manifold.problem, bounding, subdivision, c.depth);
          CHECK(keys(d) == keys(m));
          CHECK(d.visited == m.visited);
        }
      }
    }
  }
}

TEMPLATE_TEST_CASE("subdivision edge cases", "[subdivision]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const Manifold circle = circle2();
  SECTION("depth 0 is the root cell") {
    const SolutionCells cells = solve<TestType>(circle.problem, "bernstein", "binary", 0);
    REQUIRE(cells.size() == 1);
    CHECK(cells.cell(0)[0] == 0);
    CHECK(cells.cell(0)[1] == 0);
    CHECK(cells.visited == 1);
  }
  SECTION("cells are numbered consistently") {
    const SolutionCells cells = solve<TestType>(circle.problem, "bernstein", "uniform", 4);
    REQUIRE(cells.size() > 0);
    CHECK(cells.lookup.size() == cells.size());
    for (std::size_t c = 0; c < cells.size(); ++c) {
      CHECK(cells.find(cells.grid.pack(cells.cell(c))) == static_cast<std::int32_t>(c));
      for (std::int32_t i : cells.cell(c)) CHECK((i >= 0 && i < 16));
    }
  }
  SECTION("progress reports a growing share, at most about 100 times, ending at 1") {
    std::vector<double> fractions;
    const ndc::Progress progress = [&](const char* stage, double fraction) {
      CHECK(std::string(stage) == "subdivision");
      fractions.push_back(fraction);
    };
    solve<TestType>(circle.problem, "bernstein", "binary", 8, progress);
    REQUIRE(!fractions.empty());
    CHECK(fractions.size() <= 101);
    CHECK(std::is_sorted(fractions.begin(), fractions.end()));
    CHECK(fractions.front() >= 0.0);
    CHECK(fractions.back() == 1.0);
  }
  SECTION("a grid beyond a CellKey is an input error") {
    const ndc::Box<TestType> domain = circle.problem.domainAs<TestType>();
    const auto bounding = ndc::createBounding<TestType>("bernstein", circle.problem, domain);
    CHECK_THROWS_AS(ndc::subdivide<TestType>(bounding, ndc::UniformSubdivision{},
                                             Grid{2, 31, circle.problem.domain}),
                    ndc::InputError);
    const Problem five = ndc::parseProblem(
        tomlProblem("five", 5, std::vector<double>(5, -1), std::vector<double>(5, 1),
                    {"x0^2 + x1^2 + x2^2 + x3^2 + x4^2 - 1"}),
        "five");
    const auto b5 = ndc::createBounding<TestType>("interval", five, five.domainAs<TestType>());
    CHECK_THROWS_AS(
        ndc::subdivide<TestType>(b5, ndc::BinarySubdivision{}, Grid{5, 26, five.domain}),
        ndc::InputError);
  }
}

TEST_CASE("cell keys pack and unpack every grid that fits, past 64 bits", "[subdivision]") {
  // Seeded random multi-indices on grids of n * depth up to 128 bits: pack then unpack gives
  // the index back, neighbours are the keys of the shifted indices, distinct indices give
  // distinct keys, and the hash of a key below 2^64 is the key (as before the 128-bit keys).
  std::mt19937_64 rng(20261203);
  for (const auto& [n, depth] : std::vector<std::pair<int, int>>{
           {2, 30}, {3, 21}, {3, 22}, {8, 8}, {8, 9}, {8, 16}, {20, 6}, {30, 4}, {64, 2}}) {
    INFO("n = " << n << ", depth = " << depth);
    REQUIRE(Grid::fits(n, depth));
    const Grid grid{n, depth,
                    ndc::Box<double>{std::vector<double>(n, -1), std::vector<double>(n, 1)}};
    std::uniform_int_distribution<std::int32_t> pick(0, std::int32_t(grid.cellsPerAxis() - 1));
    std::set<CellKey> seen;
    std::set<std::vector<std::int32_t>> indices;
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<std::int32_t> index(n), back(n);
      for (auto& i : index) i = pick(rng);
      const CellKey key = grid.pack(index);
      grid.unpack(key, back);
      CHECK(back == index);
      const int axis = trial % n;
      if (index[axis] + 1 < grid.cellsPerAxis()) {
        std::vector<std::int32_t> up = index;
        ++up[axis];
        CHECK(grid.neighbour(key, axis, +1) == grid.pack(up));
        CHECK(grid.neighbour(grid.pack(up), axis, -1) == key);
      }
      seen.insert(key);
      indices.insert(index);
    }
    CHECK(seen.size() == indices.size());
  }
  CHECK(ndc::CellKeyHash{}(CellKey{123456789}) == std::size_t{123456789});
  CHECK_FALSE(Grid::fits(8, 17));
  CHECK_FALSE(Grid::fits(30, 5));
  CHECK_FALSE(Grid::fits(65, 1));
  CHECK(Grid::deepestFor(8) == 16);
  CHECK(Grid::deepestFor(3) == 30);
}

//! [strategy-names]
TEST_CASE("unknown strategy names are usage errors", "[subdivision]") {
  const Manifold circle = circle2();
  const ndc::Box<double> domain = circle.problem.domainAs<double>();
  CHECK_THROWS_AS(ndc::createBounding<double>("bernstien", circle.problem, domain),
                  ndc::UsageError);
  CHECK_THROWS_WITH(ndc::createBounding<double>("x", circle.problem, domain),
                    "unknown bounding strategy 'x' (known: bernstein, interval, linearized)");
  CHECK_THROWS_AS(ndc::createSubdivision("octree"), ndc::UsageError);
  CHECK_THROWS_WITH(ndc::createSubdivision("x"),
                    "unknown subdivision strategy 'x' (known: uniform, binary)");
  for (const std::string& name : ndc::boundingRegistry().names())
    CHECK_NOTHROW(ndc::createBounding<double>(name, circle.problem, domain));
  for (const std::string& name : ndc::subdivisionRegistry().names())
    CHECK_NOTHROW(ndc::createSubdivision(name));
  CHECK(std::holds_alternative<ndc::LinearizedBounding<double>>(
      ndc::createBounding<double>("linearized", circle.problem, domain)));
  CHECK(std::holds_alternative<ndc::UniformSubdivision>(ndc::createSubdivision("uniform")));
  CHECK(std::holds_alternative<ndc::BinarySubdivision>(ndc::createSubdivision("binary")));
}
//! [strategy-names]

TEST_CASE("deeper subdivisions stay conservative and strategy-independent", "[subdivision][slow]") {
  for (const Case& c : {Case{torus(), 7}, Case{clifford(), 6}, Case{circle6(), 5, 200}}) {
    DYNAMIC_SECTION(c.manifold.name << " depth " << c.depth) {
      const SolutionCells binary =
          solve<double>(c.manifold.problem, "bernstein", "binary", c.depth);
      const SolutionCells uniform =
          solve<double>(c.manifold.problem, "bernstein", "uniform", c.depth);
      INFO("cells " << binary.size() << ", visited: binary " << binary.visited << ", uniform "
                    << uniform.visited);
      checkConservative(c.manifold, binary, 20000);
      CHECK(keys(binary) == keys(uniform));
    }
  }
}

// --- The linearized bounding
// ----------------------------------------------------------------------

/// A generated k-sphere (k = 1: a circle, k = 2: a 2-sphere) in R^n: radius r about c in the
/// (k + 1)-flat spanned by the first k + 1 columns of a random orthogonal Q (seeded), the other
/// n - k - 1 directions fixed by affine equations; or, `aligned`, the unit k-sphere of the first
/// k + 1 coordinates (x_j = 0 beyond them: on grid planes of every depth, as people write it).
Manifold generatedSphere(int n, int k, unsigned seed, bool aligned) {
  std::mt19937 rng(seed);
  Eigen::MatrixXd q = Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
  double r = 1;
  if (!aligned) {
    Eigen::MatrixXd g(n, n);
    std::normal_distribution<double> normal;
    for (int i = 0; i < n * n; ++i) g.data()[i] = normal(rng);
    q = Eigen::HouseholderQR<Eigen::MatrixXd>(g).householderQ();
    for (int j = 0; j < n; ++j) c(j) = std::uniform_real_distribution<double>(-0.1, 0.1)(rng);
    r = std::uniform_real_distribution<double>(0.6, 0.9)(rng);
  }
  // y_i = q_i . (x - c), as exact text of the double coefficients.
  const auto y = [&](int i) {
    std::ostringstream e;
    e.precision(17);
    e << "(";
    for (int j = 0; j < n; ++j) e << (j ? " + " : "") << q(j, i) << "*x" << j;
    e << " + " << -q.col(i).dot(c) << ")";
    return e.str();
  };
  std::vector<std::string> equations;
  std::string sphere;
  for (int i = 0; i <= k; ++i) sphere += (i ? " + " : "") + y(i) + "^2";
  std::ostringstream radius;
  radius.precision(17);
  radius << r * r;
  equations.push_back(sphere + " - " + radius.str());
  for (int i = k + 1; i < n; ++i) equations.push_back(y(i));
  const std::string name = std::string(aligned ? "aligned" : "rotated") + "-" + std::to_string(k) +
                           "-sphere-n" + std::to_string(n);
  return {name,
          ndc::parseProblem(tomlProblem(name, n, std::vector<double>(n, -1.25),
                                        std::vector<double>(n, 1.25), equations),
                            name),
          [q, c, r, n, k](std::mt19937& g) {
            // A uniform point of the unit k-sphere, then into the flat.
            std::normal_distribution<double> normal;
            Eigen::VectorXd u(k + 1);
            for (int i = 0; i <= k; ++i) u(i) = normal(g);
            u /= u.norm();
            const Eigen::VectorXd p = c + r * q.leftCols(k + 1) * u;
            return std::vector<double>(p.data(), p.data() + n);
          }};
}

TEMPLATE_TEST_CASE("linearized subdivision keeps every cell of generated circles and spheres",
                   "[subdivision]", NDC_SCALARS) {
  // Rotated (seeded) and coordinate-aligned circles and 2-spheres in R^4..R^7: the linearized
  // test, and the halves its test of a box shows empty (whose children are discarded untested),
  // must keep every cell a sample point of the manifold lies in; the aligned ones lie on grid
  // planes, where both cells beside a plane hold points. Mpfr: R^4 and R^5 only.
  ndc::test::PrecisionScope<TestType> scope(128);
  const int top = std::is_same_v<TestType, double> ? 7 : 5;
  for (int n = 4; n <= top; ++n)
    for (int k = 1; k <= 2; ++k)
      for (int variant = 0; variant < 3; ++variant) {
        const Manifold m = generatedSphere(n, k, 100 * n + 10 * k + variant, variant == 2);
        const int depth = n <= 5 ? 4 : 3;
        DYNAMIC_SECTION(m.name << " seed variant " << variant) {
          const SolutionCells cells = solve<TestType>(m.problem, "linearized", "binary", depth);
          INFO("solution cells " << cells.size() << ", visited " << cells.visited);
          CHECK(cells.size() > 0);
          checkConservative(m, cells, 3000);
        }
      }
}

TEMPLATE_TEST_CASE("linearized bounding carries points of the manifold down to the boxes",
                   "[subdivision]", NDC_SCALARS) {
  // The whole binary subdivision of rotated circles and 2-spheres in R^4..R^7 (Mpfr: R^4 and
  // R^5) to depth 3, by hand: every point a child takes along (State::point) must lie in the
  // child by its error, be a zero of the system to rounding, and the boxes that hold one are
  // kept without a test; points must reach most of the final boxes that samples of M hit.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  using State = typename ndc::LinearizedBounding<S>::State;
  const int top = std::is_same_v<S, double> ? 7 : 5;
  std::mt19937 rng(43);
  for (int n = 4; n <= top; ++n)
    for (int k = 1; k <= 2; ++k) {
      const Manifold m = generatedSphere(n, k, 700 + 10 * n + k, false);
      const ndc::Box<S> domain = m.problem.domainAs<S>();
      const ndc::LinearizedBounding<S> bounding(m.problem, domain);
      const ndc::System<S> system(m.problem);
      const int depth = 3 * n;
      std::vector<std::pair<State, State>> children(std::size_t(depth) + 1);
      std::vector<S> f(system.m());
      int points = 0, bad = 0, finalWithPoint = 0;
      std::set<std::vector<double>> finalPointBoxes;  // lower corners, of final boxes
      const std::function<void(const State&, int)> descend = [&](const State& state, int d) {
        if (d == depth) {
          if (state.hasPoint) {
            ++finalWithPoint;
            std::vector<double> corner;
            for (const S& v : state.box.lo) corner.push_back(ndc::toDouble(v));
            finalPointBoxes.insert(corner);
          }
          return;
        }
        auto& [lower, upper] = children[std::size_t(d) + 1];
        bounding.halve(state, d % n, lower, upper);
        for (State* child : {&lower, &upper}) {
          if (child->hasPoint) {
            ++points;
            system.evaluate(std::span<const S>(child->point), std::span<S>(f));
            for (int j = 0; j < n; ++j) {
              bad += !(child->point[j] - child->pointError >= child->box.lo[j] &&
                       child->point[j] + child->pointError <= child->box.hi[j]);
            }
            for (const S& v : f) bad += !(std::abs(ndc::toDouble(v)) < 1e-12);
            bad += !(child->pointError < S(1e-8) * (child->box.hi[0] - child->box.lo[0]));
            CHECK(bounding.mayContainZero(*child));
          }
          if (bounding.mayContainZero(*child)) descend(*child, d + 1);
        }
      };
      State root;
      bounding.root(root);
      if (bounding.mayContainZero(root)) descend(root, 0);
      // The final boxes that samples of M hit, away from their faces.
      int hit = 0, hitWithPoint = 0;
      for (int s = 0; s < 2000; ++s) {
        const std::vector<double> p = m.sample(rng);
        std::vector<double> corner(n);
        bool interior = true;
        for (int j = 0; j < n; ++j) {
          const double lo = ndc::toDouble(domain.lo[j]);
          const double w = (ndc::toDouble(domain.hi[j]) - lo) / 8;
          const double t = (p[j] - lo) / w;
          interior = interior && t - std::floor(t) > 0.01 && t - std::floor(t) < 0.99;
          corner[j] = lo + std::floor(t) * w;
        }
        if (!interior) continue;
        ++hit;
        hitWithPoint += finalPointBoxes.count(corner) > 0;
      }
      INFO(m.name << ": " << points << " points carried, " << finalWithPoint
                  << " final boxes with one; of " << hit << " samples, " << hitWithPoint
                  << " in such a box");
      CHECK(bad == 0);
      CHECK(points > 10 * n);
      CHECK(hitWithPoint > hit / 4);
    }
}

TEMPLATE_TEST_CASE("linearized bounding is conservative and inside bernstein's cells",
                   "[subdivision]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const bool mpfr = !std::is_same_v<TestType, double>;
  // circle8 in addition (linearized only: bernstein keeps ~14000 cells there at depth 3).
  // Mpfr halves the 3^8 coefficients of the sphere's patch too slowly for it.
  std::vector<Case> all = cases<TestType>();
  if (!mpfr) all.push_back({circle8(), 4, 100});
  for (const Case& c : all) {
    for (const char* subdivision : {"binary", "uniform"}) {
      if (c.manifold.name == "circle8" && std::string(subdivision) == "uniform") continue;
      DYNAMIC_SECTION(c.manifold.name << " " << subdivision) {
        const SolutionCells lin =
            solve<TestType>(c.manifold.problem, "linearized", subdivision, c.depth);
        checkConservative(c.manifold, lin, 2000);
        const std::set<CellKey> l = keys(lin);
        const std::set<CellKey> hit = sampledCells(c.manifold, lin.grid, 20000);
        CHECK(std::includes(l.begin(), l.end(), hit.begin(), hit.end()));
        INFO("linearized " << l.size() << " cells (visited " << lin.visited << "), hit "
                           << hit.size());
        if (c.manifold.name != "circle8") {
          const SolutionCells bern =
              solve<TestType>(c.manifold.problem, "bernstein", subdivision, c.depth);
          const std::set<CellKey> b = keys(bern);
          INFO("bernstein " << b.size() << " cells (visited " << bern.visited << ")");
          // The Bernstein hulls run first, so linearized only removes cells.
          CHECK(std::includes(b.begin(), b.end(), l.begin(), l.end()));
          CHECK(lin.visited <= bern.visited);
          // m = 1 (circle2, torus) and equations in disjoint variables (clifford): the
          // simultaneous test is off and linearized is bernstein.
          if (c.manifold.name == "circle2" || c.manifold.name == "torus" ||
              c.manifold.name == "clifford") {
            CHECK(l == b);
            CHECK(lin.visited == bern.visited);
          }
        }
        // Close to the true cells once the cells are small enough for the linearisation
        // (circle6 at depth 3: 3.5 times the cells samples hit, circle8 at depth 4: 3.1; at
        // depth 2, 7 and 17 times).
        if (c.depth >= 3) CHECK(double(l.size()) <= 5.0 * double(hit.size()));
      }
    }
  }
}

//! [linearized-tighter]
TEST_CASE("linearized bounding is much tighter on the circle in R^6", "[subdivision]") {
  // Measured (binary): depth 3: bernstein 2505 cells (23647 visited), linearized 146 (3441),
  // i.e. 17x fewer cells; depth 4: 5534 (77387) against 170 (6091), 33x.
  const Manifold c = circle6();
  for (int depth : {3, 4}) {
    DYNAMIC_SECTION("depth " << depth) {
      const SolutionCells bern = solve<double>(c.problem, "bernstein", "binary", depth);
      const SolutionCells lin = solve<double>(c.problem, "linearized", "binary", depth);
      INFO("bernstein " << bern.size() << " cells (visited " << bern.visited << "), linearized "
                        << lin.size() << " (visited " << lin.visited << ")");
      CHECK(double(bern.size()) >= 10.0 * double(lin.size()));
      CHECK(double(bern.visited) >= 5.0 * double(lin.visited));
    }
  }
}
//! [linearized-tighter]

TEST_CASE("linearized test never discards a box around a point of the manifold", "[subdivision]") {
  // Boxes of widths from 1 down to 1e-13 around sampled points of the circles in R^6 and R^8,
  // with the point at the centre, at a corner and on a face: rounding must not discard them,
  // neither the simultaneous test nor (R^8: the sphere has 3^8 coefficients, no patch) the
  // mean-value test of an equation without a Bernstein patch.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const Manifold& m : {circle3(), circle6(), circle8()}) {
    DYNAMIC_SECTION(m.name) {
      const ndc::Box<double> domain = m.problem.domainAs<double>();
      const ndc::LinearizedBounding<double> bounding(m.problem, domain);
      const int n = m.problem.n();
      int excluded = 0, boxes = 0;
      for (int s = 0; s < 300; ++s) {
        const std::vector<double> p = m.sample(rng);
        for (double width = 1; width > 1e-13; width /= 7) {
          ndc::Box<double> box{std::vector<double>(n), std::vector<double>(n)};
          for (int j = 0; j < n; ++j) {
            // Position of the point inside the box along axis j: 0 (face), 1 (face) or random.
            const double t = s % 3 == 0 ? unit(rng) : double((s / 3 + j) % 2);
            box.lo[j] = p[j] - t * width;
            box.hi[j] = box.lo[j] + width;
            if (box.hi[j] < p[j]) box.hi[j] = p[j];
            if (box.lo[j] > p[j]) box.lo[j] = p[j];
          }
          ++boxes;
          excluded += bounding.linearizationExcludes(box) || bounding.meanValueExcludes(box);
        }
      }
      INFO(boxes << " boxes");
      CHECK(excluded == 0);
      // And it does discard: a small box 0.05 per axis away from a point of the circle.
      const std::vector<double> p = m.sample(rng);
      ndc::Box<double> off{p, p};
      for (int j = 0; j < n; ++j) {
        off.lo[j] = p[j] + 0.05 * (j % 2 ? 1 : -1) - 1e-3;
        off.hi[j] = off.lo[j] + 2e-3;
      }
      CHECK(bounding.linearizationExcludes(off));
      // Which equations have a patch: the sphere only up to R^6, the hyperplanes never (their
      // range is exact from the constant gradient).
      for (const ndc::Expression& e : m.problem.equations) {
        const bool affine = e.tape().totalDegree(2) <= 1;
        CHECK(ndc::LinearizedBounding<double>::hasPatch(e) == (!affine && n <= 6));
      }
      // The mean-value test discards a box where only the sphere excludes 0: a small box at
      // the mean of points of the circle, which lies on every hyperplane and inside the sphere.
      std::vector<double> mean(n, 0.0);
      for (int s = 0; s < 64; ++s) {
        const std::vector<double> q = m.sample(rng);
        for (int j = 0; j < n; ++j) mean[j] += q[j] / 64;
      }
      ndc::Box<double> centre{mean, mean};
      for (int j = 0; j < n; ++j) centre.lo[j] -= 1e-3, centre.hi[j] += 1e-3;
      CHECK(bounding.meanValueExcludes(centre) == (n > 6));
    }
  }
}

TEST_CASE("double and mpfr linearized bounding agree", "[subdivision][mpfr]") {
  ndc::test::PrecisionScope<ndc::Mpfr> scope(128);
  for (const Case& c : {Case{circle3(), 5}, Case{circle6(), 3}}) {
    DYNAMIC_SECTION(c.manifold.name) {
      const SolutionCells d = solve<double>(c.manifold.problem, "linearized", "binary", c.depth);
      const SolutionCells m = solve<ndc::Mpfr>(c.manifold.problem, "linearized", "binary", c.depth);
      INFO("double " << d.size() << ", mpfr " << m.size());
      CHECK(keys(d) == keys(m));
    }
  }
}

// Timings for the report (hidden: run with ./ndcontour_tests "[subdivision-timing]").
TEST_CASE("subdivision timings", "[.][subdivision-timing]") {
  struct Timing {
    Manifold manifold;
    int depth;
  };
  // circle8 beyond depth 3 takes minutes: the per-equation hulls keep ~45000 cells at depth 3.
  for (const Timing& t :
       {Timing{torus(), 6}, Timing{clifford(), 6}, Timing{circle6(), 6}, Timing{circle8(), 3}}) {
    for (const std::string& bounding : ndc::boundingRegistry().names()) {
      for (const char* subdivision : {"binary", "uniform"}) {
        const auto start = std::chrono::steady_clock::now();
        const SolutionCells cells =
            solve<double>(t.manifold.problem, bounding, subdivision, t.depth);
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%-9s L=%d %-9s %-7s double: %8zu cells %10lld visited %8.3f s\n",
                    t.manifold.name.c_str(), t.depth, bounding.c_str(), subdivision, cells.size(),
                    static_cast<long long>(cells.visited), seconds);
      }
    }
  }
}

TEMPLATE_TEST_CASE("linearized bounding decides boxes around 2-flats exactly", "[subdivision]",
                   NDC_SCALARS) {
  // Generated 2-flats in R^4..R^8: n - 2 hyperplanes with integer coefficients in [-3, 3]
  // through a point q of the 1/64 grid (every literal exact, so the linearization is the flat
  // itself up to rounding), and boxes of dyadic widths at dyadic offsets from q. The truth
  // comes from the flat's parametrisation x = q + U t: the box is 2 n half-planes in the plane
  // of t, and the flat meets it iff some point where two of their lines cross satisfies all of
  // them. Boxes the flat meets with the half-planes tightened by 1e-7 w must be kept, boxes it
  // misses with them loosened by as much must be discarded: the planar kernel test (k = 2) is
  // exact, where propagating the constraints over boxes of t leaves corners undecided.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(29);
  std::uniform_int_distribution<int> coefficient(-3, 3), grid(-64, 64), offset(-12, 4);
  int kept = 0, discarded = 0;
  for (int n = 4; n <= 8; ++n) {
    for (int flat = 0; flat < 8; ++flat) {
      std::vector<double> q(n);
      for (double& v : q) v = grid(rng) / 64.0;
      Eigen::MatrixXd a(n - 2, n);
      std::vector<std::string> equations;
      for (int i = 0; i < n - 2; ++i) {
        double c = 0;
        std::ostringstream e;
        e.precision(17);
        for (int j = 0; j < n; ++j) {
          a(i, j) = coefficient(rng);
          e << (j ? " + " : "") << "(" << a(i, j) << ")*x" << j;
          c -= a(i, j) * q[j];
        }
        e << " + (" << c << ")";
        equations.push_back(e.str());
      }
      const Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
      if (lu.rank() < n - 2) continue;
      const Eigen::MatrixXd u = lu.kernel();  // n x 2
      const Problem problem = ndc::test::makeProblem(n, equations, 2);
      const ndc::LinearizedBounding<S> bounding(problem, problem.domainAs<S>());
      for (int trial = 0; trial < 60; ++trial) {
        const double w = std::ldexp(1.0, -3 - 2 * static_cast<int>(rng() % 3));
        std::vector<double> lo(n), hi(n);
        for (int j = 0; j < n; ++j) lo[j] = q[j] + w * offset(rng) / 8, hi[j] = lo[j] + w;
        // Whether the flat meets the box with its half-planes moved out by `slack`.
        const auto meets = [&](double slack) {
          // Half-planes g . t <= r: U_j t <= hi_j - q_j + slack, -U_j t <= q_j - lo_j + slack.
          std::vector<Eigen::Vector2d> g;
          std::vector<double> r;
          for (int j = 0; j < n; ++j) {
            g.emplace_back(u(j, 0), u(j, 1)), r.push_back(hi[j] - q[j] + slack);
            g.emplace_back(-u(j, 0), -u(j, 1)), r.push_back(q[j] - lo[j] + slack);
          }
          const auto inside = [&](const Eigen::Vector2d& t) {
            for (std::size_t h = 0; h < g.size(); ++h) {
              if (g[h].dot(t) > r[h] + 1e-12) return false;
            }
            return true;
          };
          for (std::size_t h = 0; h < g.size(); ++h) {
            for (std::size_t l = h + 1; l < g.size(); ++l) {
              Eigen::Matrix2d m;
              m << g[h].transpose(), g[l].transpose();
              if (std::abs(m.determinant()) < 1e-12) continue;
              if (inside(m.inverse() * Eigen::Vector2d(r[h], r[l]))) return true;
            }
          }
          return false;
        };
        const double margin = 1e-7 * w;
        const bool surely = meets(-margin), maybe = meets(margin);
        if (surely != maybe) continue;  // within the margin of touching: no robust answer
        ndc::Box<S> box{std::vector<S>(n), std::vector<S>(n)};
        for (int j = 0; j < n; ++j) box.lo[j] = S(lo[j]), box.hi[j] = S(hi[j]);
        INFO("n = " << n << ", flat " << flat << ", trial " << trial);
        CHECK(bounding.linearizationExcludes(box) == !surely);
        ++(surely ? kept : discarded);
      }
    }
  }
  CHECK(kept >= 100);
  CHECK(discarded >= 100);
}

TEMPLATE_TEST_CASE("linearized bounding discards boxes off the flat of a 2-sphere's hyperplanes",
                   "[subdivision]", NDC_SCALARS) {
  // Generated rotated 2-spheres in R^5..R^8, as `ndcontour experiment`'s rotated-sphere
  // generator writes them: y = R (x - q) with R a random orthogonal matrix, the sphere
  // y_0^2 + y_1^2 + y_2^2 = 1 and the n - 3 hyperplanes y_i = 0, i >= 3, which alone meet a box
  // iff their 3-flat x = q + U t (U the first three columns of R^T) does: a polytope in t,
  // nonempty iff one of its candidate vertices (three of the 2 n planes U_j t = bounds)
  // satisfies all 2 n constraints. Near the sphere, a box the flat misses by 5% of its width
  // must be discarded, although the sphere's remainder over the box is large and every row of
  // the orthonormalised system mixes it in (the multiplier test: before it, 70% of such boxes
  // were kept); a box around a point of the sphere must never be.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(41);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit(0, 1);
  int kept = 0, discarded = 0;
  for (int n = 5; n <= 8; ++n) {
    for (int sphere = 0; sphere < 4; ++sphere) {
      Eigen::MatrixXd g(n, n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) g(i, j) = gauss(rng);
      const Eigen::MatrixXd r = g.householderQr().householderQ();  // rows: the axes y_i
      Eigen::VectorXd q(n);
      for (int j = 0; j < n; ++j) q(j) = 0.1 * (2 * unit(rng) - 1);
      const auto axis = [&](int i) {  // y_i = R_i . x - R_i . q as text
        std::ostringstream e;
        e.precision(17);
        e << "(";
        for (int j = 0; j < n; ++j) e << (j ? " + " : "") << "(" << r(i, j) << ")*x" << j;
        e << " + (" << -r.row(i).dot(q) << "))";
        return e.str();
      };
      std::vector<std::string> equations{axis(0) + "^2 + " + axis(1) + "^2 + " + axis(2) +
                                         "^2 - 1"};
      for (int i = 3; i < n; ++i) equations.push_back(axis(i));
      const Eigen::MatrixXd u = r.topRows(3).transpose();              // the flat's directions
      const Eigen::MatrixXd normal = r.bottomRows(n - 3).transpose();  // its normals
      const Problem problem = ndc::test::makeProblem(n, equations, 2);
      const ndc::LinearizedBounding<S> bounding(problem, problem.domainAs<S>());
      const auto toBox = [&](const std::vector<double>& lo, double w) {
        ndc::Box<S> box{std::vector<S>(n), std::vector<S>(n)};
        for (int j = 0; j < n; ++j) box.lo[j] = S(lo[j]), box.hi[j] = S(lo[j] + w);
        return box;
      };
      const auto spherePoint = [&] {
        Eigen::Vector3d t(gauss(rng), gauss(rng), gauss(rng));
        return Eigen::VectorXd(q + u * t.normalized());
      };
      for (int trial = 0; trial < 300; ++trial) {
        // A point of the sphere moved along a random normal of the flat by 0.05 to 1 width,
        // at a random place in a box of width 2.6 / 2^4 .. 2.6 / 2^6 (the per-cell depths).
        const double w = 2.6 * std::ldexp(1.0, -4 - static_cast<int>(rng() % 3));
        Eigen::VectorXd v(n - 3);
        for (int i = 0; i < n - 3; ++i) v(i) = gauss(rng);
        const Eigen::VectorXd p =
            spherePoint() + normal * v.normalized() * (w * (0.05 + 0.95 * unit(rng)));
        std::vector<double> lo(n);
        for (int j = 0; j < n; ++j) lo[j] = p(j) - unit(rng) * w;
        // Whether the flat meets the box with every face moved out by `slack`.
        const auto meets = [&](double slack) {
          std::vector<Eigen::Vector3d> dir;
          std::vector<double> bound;
          for (int j = 0; j < n; ++j) {
            const Eigen::Vector3d row = u.row(j).transpose();
            dir.push_back(row), bound.push_back(lo[j] + w - q(j) + slack);
            dir.push_back(-row), bound.push_back(q(j) - lo[j] + slack);
          }
          for (std::size_t h0 = 0; h0 < dir.size(); ++h0)
            for (std::size_t h1 = h0 + 1; h1 < dir.size(); ++h1)
              for (std::size_t h2 = h1 + 1; h2 < dir.size(); ++h2) {
                Eigen::Matrix3d m;
                m << dir[h0].transpose(), dir[h1].transpose(), dir[h2].transpose();
                if (std::abs(m.determinant()) < 1e-12) continue;
                const Eigen::Vector3d t =
                    m.inverse() * Eigen::Vector3d(bound[h0], bound[h1], bound[h2]);
                bool inside = true;
                for (std::size_t h = 0; h < dir.size() && inside; ++h)
                  inside = dir[h].dot(t) <= bound[h] + 1e-12;
                if (inside) return true;
              }
          return false;
        };
        // Only boxes the flat misses by 5% to 30% of their width: the far ones any test
        // discards.
        if (meets(0.05 * w) || !meets(0.3 * w)) continue;
        INFO("n = " << n << ", sphere " << sphere << ", trial " << trial);
        CHECK(bounding.linearizationExcludes(toBox(lo, w)));
        ++discarded;
      }
      for (int trial = 0; trial < 40; ++trial) {
        // Boxes of widths 2^-2 .. 2^-9 around a point of the sphere, anywhere inside.
        const Eigen::VectorXd p = spherePoint();
        const double w = std::ldexp(1.0, -2 - static_cast<int>(rng() % 8));
        std::vector<double> lo(n);
        for (int j = 0; j < n; ++j) lo[j] = p(j) - unit(rng) * w;
        INFO("n = " << n << ", sphere " << sphere << ", point box " << trial);
        CHECK_FALSE(bounding.linearizationExcludes(toBox(lo, w)));
        ++kept;
      }
    }
  }
  CHECK(kept >= 600);
  CHECK(discarded >= 150);
}

TEMPLATE_TEST_CASE("a quadratic without a patch is enclosed by its Taylor form", "[subdivision]",
                   NDC_SCALARS) {
  // The unit sphere F = |x - q|^2 - 1 in R^7 and R^8 (3^n coefficients: no patch, enclosed
  // from its linearisation). Its Taylor form over a box c +- h is exact:
  // F(c + d) = F(c) + grad F(c) . d + |d|^2, so F(X) lies in F(c) +- (|grad F(c)| . h + |h|^2),
  // where the mean-value form with the gradient over the box gives twice the last term. Boxes
  // near the sphere: those 1% outside the Taylor enclosure must be discarded, and some of them
  // lie within the mean-value form's.
  ndc::test::PrecisionScope<TestType> scope(128);
  using S = TestType;
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> unit(0, 1);
  int discarded = 0, onlyByTaylor = 0;
  for (int n : {7, 8}) {
    std::vector<double> q(n);
    for (double& v : q) v = std::round(64 * (0.2 * unit(rng) - 0.1)) / 64;
    std::string sphere;
    for (int j = 0; j < n; ++j) {
      std::ostringstream e;
      e.precision(17);
      e << (j ? " + " : "") << "(x" << j << " - (" << q[j] << "))^2";
      sphere += e.str();
    }
    const Problem problem = ndc::test::makeProblem(n, {sphere + " - 1"}, 2);
    REQUIRE_FALSE(ndc::LinearizedBounding<double>::hasPatch(problem.equations[0]));
    const ndc::LinearizedBounding<S> bounding(problem, problem.domainAs<S>());
    for (int trial = 0; trial < 1000; ++trial) {
      // Dyadic boxes of width 2^-1 .. 2^-4 near the sphere (the wide ones are those where the
      // remainder matters).
      const double w = std::ldexp(1.0, -1 - static_cast<int>(rng() % 4));
      std::vector<double> c(n);
      double norm = 0;
      for (int j = 0; j < n; ++j) c[j] = unit(rng) - 0.5, norm += c[j] * c[j];
      const double radius = 1 + (unit(rng) - 0.5) * 6 * w;
      double value = -1, reach = 0, square = 0;
      for (int j = 0; j < n; ++j) {
        c[j] = q[j] + std::round(c[j] / std::sqrt(norm) * radius / w) * w;
        value += (c[j] - q[j]) * (c[j] - q[j]);
        reach += std::abs(2 * (c[j] - q[j])) * w / 2;
        square += w * w / 4;
      }
      if (std::abs(value) <= 1.01 * (reach + square)) continue;
      ndc::Box<S> box{std::vector<S>(n), std::vector<S>(n)};
      for (int j = 0; j < n; ++j) box.lo[j] = S(c[j] - w / 2), box.hi[j] = S(c[j] + w / 2);
      INFO("n = " << n << ", trial " << trial << ", F(c) = " << value << ", Taylor reach "
                  << reach + square);
      CHECK(bounding.meanValueExcludes(box));
      ++discarded;
      onlyByTaylor += std::abs(value) < 0.99 * (reach + 2 * square);
    }
  }
  CHECK(discarded >= 100);
  CHECK(onlyByTaylor >= 20);
}
