// Tests of the compiled expression (Tape) and its evaluators beyond expression.hpp: built
// programs against parsed ones, shared leaves, the midpoint-radius evaluator against exact
// values, the magnitude bound's counts, and the one-switch interval de Casteljau kernel against
// the per-operation interval arithmetic it replaces (bit for bit).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "framework/numeric/iteration.hpp"
#include "framework/numeric/magnitude.hpp"
#include "framework/numeric/midrad.hpp"
#include "framework/numeric/tape.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Box;
using ndc::Expression;
using ndc::Interval;
using ndc::Mpfr;
using ndc::Tape;
using ndc::TapeOp;
using ndc::test::exact;
using ndc::test::kExactBits;
using ndc::test::PrecisionScope;
using ndc::test::uniform;

const std::vector<std::string> kXyz = {"x", "y", "z"};

/// Variable names x0..x(n-1).
std::vector<std::string> names(int n) {
  std::vector<std::string> out;
  for (int j = 0; j < n; ++j) out.push_back("x" + std::to_string(j));
  return out;
}

/// A random affine form in x0..x(n-1), parenthesised: coefficients in [-2, 2], its value at
/// `centre` (0 if empty) in [-1, 1].
std::string randomAffine(int n, std::mt19937& rng, const std::vector<double>& centre = {}) {
  std::ostringstream e;
  e.precision(17);
  double offset = 0;
  e << "(";
  for (int j = 0; j < n; ++j) {
    const double a = uniform<double>(rng, -2, 2);
    if (!centre.empty()) offset -= a * centre[j];
    e << (j ? " + " : "") << "(" << a << ")*x" << j;
  }
  e << " + (" << offset + uniform<double>(rng, -1, 1) << "))";
  return e.str();
}

// A piecewise leaf in (x, z): two pieces along x (breaks -1, 0, 1), degree 2 x 1.
std::shared_ptr<const ndc::PiecewiseBernstein> makeLeaf() {
  auto leaf = std::make_shared<ndc::PiecewiseBernstein>();
  leaf->name = "L";
  leaf->axes = {0, 2};
  leaf->breaks = {{-1, 0, 1}, {-2, 2}};
  for (int piece = 0; piece < 2; ++piece) {
    Box<double> box{{piece - 1.0, -2}, {piece + 0.0, 2}};
    ndc::Bernstein<double> b(box, {2, 1});
    const double c[6] = {0.5, -1.25, 2, 0.75 * piece, 1, -0.5};
    for (std::size_t i = 0; i < 6; ++i) b.coefficients()[i] = c[i] + piece;
    leaf->pieces.push_back(b);
  }
  return leaf;
}

// The interval de Casteljau of the per-operation interval arithmetic (the reference the kernel
// must reproduce bit for bit).
Interval<double> referenceDeCasteljau(const ndc::Bernstein<double>& piece,
                                      const std::vector<Interval<double>>& t) {
  std::vector<Interval<double>> work;
  for (double c : piece.coefficients()) work.emplace_back(c);
  std::size_t count = work.size();
  for (int a = 0; a < piece.dim(); ++a) {
    const int d = piece.degree(a);
    const std::size_t block = static_cast<std::size_t>(d) + 1, blocks = count / block;
    for (std::size_t b = 0; b < blocks; ++b) {
      Interval<double>* w = &work[b * block];
      for (int r = 1; r <= d; ++r)
        for (int i = 0; i + r <= d; ++i) w[i] += t[a] * (w[i + 1] - w[i]);
      if (b) work[b] = w[0];
    }
    count = blocks;
  }
  return work[0];
}

}  // namespace

