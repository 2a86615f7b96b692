// Tests of polynomial expressions: parsing and errors, and every evaluator against ground truth
// (hand-computed values, analytic gradients, exact 2000-bit MPFR evaluation, and the Bernstein
// form evaluated independently).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/parser.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Bernstein;
using ndc::Box;
using ndc::Expression;
using ndc::ExpressionError;
using ndc::Interval;
using ndc::Mpfr;
using ndc::toDouble;
using ndc::test::PrecisionScope;
using ndc::test::relativeTolerance;
using ndc::test::uniform;

using ndc::test::exact;
using ndc::test::kExactBits;

// Variable names: x, y, z up to three variables, x1..xn beyond.
std::vector<std::string> names(int n) {
  std::vector<std::string> v;
  for (int j = 1; j <= n; ++j)
    v.push_back(n <= 3 ? std::string(1, "xyz"[j - 1]) : "x" + std::to_string(j));
  return v;
}

template <class S>
double absD(const S& v) {
  return std::abs(toDouble(v));
}

// |a - b| <= tol * scale, in S.
template <class S>
bool close(const S& a, const S& b, double scale) {
  using std::abs;
  S diff = abs(S(a - b));
  return diff <= S(relativeTolerance<S>() * std::max(1.0, scale));
}

// The value and gradient at x in 2000-bit MPFR: the literals and every operation are exact to
// far below the precision of S, so this is the ground truth for enclosures.
template <class S>
Mpfr exactValue(const Expression& e, const std::vector<S>& x, std::vector<Mpfr>* gradient) {
  PrecisionScope<Mpfr> high(kExactBits);
  std::vector<Mpfr> p;
  for (const S& v : x) p.push_back(exact(v));
  if (!gradient) return e.evaluate<Mpfr>(p);
  gradient->assign(x.size(), Mpfr(0));
  return e.evaluate<Mpfr>(p, *gradient);
}

// A magnitude bound for rounding errors: the expression with every operation made
// non-negative (a - b -> |a| + |b|, literals and variables by their absolute value) at
// |x_j| <= bound_j. It bounds every intermediate of the plain evaluation at points of the box,
// and every coefficient of the intermediate Bernstein forms on it. Computed here from the
// tape's instructions with the literals read again (an independent reading of the program):
// each stack entry holds the magnitude and, for constant subprograms, the value.
double magnitude(const ndc::Tape& tape, const std::vector<double>& bound) {
  using K = ndc::TapeOp::Kind;
  struct Entry {
    double magnitude, value;
  };
  std::vector<Entry> stack;
  for (const ndc::TapeOp& op : tape.ops()) {
    switch (op.kind) {
      case K::kConstant: {
        const double v = std::stod(tape.constants()[op.arg].literal);
        stack.push_back({std::abs(v), v});
        break;
      }
      case K::kVariable:
        stack.push_back({bound[op.arg], 0});
        break;
      case K::kLeaf:
        throw std::logic_error("parsed expressions have no piecewise leaves");
      case K::kNeg:
        stack.back().value = -stack.back().value;
        break;
      case K::kPow:
        stack.back() = {std::pow(stack.back().magnitude, op.arg),
                        std::pow(stack.back().value, op.arg)};
        break;
      default: {
        const Entry b = stack.back();
        stack.pop_back();
        Entry& a = stack.back();
        if (op.kind == K::kDiv)
          a = {a.magnitude / std::abs(b.value), a.value / b.value};
        else if (op.kind == K::kMul)
          a = {a.magnitude * b.magnitude, a.value * b.value};
        else
          a = {a.magnitude + b.magnitude,
               op.kind == K::kAdd ? a.value + b.value : a.value - b.value};
      }
    }
  }
  return stack.back().magnitude;
}

template <class S>
Box<S> randomBox(std::mt19937& rng, int n) {
  Box<S> box;
  for (int j = 0; j < n; ++j) {
    double lo = std::uniform_real_distribution<double>(-2, 1)(rng);
    double w = std::uniform_real_distribution<double>(0.1, 1.5)(rng);
    box.lo.push_back(S(lo));
    box.hi.push_back(S(lo + w));
  }
  return box;
}

template <class S>
std::vector<S> randomPoint(std::mt19937& rng, const Box<S>& box) {
  std::vector<S> x;
  for (int j = 0; j < box.dim(); ++j) {
    S t = uniform<S>(rng, 0, 1);
    x.push_back(box.lo[j] + t * (box.hi[j] - box.lo[j]));
  }
  return x;
}

