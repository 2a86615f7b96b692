// Tests of the proven rounding bound of double Bernstein forms (form_rounding.hpp): on generated
// polynomials (sums of squares, products, powers, cancellation at several scales, short and
// long decimal literals, in 1 to 5 variables) every coefficient of the double form lies within
// the bound of the form computed in 256-bit arithmetic from the same literals, the form itself is
// the one toBernstein computes, and the bound is small where the arithmetic is benign.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/form_rounding.hpp"
#include "framework/problem/expression.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Bernstein;
using ndc::Box;
using ndc::Expression;
using ndc::FormRounding;
using ndc::Mpfr;
using ndc::test::PrecisionScope;

std::vector<std::string> names(int n) {
  std::vector<std::string> out;
  for (int j = 0; j < n; ++j) out.push_back("x" + std::to_string(j));
  return out;
}

/// Literals are drawn as doubles and written with 17 significant digits or 2 (0.1, 0.35:
/// inexact in binary), or, with `exact`, with all their digits (every double is a finite
/// decimal), so that only the arithmetic rounds.
struct Literals {
  std::mt19937 rng;
  bool exact = false;

  std::string operator()(double lo, double hi) {
    const double v = std::uniform_real_distribution<double>(lo, hi)(rng);
    std::ostringstream o;
    o.precision(exact ? 80 : rng() % 2 ? 17 : 2);
    o << v;
    return "(" + o.str() + ")";
  }
};

/// A random affine form in x0..x(n-1) with coefficients in [-2, 2] and an offset of `scale`.
std::string affine(Literals& literal, int n, double scale) {
  std::string e = "(" + literal(-scale, scale);
  for (int j = 0; j < n; ++j) e += " + " + literal(-2, 2) + "*x" + std::to_string(j);
  return e + ")";
}

/// One of the generated families: 0 sum of squares minus a constant (a sphere), 1 a product of
/// three affine forms, 2 a power 3..5 of one, 3 a square expanded against itself (cancellation
/// of terms of size `scale`^2), 4 nested products and powers with short literals.
std::string generated(Literals& literal, int family, int n, double scale) {
  switch (family) {
    case 0: {
      std::string e;
      for (int i = 0; i < std::min(n, 3); ++i) e += affine(literal, n, 1) + "^2 + ";
      return e + "(-1)";
    }
    case 1:
      return affine(literal, n, 1) + "*" + affine(literal, n, 1) + "*" + affine(literal, n, 1);
    case 2:
      return affine(literal, n, 1) + "^" + std::to_string(3 + literal.rng() % 3);
    case 3: {
      // (x0 + s)^2 - 2 s x0 - s^2 = x0^2, the terms of size s^2.
      const std::string s = literal(scale, 2 * scale);
      return "(x0 + " + s + ")^2 - 2*" + s + "*x0 - " + s + "^2 + " + affine(literal, n, 1);
    }
    default:
      return "(" + affine(literal, n, 1) + "*" + affine(literal, n, 1) + " + 0.1)^2 - 0.3*" +
             affine(literal, n, 1) + "^3";
  }
}

Box<double> randomBox(std::mt19937& rng, int n, double offset) {
  Box<double> box;
  for (int j = 0; j < n; ++j) {
    const double lo = offset + std::uniform_real_distribution<double>(-2, 1)(rng);
    box.lo.push_back(lo);
    box.hi.push_back(lo + std::uniform_real_distribution<double>(0.01, 1.5)(rng));
  }
  return box;
}

}  // namespace

TEST_CASE("The proven rounding of double Bernstein forms holds against 256-bit forms",
          "[form-rounding]") {
  PrecisionScope<Mpfr> scope(256);
  std::mt19937 rng(77);
  Literals literal{std::mt19937(78)};
  int checked = 0;
  double tightest = std::numeric_limits<double>::infinity(), loosest = 0;
  for (bool exactLiterals : {false, true})
    for (int n = 1; n <= 5; ++n)
      for (int family = 0; family < 5; ++family)
        for (double scale : {1.0, 1e2, 1e4})
          for (double offset : {0.0, 10.0}) {
            literal.exact = exactLiterals;
            const std::string text = generated(literal, family, n, scale);
            INFO(text);
            const Expression e = Expression::parse(text, names(n));
            const Box<double> box = randomBox(rng, n, offset);
            double bound = -1;
            const Bernstein<double> form = e.toBernstein(box, bound);
            REQUIRE(std::isfinite(bound));
            // The same form as without the bound, bit for bit.
            const Bernstein<double> plain = e.toBernstein<double>(box);
            REQUIRE(form.degrees() == plain.degrees());
            CHECK(std::equal(form.coefficients().begin(), form.coefficients().end(),
                             plain.coefficients().begin()));
            const Bernstein<Mpfr> exact = e.toBernstein<Mpfr>(ndc::toScalar<Mpfr>(box));
            REQUIRE(exact.degrees() == form.degrees());
            double error = 0;
            for (std::size_t k = 0; k < form.size(); ++k)
              error = std::max(error, std::abs(ndc::toDouble(Mpfr(form.coefficients()[k]) -
                                                             exact.coefficients()[k])));
            INFO("error " << error << " bound " << bound);
            CHECK(error <= bound);
            if (error > 0) {
              tightest = std::min(tightest, bound / error);
              loosest = std::max(loosest, bound / error);
            }
            ++checked;
          }
  INFO("bound / error from " << tightest << " to " << loosest);
  CHECK(checked == 300);
  // The bound is not vacuous: within a few thousand times the error on every input.
  CHECK(loosest < 1e4);
}

TEST_CASE("The proven rounding is small for well-scaled quadrics in up to 8 variables",
          "[form-rounding]") {
  // The relative bound decides whether the precision check needs 128-bit arithmetic
  // (pipeline.cpp: at most 2^-40); rotated spheres and circles must not.
  std::mt19937 rng(5);
  Literals literal{std::mt19937(6)};
  for (int n = 2; n <= 8; ++n) {
    const std::string text = generated(literal, 0, n, 1);
    INFO(text);
    const Expression e = Expression::parse(text, names(n));
    const Box<double> box = randomBox(rng, n, 0);
    double bound = 0;
    const Bernstein<double> form = e.toBernstein(box, bound);
    const double relative = FormRounding::relative(form, bound);
    INFO("relative " << relative);
    CHECK(relative < 0x1p-42);
  }
}

TEST_CASE("Forms with leaves or divisions have no proven rounding", "[form-rounding]") {
  const Expression e = Expression::parse("x0/3 + x1", names(2));
  Box<double> box;
  box.lo = {0, 0};
  box.hi = {1, 1};
  double bound = 0;
  const Bernstein<double> form = e.toBernstein(box, bound);
  CHECK(std::isinf(bound));
  CHECK(std::isinf(FormRounding::relative(form, bound)));
}