TEST_CASE("Tape: a built expression is the program of its parsed text", "[tape]") {
  using K = TapeOp::Kind;
  const Expression a = Expression::parse("x/3 - y", kXyz);
  const Expression b = Expression::parse("y^2 + 0.1*z", kXyz);
  const Expression built = a * b - a;
  const Expression parsed = Expression::parse("(x/3 - y)*(y^2 + 0.1*z) - (x/3 - y)", kXyz);
  const Tape& t = built.tape();
  REQUIRE(t.ops().size() == parsed.tape().ops().size());
  for (std::size_t i = 0; i < t.ops().size(); ++i) {
    INFO("instruction " << i);
    CHECK(t.ops()[i].kind == parsed.tape().ops()[i].kind);
    if (t.ops()[i].kind != K::kConstant) CHECK(t.ops()[i].arg == parsed.tape().ops()[i].arg);
  }
  CHECK(t.stackDepth() == parsed.tape().stackDepth());
  // Both divisors point at their own constant subprogram, the second one shifted by the join.
  int divisions = 0;
  for (std::size_t i = 0; i < t.ops().size(); ++i) {
    if (t.ops()[i].kind != K::kDiv) continue;
    ++divisions;
    CHECK(ndc::evaluateConstant<double>(t, static_cast<std::size_t>(t.ops()[i].arg), i) == 3);
  }
  CHECK(divisions == 2);
  // The same program gives the same bits, value and gradient.
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> x = {uniform<double>(rng, -2, 2), uniform<double>(rng, -2, 2),
                             uniform<double>(rng, -2, 2)};
    std::vector<double> g1(3), g2(3);
    CHECK(built.evaluate<double>(x, g1) == parsed.evaluate<double>(x, g2));
    CHECK(g1 == g2);
  }
  CHECK(built.degrees() == std::vector<int>{1, 3, 1});
  CHECK(t.totalDegree(2) == 2);
  CHECK(Expression::parse("3*x - y/2 + 1", kXyz).tape().totalDegree(2) == 1);
}

TEST_CASE("Tape: a leaf used many times is one leaf, computed once", "[tape]") {
  const auto leaf = makeLeaf();
  const Expression l = Expression::polynomial(3, leaf);
  const Expression y = Expression::variable(3, 1, "y");
  const Expression e = l * l + y * l - l;
  REQUIRE(e.tape().leaves().size() == 1);
  int uses = 0;
  for (const TapeOp& op : e.tape().ops()) uses += op.kind == TapeOp::Kind::kLeaf;
  CHECK(uses == 4);
  CHECK(e.breaks(0) == std::vector<double>{-1, 0, 1});
  CHECK(e.breaks(1).empty());
  CHECK(e.degrees() == std::vector<int>{4, 1, 2});
  // Value and gradient against the leaf evaluated directly.
  std::mt19937 rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> x = {uniform<double>(rng, -1, 1), uniform<double>(rng, -2, 2),
                                   uniform<double>(rng, -2, 2)};
    const std::vector<double> local = {x[0], x[2]};
    const double v = leaf->evaluate<double>(local);
    std::vector<double> g(3);
    const double value = e.evaluate<double>(x, g);
    CHECK(value == Approx(v * v + x[1] * v - v).margin(1e-12));
    CHECK(g[1] == Approx(v).margin(1e-12));
  }
}

TEMPLATE_TEST_CASE("Tape: the midpoint-radius evaluator encloses value and gradient", "[tape]",
                   NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(31);
  const std::vector<std::string> texts = {"(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)",
                                          "x*y*z - (x - y)^2*(y - z)^2/2.5 + z^4 - -x",
                                          "(x - 2*y)^4 - x*y/3 + 1.5e-1*z"};
  for (const std::string& text : texts) {
    INFO(text);
    const Expression e = Expression::parse(text, kXyz);
    const ndc::MidRadEvaluator<S> evaluator(e.sharedTape());
    for (int trial = 0; trial < 8; ++trial) {
      std::vector<S> c(3), r(3);
      for (int j = 0; j < 3; ++j) {
        c[j] = uniform<S>(rng, -1.5, 1.5);
        r[j] = uniform<S>(rng, 0, 0.3);
      }
      REQUIRE(evaluator.run(c, r, true));
      for (int i = 0; i < 10; ++i) {
        // A point of the box, and the exact value and gradient there.
        std::vector<S> x(3);
        for (int j = 0; j < 3; ++j) x[j] = c[j] + uniform<S>(rng, -0.99, 0.99) * r[j];
        PrecisionScope<Mpfr> high(kExactBits);
        std::vector<Mpfr> p, g(3);
        for (const S& v : x) p.push_back(exact(v));
        const Mpfr value = e.evaluate<Mpfr>(p, g);
        for (int q = 0; q <= 3; ++q) {
          const Mpfr truth = q == 0 ? value : g[q - 1];
          CHECK(abs(truth - exact(evaluator.mid(q))) <= exact(evaluator.rad(q)));
        }
      }
    }
  }
}