template <class S>
std::vector<double> boxBound(const Box<S>& box) {
  std::vector<double> b;
  for (int j = 0; j < box.dim(); ++j)
    b.push_back(std::max(absD(box.lo[j]), absD(box.hi[j])) * (1 + 1e-12));
  return b;
}

struct Case {
  int n;
  const char* text;
};

// Polynomials in 2..6 variables: products, powers up to 4, nested parentheses, division by
// constants, every literal form.
const std::vector<Case> kCases = {
    {2, "x^2 + y^2 - 0.5"},
    {2, "(x - 2*y)^4 - x*y/3 + 1.5e-1"},
    {2, "-(x + 0.25)^3 * (y - .5)^2 + ((x*y) - (1/7))"},
    {3, "(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)"},
    {3, "x*y*z - (x - y)^2*(y - z)^2/2.5 + z^4 - -x"},
    {4, "(x1*x2 - x3*x4)^2 + (x1 + x2 + x3 + x4)^3/7 - 0.25"},
    {5, "x1*x2*x3*x4*x5 - (x1 + x2)^2*(x3 - x4)^2 + x5^4 - 1e-2"},
    {6, "((x1 - x2)*(x3 + x4) - x5^2)*(x6 + 1)^2 - 3*(x1*x6)^2 + (((x2)))"},
};

}  // namespace

TEMPLATE_TEST_CASE("Expression: known values, precedence and associativity", "[expression]",
                   NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  struct Known {
    const char* text;
    double x, y, z;
    const char* expected;  // hand-computed, as a decimal literal
  };
  const std::vector<Known> known = {
      {"x^2 + y^2 - 0.5", 0.5, 0.25, 0, "-0.1875"},
      {"(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)", 1, 0, 0, "-0.6144"},
      {"(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)", 0.5, 0.25, -1.5, "10.32700625"},
      {"-x^2", 3, 0, 0, "-9"},
      {"(-x)^2", 3, 0, 0, "9"},
      {"-2^2", 0, 0, 0, "-4"},
      {"2^3", 0, 0, 0, "8"},
      {"2^3^2", 0, 0, 0, "512"},
      {"(2^3)^2", 0, 0, 0, "64"},
      {"x^2^0", 0.5, 0, 0, "0.5"},
      {"x^(2)", 0.5, 0, 0, "0.25"},
      {"x^0", 0.5, 0, 0, "1"},
      {"x/2", 3, 0, 0, "1.5"},
      {"x/2/2", 3, 0, 0, "0.75"},
      {"6/(1+2)*x", 3, 0, 0, "6"},
      {"1.5e-3*x", 2, 0, 0, "0.003"},
      {"1.5E+2*x", 2, 0, 0, "300"},
      {".5*x + 2.", 2, 0, 0, "3"},
      {"--x", 0.5, 0, 0, "0.5"},
      {"- - -x", 0.5, 0, 0, "-0.5"},
      {"-(-(-(x)))", 0.5, 0, 0, "-0.5"},
      {"+x", 0.5, 0, 0, "0.5"},
      {"2*-x", 0.5, 0, 0, "-1"},
      {"2+3*4", 0, 0, 0, "14"},
      {"(2+3)*4", 0, 0, 0, "20"},
      {"2*3^2", 0, 0, 0, "18"},
      {"1-2+3", 0, 0, 0, "2"},
      {"x-y-z", 0.5, 0.25, -1.5, "1.75"},
      {"x*y+z", 0.5, 0.25, -1.5, "-1.375"},
      {"x+y*z", 0.5, 0.25, -1.5, "0.125"},
      {"(x+y)*z", 0.5, 0.25, -1.5, "-1.125"},
      {" x  *\ty ", 0.5, 0.25, 0, "0.125"},
      {"0.1*3", 0, 0, 0, "0.3"},
      {"1/3*3", 0, 0, 0, "1"},
      {"((((x))))", 0.5, 0, 0, "0.5"},
  };
  const std::vector<std::string> v = {"x", "y", "z"};
  for (const auto& k : known) {
    INFO(k.text);
    Expression e = Expression::parse(k.text, v);
    S got = e.evaluate<S>(std::vector<S>{S(k.x), S(k.y), S(k.z)});
    S want = ndc::ScalarTraits<S>::fromString(k.expected);
    CHECK(close(got, want, absD(want)));
    // The gradient evaluator returns the same value.
    std::vector<S> g(3);
    CHECK(close(e.evaluate<S>(std::vector<S>{S(k.x), S(k.y), S(k.z)}, g), want, absD(want)));
  }

  // Literals are read at the full precision of S (not through a double).
  Expression tenth = Expression::parse("0.1", v);
  S value = tenth.evaluate<S>(std::vector<S>(3, S(0)));
  const double eps = toDouble(ndc::ScalarTraits<S>::epsilon());
  PrecisionScope<Mpfr> high(kExactBits);
  Mpfr error = exact(value) - exact(Mpfr(1)) / 10;
  CHECK(std::abs(toDouble(error)) < 0.1 * eps);
}