TEMPLATE_TEST_CASE("Tape: the quadratic form encloses value and gradient, as tight as the pass",
                   "[tape]", NDC_SCALARS) {
  // Generated programs of total degree <= 2 in R^1..R^8 (sums and differences of squares of
  // random affine forms, products of two affine forms, affine forms, sparse quadratics), each
  // on points, on boxes with some zero radii and on wide boxes: run() (the quadratic form) must
  // enclose the exact value and gradient at sample points of the box (its corners among them),
  // be no wider than the pass over the program up to rounding, and gradientSpread must bound
  // how far the gradient moves from the centre's.
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(83);
  const S eps = ndc::ScalarTraits<S>::epsilon();
  int runs = 0;
  for (int n = 1; n <= 8; ++n) {
    const auto affine = [&]() { return randomAffine(n, rng); };
    for (int kind = 0; kind < 5; ++kind) {
      std::string text;
      if (kind == 0) text = affine() + "^2 + " + affine() + "^2 - 1";
      if (kind == 1) text = affine() + "^2 - 2*" + affine() + "^2 + 0.25";
      if (kind == 2) text = affine() + "*" + affine();
      if (kind == 3) text = affine();
      if (kind == 4)
        text = "x0^2 - 3*x" + std::to_string(n - 1) + "*x" + std::to_string(n / 2) + " + 0.5";
      INFO("n = " << n << ": " << text);
      const Expression e = Expression::parse(text, names(n));
      // About 0, and about a point of the box's range (the domain's centre in the pipeline).
      std::vector<S> origin(n);
      for (S& o : origin) o = uniform<S>(rng, -2, 2);
      const ndc::MidRadEvaluator<S> atZero(e.sharedTape());
      const ndc::MidRadEvaluator<S> atOrigin(e.sharedTape(), std::span<const S>(origin));
      for (int trial = 0; trial < 12; ++trial) {
        const ndc::MidRadEvaluator<S>& evaluator = trial % 2 ? atOrigin : atZero;
        REQUIRE(evaluator.quadraticForm());
        std::vector<S> c(n), r(n);
        for (int j = 0; j < n; ++j) {
          c[j] = uniform<S>(rng, -2, 2);
          const int shape = trial % 4;  // a point, some axes fixed, tiny, wide
          r[j] = shape == 0                 ? S(0)
                 : shape == 1 && j % 2 == 0 ? S(0)
                 : shape == 2               ? S(1e-9)
                                            : uniform<S>(rng, 0, 0.5);
        }
        REQUIRE(evaluator.runProgram(c, r, true));
        std::vector<S> passMid(n + 1), passRad(n + 1);
        for (int q = 0; q <= n; ++q) passMid[q] = evaluator.mid(q), passRad[q] = evaluator.rad(q);
        std::vector<S> spread(n);
        REQUIRE(evaluator.gradientSpread(r, spread));
        // runWithCentre: the numbers of run(c, r, true) and of run(c, 0, false) in one run; for
        // a program (the quadratic times x0^2), those of its two passes.
        const std::vector<S> zero(n, S(0));
        const Expression cubic = Expression::parse("(" + text + ")*x0^2", names(n));
        const ndc::MidRadEvaluator<S> program(cubic.sharedTape());
        REQUIRE_FALSE(program.quadraticForm());
        for (const ndc::MidRadEvaluator<S>* tested : {&evaluator, &program}) {
          REQUIRE(tested->run(c, zero, false));
          const S pointMid = tested->mid(0), pointRad = tested->rad(0);
          REQUIRE(tested->run(c, r, true));
          std::vector<S> boxMid(n + 1), boxRad(n + 1);
          for (int q = 0; q <= n; ++q) boxMid[q] = tested->mid(q), boxRad[q] = tested->rad(q);
          REQUIRE(tested->runWithCentre(c, r));
          CHECK(tested->centreMid() == pointMid);
          CHECK(tested->centreRad() == pointRad);
          for (int q = 0; q <= n; ++q) {
            CHECK(tested->mid(q) == boxMid[q]);
            CHECK(tested->rad(q) == boxRad[q]);
          }
        }
        REQUIRE(evaluator.run(c, r, true));
        ++runs;
        for (int q = 0; q <= n; ++q) {
          using std::abs;
          const S slack = S(1e4) * S(n + 2) * eps * (1 + abs(passMid[q]));
          CHECK(evaluator.rad(q) <= passRad[q] * (1 + S(1e-6)) + slack);
          CHECK(abs(evaluator.mid(q) - passMid[q]) <= evaluator.rad(q) + passRad[q]);
        }
        PrecisionScope<Mpfr> high(kExactBits);
        std::vector<Mpfr> centre, gc(n);
        for (const S& v : c) centre.push_back(exact(v));
        e.evaluate<Mpfr>(centre, gc);
        for (int i = 0; i < 12; ++i) {
          // A corner of the box first, then points inside it.
          std::vector<Mpfr> p, g(n);
          for (int j = 0; j < n; ++j) {
            const S t = i < 4 ? S((i >> (j % 2)) & 1 ? 1 : -1) : uniform<S>(rng, -1, 1);
            p.push_back(exact(c[j]) + exact(t) * exact(r[j]));
          }
          const Mpfr value = e.evaluate<Mpfr>(p, g);
          for (int q = 0; q <= n; ++q) {
            const Mpfr truth = q == 0 ? value : g[q - 1];
            CHECK(abs(truth - exact(evaluator.mid(q))) <= exact(evaluator.rad(q)));
          }
          for (int j = 0; j < n; ++j) CHECK(abs(g[j] - gc[j]) <= exact(spread[j]));
        }
      }
    }
  }
  CHECK(runs == 8 * 5 * 12);
  // A sphere far from 0, about its domain's centre: the rounding stays at the scale of the
  // values near it (about 0 the expanded terms are 1e6 and their rounding 1e-10, and H taken
  // from gradients at 0, about 2000, would carry their rounding).
  const std::vector<std::string> xy = {"x", "y"};
  const Expression far = Expression::parse("(x - 1000)^2 + (y - 1000)^2 - 1", xy);
  const std::vector<S> centre = {S(1000), S(1000)};
  const ndc::MidRadEvaluator<S> evaluator(far.sharedTape(), std::span<const S>(centre));
  const std::vector<S> p = {S(1000.6), S(1000.8)}, zero = {S(0), S(0)};
  REQUIRE(evaluator.run(p, zero, true));
  CHECK(evaluator.rad(0) < S(1e4) * eps);
}