TEST_CASE("Expression: compiled program, text, copies", "[expression]") {
  using K = ndc::TapeOp::Kind;
  const std::vector<std::string> v = {"x", "y"};
  Expression e = Expression::parse("-x^2 + 3", v);
  CHECK(e.dim() == 2);
  CHECK(e.text() == "-x^2 + 3");
  // Postfix: x, ^2, negate (`^` binds tighter than unary minus), 3, add.
  const auto ops = e.tape().ops();
  REQUIRE(ops.size() == 5);
  CHECK((ops[0].kind == K::kVariable && ops[0].arg == 0));
  CHECK((ops[1].kind == K::kPow && ops[1].arg == 2));
  CHECK(ops[2].kind == K::kNeg);
  REQUIRE(ops[3].kind == K::kConstant);
  CHECK(e.tape().constants()[ops[3].arg].literal == "3");
  CHECK(ops[4].kind == K::kAdd);
  CHECK(e.tape().stackDepth() == 2);
  // A divisor is the constant subprogram just before its instruction.
  Expression d = Expression::parse("y/(1+1)", v);
  REQUIRE(d.tape().ops().size() == 5);
  CHECK((d.tape().ops()[4].kind == K::kDiv && d.tape().ops()[4].arg == 1));
  CHECK(ndc::evaluateConstant<double>(d.tape(), 1, 4) == 2);

  Expression copy = e;
  Expression assigned;
  CHECK(assigned.evaluate<double>(std::vector<double>{}) == 0);
  assigned = copy;
  Expression moved = std::move(copy);
  CHECK(moved.evaluate<double>(std::vector<double>{2, 0}) == -1);
  CHECK(assigned.evaluate<double>(std::vector<double>{2, 0}) == -1);
  CHECK(&assigned.tape() == &e.tape());  // copies share the immutable program
  CHECK_THROWS_AS(e.evaluate<double>(std::vector<double>{1}), std::invalid_argument);
}

TEMPLATE_TEST_CASE("Expression: degrees and coefficient count", "[expression]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  struct Known {
    const char* text;
    std::vector<int> degrees;
  };
  const std::vector<Known> known = {
      {"x^2 + y^2 - 0.5", {2, 2, 0}},
      {"(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)", {4, 4, 4}},
      {"x*y^3 - z", {1, 3, 1}},
      {"(x+y)^3*z/2", {3, 3, 1}},
      {"2^3", {0, 0, 0}},
      {"-(x*x*x)", {3, 0, 0}},
      {"x - x", {1, 0, 0}},  // an upper bound: cancellation is ignored
      {"(x*y^2)^3 + z^0", {3, 6, 0}},
      {"x^2^2*y", {4, 1, 0}},
      // a^0 is 1 without its base: the Bernstein form of the base (degree 10^8) is never
      // built (a fuzzing finding: the evaluators used to build it and time out).
      {"((x^10000)^10000)^0 - y", {0, 1, 0}},
  };
  const std::vector<std::string> v = {"x", "y", "z"};
  Box<S> box{{S(-1), S(0), S(0.5)}, {S(1), S(2), S(1)}};
  for (const auto& k : known) {
    INFO(k.text);
    Expression e = Expression::parse(k.text, v);
    CHECK(e.degrees() == k.degrees);
    Bernstein<S> b = e.toBernstein(box);
    CHECK(b.degrees() == k.degrees);
    std::size_t count = 1;
    for (int d : k.degrees) count *= static_cast<std::size_t>(d + 1);
    CHECK(b.size() == count);
  }
}