TEMPLATE_TEST_CASE("Tape: a system evaluates its quadratics in their form, as the programs do",
                   "[tape]", NDC_SCALARS) {
  // Generated systems in R^2..R^8 on domains about random centres (far from 0 for some): a sum
  // of squares of random affine forms, a product of two, an affine form and a cubic (which keeps
  // its program). System::evaluate must give the programs' values and gradients at random points
  // of the domain up to rounding at the scale of the terms.
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(89);
  const S eps = ndc::ScalarTraits<S>::epsilon();
  for (int n = 2; n <= 8; ++n) {
    const std::vector<std::string> variables = names(n);
    const double shift = n % 3 == 0 ? 500 : 0;
    std::vector<double> centre(n);
    for (double& c : centre) c = shift + uniform<double>(rng, -2, 2);
    const auto affine = [&]() { return randomAffine(n, rng, centre); };
    ndc::Problem problem;
    problem.variables = variables;
    for (int j = 0; j < n; ++j) {
      problem.domain.lo.push_back(centre[j] - 1.5);
      problem.domain.hi.push_back(centre[j] + 1.5);
    }
    problem.equations = {Expression::parse(affine() + "^2 + " + affine() + "^2 - 1", variables),
                         Expression::parse(affine() + "*" + affine(), variables),
                         Expression::parse(affine(), variables),
                         Expression::parse(affine() + "^3 - x0", variables)};
    const ndc::System<S> system(problem);
    CHECK(system.quadraticForm(0));
    CHECK(system.quadraticForm(1));
    CHECK(system.quadraticForm(2));
    CHECK_FALSE(system.quadraticForm(3));
    const auto m = problem.equations.size();
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<S> x(n), f(m), jac(m * n), g(n);
      for (int j = 0; j < n; ++j) x[j] = S(centre[j]) + uniform<S>(rng, -1.5, 1.5);
      system.evaluate(x, f, jac);
      for (std::size_t i = 0; i < m; ++i) {
        const S value = problem.equations[i].evaluate<S>(x, g);
        // The terms' scale: the value and gradient of the affine factors are O(10) here.
        using std::abs;
        const S tolerance = S(1e4) * S(n) * eps * (1 + abs(value));
        INFO("n = " << n << ", equation " << i << ", trial " << trial);
        CHECK(abs(f[i] - value) <= tolerance);
        for (int j = 0; j < n; ++j) CHECK(abs(jac[i * n + j] - g[j]) <= tolerance);
      }
      // The Hessian's bounds against the programs' gradients at x and a second point y:
      // |G_j(x) - G_j(y)| <= (|H| |x - y|)_j and |G(x) - G(y)|_2 <= |H|_F |x - y|_2.
      using std::abs;
      std::vector<S> y(n), gy(n), h(n), spread(n);
      S distance2 = 0;
      for (int j = 0; j < n; ++j) {
        y[j] = S(centre[j]) + uniform<S>(rng, -1.5, 1.5);
        h[j] = abs(x[j] - y[j]);
        distance2 += h[j] * h[j];
      }
      for (std::size_t i = 0; i < m; ++i) {
        const int row = static_cast<int>(i);
        if (!system.quadraticForm(row)) {
          CHECK_FALSE(system.hessianSpread(row, h, spread));
          CHECK(system.hessianNorm(row) == S(-1));
          continue;
        }
        REQUIRE(system.hessianSpread(row, h, spread));
        problem.equations[i].evaluate<S>(x, g);
        problem.equations[i].evaluate<S>(y, gy);
        const S tolerance = S(1e4) * S(n) * eps * (1 + ndc::normInf<S>(g) + ndc::normInf<S>(gy));
        S moved2 = 0;
        for (int j = 0; j < n; ++j) {
          CHECK(abs(g[j] - gy[j]) <= spread[j] + tolerance);
          moved2 += (g[j] - gy[j]) * (g[j] - gy[j]);
        }
        using std::sqrt;
        CHECK(sqrt(moved2) <= system.hessianNorm(row) * sqrt(distance2) + tolerance);
        if (i == 2) CHECK(system.hessianNorm(row) == S(0));  // the affine form
      }
    }
  }
}