TEST_CASE("Expression: errors name the problem and its column", "[expression]") {
  const std::vector<std::string> v = {"x", "y"};
  struct Bad {
    const char* text;
    int column;
    const char* message;
  };
  const std::vector<Bad> bad = {
      {"x + sin(y)", 5, "function calls are not allowed: 'sin'"},
      {"x + sin (y)", 5, "function calls are not allowed: 'sin'"},
      {"x^2.5", 3, "non-negative integer"},
      {"x^2.0", 3, "non-negative integer"},
      {"x^-1", 3, "non-negative integer"},
      {"x^y", 3, "non-negative integer"},
      {"x^", 3, "expected an exponent"},
      {"x^100001", 3, "exponent too large"},
      {"1/x", 3, "division by a non-constant"},
      {"x/(2*(y+1))", 7, "depends on 'y'"},
      {"x/0", 3, "division by zero"},
      {"x/(1-1)", 3, "division by zero"},
      {"x/(0.1+0.2-0.3)", 3, "too close to zero"},
      {"x + q", 5, "unknown variable 'q'"},
      {"x*yy", 3, "unknown variable 'yy'"},
      {"(x+y", 5, "missing ')'"},
      {"((x+y)*2", 9, "missing ')' to close '(' at column 1"},
      {"x+y)", 4, "unmatched ')'"},
      {"x +", 4, "unexpected end"},
      {"", 1, "empty expression"},
      {"   ", 1, "empty expression"},
      {"x $ y", 3, "unexpected character '$'"},
      {"x + $", 5, "unexpected character '$'"},
      {"2x", 2, "missing operator"},
      {"(x)(y)", 4, "missing operator"},
      {"x**2", 3, "unexpected '*'"},
      {"()", 2, "unexpected ')'"},
      {"1e999", 1, "not finite"},
      {"x*1e999", 3, "not finite"},
      {"x = y", 3, "unexpected character '='"},
  };
  for (const auto& b : bad) {
    INFO("expression: \"" << b.text << "\"");
    try {
      Expression::parse(b.text, v);
      FAIL("no ExpressionError");
    } catch (const ExpressionError& error) {
      CHECK(error.column() == b.column);
      CHECK_THAT(std::string(error.what()), Catch::Contains(b.message));
    }
  }
  // Accepted edge cases.
  CHECK_NOTHROW(Expression::parse("x^(2)^(2)", v));
  CHECK_NOTHROW(Expression::parse("x/(2^3 - 7.5)", v));
  CHECK_NOTHROW(Expression::parse("1e-999*x", v));  // underflows to 0 in double: finite
}

TEMPLATE_TEST_CASE("Expression: Bernstein form equals direct evaluation", "[expression]",
                   NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(2024);
  for (const auto& c : kCases) {
    INFO(c.text);
    Expression e = Expression::parse(c.text, names(c.n));
    for (int trial = 0; trial < 4; ++trial) {
      Box<S> box = randomBox<S>(rng, c.n);
      Bernstein<S> b = e.toBernstein(box);
      double scale = magnitude(e.tape(), boxBound(box));
      for (int i = 0; i < 12; ++i) {
        std::vector<S> x = randomPoint(rng, box);
        S direct = e.evaluate<S>(x);
        S viaBernstein = b.evaluate(x);
        INFO("direct " << toDouble(direct) << " bernstein " << toDouble(viaBernstein) << " scale "
                       << scale);
        CHECK(close(direct, viaBernstein, scale));
        // Ground truth at 2000 bits as well.
        CHECK(close(direct, S(exactValue(e, x, nullptr)), scale));
      }
    }
  }
}