TEMPLATE_TEST_CASE("Tape: the magnitude bound and its operation count", "[tape]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  struct Known {
    const char* text;
    int count;         // rounding operations + total degree
    double magnitude;  // at x = -2, y = 3, z = 0.5
  };
  const std::vector<Known> known = {
      {"x^2 - 3*y", 4 + 2, 4 + 9},
      {"x/4", 2 + 1, 0.5},
      {"-(x*y) + z/(1+1)", (1 + 1 + 2) + 2, 6 + 0.25},
      {"(x + y)^3", (1 + 2) + 3, 125},
  };
  const std::vector<S> absX = {S(2), S(3), S(0.5)};
  for (const Known& k : known) {
    INFO(k.text);
    const ndc::MagnitudeBound<S> bound(Expression::parse(k.text, kXyz).sharedTape());
    std::vector<S> stack;
    CHECK(bound.count() == k.count);
    CHECK(ndc::toDouble(bound(absX, stack)) == Approx(k.magnitude));
  }
}

TEST_CASE("Tape: the one-switch interval de Casteljau equals per-operation intervals", "[tape]") {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 200; ++trial) {
    const int p = 1 + trial % 3;
    std::vector<int> degrees;
    Box<double> box;
    for (int a = 0; a < p; ++a) {
      degrees.push_back(1 + static_cast<int>(rng() % 5));
      box.lo.push_back(0);
      box.hi.push_back(1);
    }
    ndc::Bernstein<double> piece(box, degrees);
    for (double& c : piece.coefficients()) c = uniform<double>(rng, -3, 3) / 7;
    std::vector<Interval<double>> t;
    for (int a = 0; a < p; ++a) {
      const double lo = uniform<double>(rng, -0.1, 1.0), w = uniform<double>(rng, 0, 0.3) / 3;
      t.emplace_back(lo, lo + w);
    }
    const Interval<double> fast =
        ndc::tensorDeCasteljauEnclosure(piece.coefficients(), piece.degrees(), t.data());
    const Interval<double> reference = referenceDeCasteljau(piece, t);
    CHECK(fast.lower() == reference.lower());
    CHECK(fast.upper() == reference.upper());
  }
}