TEMPLATE_TEST_CASE("Expression: gradient against analytic and Bernstein derivatives",
                   "[expression]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(77);
  const std::vector<std::string> v = {"x", "y", "z"};

  // The torus and a mixed polynomial, with hand-derived gradients.
  Expression torus = Expression::parse("(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)", v);
  Expression mixed = Expression::parse("x*y^3 - 2*x/3 + (z - x)^2", v);
  S c = ndc::ScalarTraits<S>::fromString("0.84");
  for (int i = 0; i < 20; ++i) {
    S x = uniform<S>(rng, -2, 2), y = uniform<S>(rng, -2, 2), z = uniform<S>(rng, -2, 2);
    std::vector<S> p = {x, y, z}, g(3);
    S s = x * x + y * y + z * z + c;
    S value = torus.evaluate<S>(p, g);
    CHECK(close(value, S(s * s - 4 * (x * x + y * y)), 100));
    CHECK(close(g[0], S(4 * x * s - 8 * x), 100));
    CHECK(close(g[1], S(4 * y * s - 8 * y), 100));
    CHECK(close(g[2], S(4 * z * s), 100));

    value = mixed.evaluate<S>(p, g);
    CHECK(close(value, S(x * y * y * y - 2 * x / 3 + (z - x) * (z - x)), 50));
    CHECK(close(g[0], S(y * y * y - S(2) / 3 - 2 * (z - x)), 50));
    CHECK(close(g[1], S(3 * x * y * y), 50));
    CHECK(close(g[2], S(2 * (z - x)), 50));
  }

  // Every case: the gradient equals the derivatives of the Bernstein form.
  for (const auto& k : kCases) {
    INFO(k.text);
    Expression e = Expression::parse(k.text, names(k.n));
    Box<S> box = randomBox<S>(rng, k.n);
    Bernstein<S> b = e.toBernstein(box);
    double m = magnitude(e.tape(), boxBound(box));
    std::vector<int> degrees = e.degrees();
    for (int i = 0; i < 6; ++i) {
      std::vector<S> x = randomPoint(rng, box), g(k.n);
      S value = e.evaluate<S>(x, g);
      CHECK(close(value, e.evaluate<S>(x), m));
      for (int j = 0; j < k.n; ++j) {
        // Derivative magnitudes are at most 2 d_j M / w_j (Markov; every intermediate too).
        double scale = 2 * degrees[j] * m / toDouble(box.width(j));
        INFO("axis " << j);
        CHECK(close(g[j], b.derivative(j).evaluate(x), scale));
      }
    }
  }
}

TEMPLATE_TEST_CASE("Expression: interval evaluation encloses sampled values and gradients",
                   "[expression]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(99);

  // Integer powers are tight (even-power rule); products are the natural extension.
  {
    const std::vector<std::string> v = {"x"};
    std::vector<Interval<S>> box = {Interval<S>(S(-1), S(2))};
    Interval<S> square = Expression::parse("x^2", v).evaluate<S>(box);
    CHECK(square.lower() == S(0));
    CHECK(square.upper() == S(4));
    Interval<S> product = Expression::parse("x*x", v).evaluate<S>(box);
    CHECK(product.lower() == S(-2));
    CHECK(product.upper() == S(4));
    Interval<S> third = Expression::parse("x/3", v).evaluate<S>(box);
    CHECK(third.lower() < S(-1) / S(3));
    CHECK(third.upper() > S(2) / S(3));
    // Literals are enclosed, not rounded to a point: 0.1 * [1, 1] holds 1/10.
    std::vector<Interval<S>> one = {Interval<S>(S(1))};
    Interval<S> tenth = Expression::parse("0.1*x", v).evaluate<S>(one);
    PrecisionScope<Mpfr> high(kExactBits);
    Mpfr exactTenth = exact(Mpfr(1)) / 10;
    CHECK(exact(tenth.lower()) < exactTenth);
    CHECK(exactTenth < exact(tenth.upper()));
  }

  int valueFailures = 0, gradientFailures = 0, samples = 0;
  for (const auto& k : kCases) {
    INFO(k.text);
    Expression e = Expression::parse(k.text, names(k.n));
    for (int trial = 0; trial < 8; ++trial) {
      // A sub-box whose ends are not dyadic in Mpfr (x/3 rounds); the last trials use point
      // boxes, where only the rounding of literals and operations separates the ends.
      std::vector<Interval<S>> box;
      std::vector<S> lo, hi;
      for (int j = 0; j < k.n; ++j) {
        S a = uniform<S>(rng, -6, 3) / S(3);
        S w = trial < 5 ? uniform<S>(rng, 0.003, 1.5) / S(3) : S(0);
        lo.push_back(a);
        hi.push_back(a + w);
        box.emplace_back(lo.back(), hi.back());
      }
      std::vector<Interval<S>> grad(k.n);
      Interval<S> range = e.evaluate<S>(box);
      Interval<S> range2 = e.evaluate<S>(box, grad);
      // Samples: every corner (where the extremes of a tight enclosure sit), then random.
      const int corners = 1 << k.n;
      for (int i = 0; i < corners + 40; ++i) {
        std::vector<S> x(k.n);
        for (int j = 0; j < k.n; ++j) {
          if (i < corners) {
            x[j] = (i >> j) & 1 ? hi[j] : lo[j];
          } else {
            x[j] = lo[j] + uniform<S>(rng, 0, 1) * (hi[j] - lo[j]);
            if (x[j] > hi[j]) x[j] = hi[j];
          }
        }
        std::vector<Mpfr> g;
        Mpfr value = exactValue(e, x, &g);
        ++samples;
        if (!(exact(range.lower()) <= value && value <= exact(range.upper()))) ++valueFailures;
        if (!(exact(range2.lower()) <= value && value <= exact(range2.upper()))) ++valueFailures;
        for (int j = 0; j < k.n; ++j)
          if (!(exact(grad[j].lower()) <= g[j] && g[j] <= exact(grad[j].upper())))
            ++gradientFailures;
      }
    }
  }
  CHECK(samples > 1000);
  CHECK(valueFailures == 0);
  CHECK(gradientFailures == 0);
}

// ---- Compilation to the canonical form (canonical.hpp) ----------------------------------------

namespace {

/// A random decimal literal: digits, maybe a point, maybe an exponent.
std::string randomLiteral(std::mt19937& rng) {
  std::string s = std::to_string(std::uniform_int_distribution<int>(0, 999)(rng));
  if (rng() % 2) s += "." + std::to_string(std::uniform_int_distribution<int>(0, 99)(rng));
  if (rng() % 4 == 0) s += "e" + std::to_string(std::uniform_int_distribution<int>(-3, 2)(rng));
  return s;
}

/// A random monomial of total degree <= 3 in `v`, as text: `c*x^a*y`.
std::string randomMonomial(std::mt19937& rng, const std::vector<std::string>& v) {
  std::string s = randomLiteral(rng);
  const int degree = std::uniform_int_distribution<int>(0, 3)(rng);
  for (int d = 0; d < degree; ++d) s += "*" + v[rng() % v.size()];
  return s;
}

/// A long generated equation: `count` signed copies of a few monomials in random order (so
/// like terms collect), some as products of sums, some divided by 4 or 0.8 (finite decimals).
std::string generatedEquation(std::mt19937& rng, const std::vector<std::string>& v, int count) {
  std::vector<std::string> pool;
  for (int i = 0; i < 6; ++i) pool.push_back(randomMonomial(rng, v));
  pool.push_back("(" + v[0] + " + 1)*(" + v[1 % v.size()] + " - 2)");
  pool.push_back(v[0] + "^2/4");
  pool.push_back(v.back() + "/0.8");
  std::string text;
  for (int i = 0; i < count; ++i) {
    text += i == 0 ? "" : (rng() % 3 == 0 ? " - " : " + ");
    text += pool[rng() % pool.size()];
  }
  return text;
}

}  // namespace

TEMPLATE_TEST_CASE("Expression: a long generated equation is compiled to its collected terms",
                   "[expression]", NDC_SCALARS) {
  using S = TestType;
  std::mt19937 rng(40);
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 2 + trial % 3;
    const std::vector<std::string> v = names(n);
    const std::string text = generatedEquation(rng, v, 200 + 150 * trial);
    INFO("trial " << trial << ": " << text.substr(0, 200));
    const Expression e = Expression::parse(text, v);
    // The program is the collected one (at most 9 monomials of degree <= 3 in n variables),
    // far shorter than the text's.
    CHECK(e.writtenInstructions() > 1000);
    CHECK(e.tape().ops().size() * 10 < e.writtenInstructions());
    // The same polynomial: the exact value (the written program in 2000-bit MPFR) at random
    // points agrees with the collected program's in S to rounding.
    const ndc::Tape written = ndc::parseExpression(text, v);
    for (int p = 0; p < 5; ++p) {
      std::vector<S> x;
      for (int j = 0; j < n; ++j) x.push_back(uniform<S>(rng, -2.0, 2.0));
      PrecisionScope<Mpfr> high(kExactBits);
      std::vector<Mpfr> px;
      for (const S& value : x) px.push_back(exact(value));
      const Mpfr truth = ndc::evaluateTape<Mpfr>(written, px);
      const Mpfr collected = ndc::evaluateTape<Mpfr>(e.tape(), px);
      CHECK(toDouble(Mpfr(abs(truth - collected) / (1 + abs(truth)))) <= 1e-300);
      const S value = e.evaluate<S>(x);
      CHECK(absD(S(value - S(truth))) <= 1e-9 * std::max(1.0, absD(S(truth))));
    }
    // The Bernstein forms of both programs agree on a box.
    Box<S> box{std::vector<S>(std::size_t(n), S(-1)), std::vector<S>(std::size_t(n), S(1.5))};
    const Bernstein<S> a = e.toBernstein(box);
    const Bernstein<S> b = ndc::bernsteinOfTape(written, box);
    REQUIRE(a.degrees() == b.degrees());
    double scale = 0;
    for (const S& c : b.coefficients()) scale = std::max(scale, absD(c));
    for (std::size_t i = 0; i < a.coefficients().size(); ++i)
      CHECK(absD(S(a.coefficients()[i] - b.coefficients()[i])) <= 1e-12 * std::max(1.0, scale));
  }
}