TEST_CASE("Tape: the one-switch de Casteljau gives the whole line where it overflows", "[tape]") {
  // Coefficients near the top of double: the differences overflow to inf and inf - inf is
  // NaN; the enclosure must then be everything (the fuzzer found the NaN end thrown as an
  // invalid interval).
  Box<double> box{{0}, {1}};
  ndc::Bernstein<double> piece(box, {2});
  piece.coefficients()[0] = -1.7e308;
  piece.coefficients()[1] = 1.7e308;
  piece.coefficients()[2] = -1.7e308;
  const Interval<double> t(0.25, 0.75);
  const Interval<double> e =
      ndc::tensorDeCasteljauEnclosure(piece.coefficients(), piece.degrees(), &t);
  CHECK(e.lower() == -std::numeric_limits<double>::infinity());
  CHECK(e.upper() == std::numeric_limits<double>::infinity());
  // Coefficients that do not overflow keep their tight enclosure.
  piece.coefficients()[0] = -1;
  piece.coefficients()[1] = 1;
  piece.coefficients()[2] = -1;
  const Interval<double> f =
      ndc::tensorDeCasteljauEnclosure(piece.coefficients(), piece.degrees(), &t);
  CHECK(f.lower() > -2);
  CHECK(f.upper() < 2);
}