TEST_CASE("Expression: short or expanding programs stay as written", "[expression]") {
  const std::vector<std::string> v = {"x", "y", "z"};
  // Hand-written: kept, with its natural interval extension.
  const Expression sphere = Expression::parse("x*x + y*y + z*z - 1", v);
  CHECK(sphere.tape().ops().size() == sphere.writtenInstructions());
  // A short power whose expansion is long: kept.
  const std::string power = "(x + y + z + 1)^12 + " + std::string(100, '0') + "*x";
  const Expression p = Expression::parse(power, v);
  CHECK(p.tape().ops().size() == p.writtenInstructions());
  // A quotient by 3 has no finite decimal: kept, and still right.
  std::string third;
  for (int i = 0; i < 200; ++i) third += (i ? " + " : "") + std::string("x*y/3");
  const Expression t = Expression::parse(third, v);
  CHECK(t.tape().ops().size() == t.writtenInstructions());
  CHECK(t.evaluate<double>(std::vector<double>{1.5, 2, 0}) == Approx(200.0));
  // 5,000 copies of x*y*z: one monomial, 5000*x*y*z, 5 instructions.
  std::string copies;
  for (int i = 0; i < 5000; ++i) copies += (i ? " + " : "") + std::string("x*y*z");
  const Expression c = Expression::parse(copies + " - 1", v);
  CHECK(c.tape().ops().size() == 9);  // 5e3 x mul y mul z mul 1 sub
  CHECK(c.writtenInstructions() > 20000);
  CHECK(c.tape().constants().front().literal == "5e3");
  CHECK(c.evaluate<double>(std::vector<double>{0.1, 0.2, 0.5}) == Approx(5000 * 0.01 - 1));
}

TEST_CASE("Expression: chains of powers fold without recursion", "[expression]") {
  const std::vector<std::string> v = {"x", "y"};
  std::mt19937 rng(7);
  for (int length : {1, 2, 10, 1000, 50000}) {
    // x^1^1^...^1 is x; x^2^1^...^1 is x^2; x^2^3^2 is x^512 (right associative).
    std::string ones;
    for (int i = 0; i < length; ++i) ones += "^1";
    CHECK(Expression::parse("x" + ones + " + y", v).degrees() == std::vector<int>{1, 1});
    CHECK(Expression::parse("x^2" + ones + " + y", v).degrees() == std::vector<int>{2, 1});
    CHECK(Expression::parse("x^(3" + ones + ")^2 - y", v).degrees() == std::vector<int>{9, 1});
    // 1^2^...: 1; 0^...^0 alternates.
    CHECK(Expression::parse("x^1^2" + ones + " - y", v).degrees() == std::vector<int>{1, 1});
  }
  CHECK(Expression::parse("x^2^3^2 - y", v).degrees() == std::vector<int>{512, 1});
  CHECK(Expression::parse("x^0^0 - y", v).degrees() == std::vector<int>{1, 1});  // 0^0 = 1
  CHECK(Expression::parse("x^2^0^5 - y", v).degrees() == std::vector<int>{1, 1});
  // Past the cap, with the chain's column.
  try {
    Expression::parse("y + x^2^3^2^2", v);
    FAIL("no error");
  } catch (const ExpressionError& e) {
    CHECK(e.column() == 7);
    CHECK(std::string(e.what()).find("exponent too large") != std::string::npos);
  }
}