TEST_CASE("Tape: the curvature of quadratics: sums of squares, their negatives, indefinite ones",
          "[tape]") {
  // Generated quadratics in R^2..R^8 from random rotations R (rows r_l) and offsets q:
  //  - sum over l < rank of (r_l . x + q_l)^2 - 1: H = 2 sum r_l r_l^T is positive
  //    semidefinite of that rank (a sphere in a rotated flat, a cylinder), so sign +1 with a
  //    slack at rounding level;
  //  - its negative: sign -1;
  //  - sum of squares minus one more square, (r_0 . x)^2 - (r_1 . x)^2 + ...: indefinite, sign 0.
  // And the claim itself, sign d^T H d / 2 >= -slack max d_j^2, at random d (where
  // d^T H d / 2 = (F(d) + F(-d)) / 2 - F(0), enclosed by midpoint-radius runs).
  std::mt19937 rng(61);
  std::normal_distribution<double> gauss;
  int semidefinite = 0, indefinite = 0;
  for (int n = 2; n <= 8; ++n) {
    std::vector<std::string> names;
    for (int j = 0; j < n; ++j) names.push_back("x" + std::to_string(j));
    for (int trial = 0; trial < 15; ++trial) {
      // Rows of a random orthogonal matrix by Gram-Schmidt.
      std::vector<std::vector<double>> r;
      while (static_cast<int>(r.size()) < n) {
        std::vector<double> v(n);
        for (double& x : v) x = gauss(rng);
        for (const auto& w : r) {
          double dot = 0;
          for (int j = 0; j < n; ++j) dot += v[j] * w[j];
          for (int j = 0; j < n; ++j) v[j] -= dot * w[j];
        }
        double norm = 0;
        for (double x : v) norm += x * x;
        for (double& x : v) x /= std::sqrt(norm);
        r.push_back(v);
      }
      const auto square = [&](int l) {
        std::ostringstream e;
        e.precision(17);
        e << "(";
        for (int j = 0; j < n; ++j) e << (j ? " + " : "") << "(" << r[l][j] << ")*x" << j;
        e << " + (" << 0.1 * gauss(rng) << "))^2";
        return e.str();
      };
      const int rank = 1 + static_cast<int>(rng() % n);
      std::string sum;
      for (int l = 0; l < rank; ++l) sum += (l ? " + " : "") + square(l);
      const int kind = trial % 3;  // 0: sum, 1: its negative, 2: indefinite
      std::string text = kind == 1 ? "-(" + sum + ") + 1" : sum + " - 1";
      if (kind == 2) {
        if (rank == n) continue;  // no direction left for the negative square
        text = sum + " - 2*" + square(rank) + " - 1";
      }
      const Expression e = Expression::parse(text, names);
      const ndc::Curvature c = ndc::quadraticCurvature(e.sharedTape());
      INFO("n = " << n << ", rank " << rank << ": " << text);
      const int expected = kind == 0 ? 1 : kind == 1 ? -1 : 0;
      CHECK(c.sign == expected);
      if (c.sign != 0) {
        ++semidefinite;
        CHECK(c.slack < 1e-12);
        // d^T H d / 2 = (F(d) + F(-d)) / 2 - F(0) for a quadratic: never beyond the slack.
        const ndc::MidRadEvaluator<double> f(e.sharedTape());
        const std::vector<double> zero(n, 0.0);
        for (int s = 0; s < 20; ++s) {
          std::vector<double> d(n), minus(n);
          double dMax = 0;
          for (int j = 0; j < n; ++j)
            d[j] = gauss(rng), minus[j] = -d[j], dMax = std::max(dMax, std::abs(d[j]));
          REQUIRE(f.run(d, zero, false));
          double q = f.mid(0) / 2, bound = f.rad(0) / 2;
          REQUIRE(f.run(minus, zero, false));
          q += f.mid(0) / 2, bound += f.rad(0) / 2;
          REQUIRE(f.run(zero, zero, false));
          q -= f.mid(0), bound += f.rad(0);
          CHECK(c.sign * q + bound >= -c.slack * dMax * dMax);
        }
      } else {
        ++indefinite;
      }
    }
  }
  CHECK(semidefinite >= 50);
  CHECK(indefinite >= 20);
  // Not quadratics: affine, cubic, piecewise leaves have no curvature.
  CHECK(ndc::quadraticCurvature(Expression::parse("x - 2*y + z", kXyz).sharedTape()).sign == 0);
  CHECK(ndc::quadraticCurvature(Expression::parse("x^3 + y^2", kXyz).sharedTape()).sign == 0);
}
