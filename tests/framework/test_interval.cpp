// Tests of outward-rounded interval arithmetic against ground truth computed exactly in
// 2000-bit MPFR (every operation below is exact at that precision for the operands used).
#include <catch2/catch.hpp>

#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "framework/numeric/interval.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Interval;
using ndc::Mpfr;
using ndc::toDouble;
using ndc::test::PrecisionScope;
using ndc::test::uniform;

using ndc::test::exact;
using ndc::test::kExactBits;

// The exact value of a short decimal literal (2000 bits hold it to ~600 digits).
Mpfr exactLiteral(const char* literal) {
  Mpfr r;
  mpfr_set_prec(r.backend().data(), kExactBits);
  mpfr_set_str(r.backend().data(), literal, 10, MPFR_RNDN);
  return r;
}

// Whether the interval holds the exact value `v`.
template <class S>
bool encloses(const Interval<S>& a, const Mpfr& v) {
  return exact(a.lower()) <= v && v <= exact(a.upper());
}

// A random interval whose ends are not dyadic in Mpfr (x/3 rounds), so rounding matters.
template <class S>
Interval<S> randomInterval(std::mt19937& rng) {
  S a = uniform<S>(rng, -4, 4) / S(3), b = uniform<S>(rng, -4, 4) / S(3);
  if (b < a) std::swap(a, b);
  return Interval<S>(a, b);
}

// A point of [lo, hi]: the ends themselves or a random point between them.
template <class S>
S samplePoint(const Interval<S>& a, std::mt19937& rng, int k) {
  if (k == 0) return a.lower();
  if (k == 1) return a.upper();
  S lo = a.lower(), hi = a.upper();
  S p = lo + uniform<S>(rng, 0, 1) * (hi - lo);
  if (p < lo) p = lo;
  if (p > hi) p = hi;
  return p;
}

}  // namespace

TEMPLATE_TEST_CASE("Interval: construction, accessors, fromString", "[interval]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);

  Interval<S> zero;
  CHECK(zero.lower() == 0);
  CHECK(zero.upper() == 0);
  CHECK(zero.containsZero());

  Interval<S> a(S(-1.5), S(2.5));
  CHECK(a.lower() == S(-1.5));
  CHECK(a.upper() == S(2.5));
  CHECK(a.width() == S(4));
  CHECK(a.midpoint() == S(0.5));
  CHECK(a.contains(S(-1.5)));
  CHECK(a.contains(S(2.5)));
  CHECK_FALSE(a.contains(S(2.6)));
  CHECK(a.containsZero());
  CHECK_FALSE(Interval<S>(S(0.5), S(1)).containsZero());
  CHECK_THROWS_AS(Interval<S>(S(1), S(0)), std::invalid_argument);

  // Copies and moves keep the value.
  Interval<S> b = a;
  Interval<S> c = std::move(b);
  Interval<S> d;
  d = c;
  Interval<S> e;
  e = std::move(d);
  CHECK(e.lower() == S(-1.5));
  CHECK(e.upper() == S(2.5));

  // The literal 1/10 is enclosed strictly: it is neither a double nor a binary Mpfr.
  Mpfr tenth = exact(Mpfr(1)) / 10;
  auto t = Interval<S>::fromString("0.1");
  CHECK(exact(t.lower()) < tenth);
  CHECK(tenth < exact(t.upper()));
  // ... and tightly: the width is about one unit in the last place.
  CHECK(toDouble(t.width()) < 4 * toDouble(ndc::ScalarTraits<S>::epsilon()) * 0.1);
  CHECK(toDouble(t.width()) > 0);

  // Exactly representable literals give points.
  for (const char* literal : {"0.5", "3", "-2.25", "1.5e3", "0", "1e-2"}) {
    auto p = Interval<S>::fromString(literal);
    CHECK(encloses(p, exactLiteral(literal)));
    if (std::string(literal) != "1e-2") CHECK(p.lower() == p.upper());
  }
  auto p = Interval<S>::fromString("-3.14159e-7");
  CHECK(encloses(p, exactLiteral("-3.14159e-7")));
  CHECK(p.lower() < p.upper());
  CHECK_THROWS_AS(Interval<S>::fromString("abc"), std::invalid_argument);
  CHECK_THROWS_AS(Interval<S>::fromString("1.5x"), std::invalid_argument);
  CHECK_THROWS_AS(Interval<S>::fromString(""), std::invalid_argument);
}

TEMPLATE_TEST_CASE("Interval: rounding is outward", "[interval]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);

  // 1/3 is not representable: the enclosure has two distinct ends around it.
  auto third = Interval<S>(S(1)).dividedBy(S(3));
  CHECK(third.lower() < third.upper());
  CHECK(exact(third.lower()) * 3 < 1);
  CHECK(exact(third.upper()) * 3 > 1);

  // A sum that rounds: 1 + tiny.
  S tiny = ndc::ScalarTraits<S>::epsilon() / S(8);
  auto sum = Interval<S>(S(1)) + Interval<S>(tiny);
  CHECK(sum.lower() == S(1));
  CHECK(sum.upper() > S(1));
  auto diff = Interval<S>(S(1)) - Interval<S>(tiny);
  CHECK(diff.upper() == S(1));
  CHECK(diff.lower() < S(1));

  // A product that rounds: (1 + eps)^2 = 1 + 2 eps + eps^2.
  S onePlus = S(1) + ndc::ScalarTraits<S>::epsilon();
  auto sq = Interval<S>(onePlus) * Interval<S>(onePlus);
  Mpfr exactSq = exact(onePlus) * exact(onePlus);
  CHECK(encloses(sq, exactSq));
  CHECK(sq.lower() < sq.upper());
  auto sq2 = Interval<S>(onePlus).pow(2);
  CHECK(encloses(sq2, exactSq));
  CHECK(sq2.lower() < sq2.upper());
}

TEMPLATE_TEST_CASE("Interval: integer powers use the even-power rule", "[interval]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  auto check = [](double lo, double hi, int n, double elo, double ehi) {
    auto r = Interval<S>(S(lo), S(hi)).pow(n);
    CHECK(r.lower() == S(elo));
    CHECK(r.upper() == S(ehi));
  };
  check(-1, 2, 2, 0, 4);
  check(-3, 1, 2, 0, 9);
  check(-3, -2, 2, 4, 9);
  check(-3, -2, 3, -27, -8);
  check(-2, 1, 3, -8, 1);
  check(0.5, 2, 4, 0.0625, 16);
  check(-2, 3, 0, 1, 1);
  check(-2, 3, 1, -2, 3);
  check(-2, -1, 4, 1, 16);
  CHECK_THROWS(Interval<S>(S(1)).pow(-1));
}

TEMPLATE_TEST_CASE("Interval: operations enclose exact results at sampled points", "[interval]",
                   NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  std::mt19937 rng(12345);
  int failures = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Interval<S> a = randomInterval<S>(rng), b = randomInterval<S>(rng);
    S divisor = uniform<S>(rng, 0.5, 3) / S(7);
    int n = trial % 6;
    auto sum = a + b, difference = a - b, product = a * b, negation = -a, power = a.pow(n);
    auto quotient = a.dividedBy(divisor), hull = a.hull(b);
    // Midpoint inside, width rounded up.
    CHECK(a.contains(a.midpoint()));
    CHECK(exact(a.width()) >= exact(a.upper()) - exact(a.lower()));
    for (int i = 0; i < 8; ++i) {
      for (int k = 0; k < 8; ++k) {
        Mpfr x = exact(samplePoint(a, rng, i)), y = exact(samplePoint(b, rng, k));
        Mpfr xn = exact(S(1));
        for (int e = 0; e < n; ++e) xn *= x;
        bool ok = encloses(sum, x + y) && encloses(difference, x - y) && encloses(product, x * y) &&
                  encloses(negation, -x) && encloses(power, xn) && encloses(hull, x) &&
                  encloses(hull, y);
        // Quotient: x / divisor is inexact, compare x against quotient * divisor instead.
        ok = ok && exact(quotient.lower()) * exact(divisor) <= x &&
             x <= exact(quotient.upper()) * exact(divisor);
        if (!ok) ++failures;
      }
    }
  }
  CHECK(failures == 0);
}

TEMPLATE_TEST_CASE("Interval: compound assignment", "[interval]", NDC_SCALARS) {
  using S = TestType;
  PrecisionScope<S> scope(160);
  Interval<S> a(S(1), S(2));
  a += Interval<S>(S(0.5), S(1));
  CHECK(a.lower() == S(1.5));
  CHECK(a.upper() == S(3));
  a -= Interval<S>(S(1), S(2));
  CHECK(a.lower() == S(-0.5));
  CHECK(a.upper() == S(2));
  a *= Interval<S>(S(-2), S(1));
  CHECK(a.lower() == S(-4));
  CHECK(a.upper() == S(2));
  CHECK_THROWS(a.dividedBy(S(0)));
}

TEMPLATE_TEST_CASE("Interval: an overflow to NaN may contain zero", "[interval]", NDC_SCALARS) {
  // inf - inf has NaN ends: no information, so containsZero must not let an exclusion test
  // discard a box or a regularity test certify a Jacobian on it.
  using S = TestType;
  PrecisionScope<S> scope(160);
  const S inf = S(std::numeric_limits<double>::infinity());
  Interval<S> nan(inf);
  nan -= Interval<S>(inf);
  CHECK(nan.containsZero());
  Interval<S> product = nan;
  product *= Interval<S>(S(2), S(3));
  CHECK(product.containsZero());
  CHECK_FALSE(Interval<S>(S(1), inf).containsZero());
}

TEST_CASE("Interval: the one-switch scaled quotient equals per-operation arithmetic",
          "[interval]") {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(-1e3, 1e3), w(0, 10);
  for (int trial = 0; trial < 1000; ++trial) {
    const double lo = u(rng) / 7, hi = lo + w(rng) / 3, factor = 1 + trial % 9,
                 divisor = (trial % 2 ? 1 : -1) * (w(rng) + 1e-3) / 11;
    const Interval<double> a(lo, hi);
    const Interval<double> reference = (a * Interval<double>(factor)).dividedBy(divisor);
    const Interval<double> fast = ndc::scaledQuotient(a, factor, divisor);
    INFO("trial " << trial);
    CHECK(fast.lower() == reference.lower());
    CHECK(fast.upper() == reference.upper());
    CHECK(a.midpoint() == (lo + hi) / 2);
  }
  CHECK_THROWS_AS(ndc::scaledQuotient(Interval<double>(1.0), 2, 0), std::domain_error);
}

TEST_CASE("Interval: the one-switch Krawczyk operator equals per-operation arithmetic",
          "[interval]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1), w(0, 0.1);
  for (int trial = 0; trial < 400; ++trial) {
    const int m = trial % 50 == 49 ? 20 : 1 + trial % 5;  // and a few larger than any cap
    std::vector<double> y(m), lo(m), hi(m), inverse(std::size_t(m) * m);
    std::vector<Interval<double>> fy, jx;
    for (int c = 0; c < m; ++c) {
      y[c] = u(rng) / 3;
      lo[c] = y[c] - w(rng) / 7;  // y inside [lo, hi], the differences inexact in general
      hi[c] = y[c] + w(rng) / 7;
      const double f = u(rng) * 1e-3;
      fy.emplace_back(f, f + w(rng) * 1e-6);
    }
    for (double& v : inverse) v = u(rng) / 3;
    for (int e = 0; e < m * m; ++e) {
      const double a = u(rng) / 9;
      jx.emplace_back(a, a + w(rng));
    }
    std::vector<double> kLower(m), kUpper(m);
    ndc::krawczykOperator(m, y, inverse, fy, jx, lo, hi, kLower, kUpper);
    for (int i = 0; i < m; ++i) {
      using I = Interval<double>;
      I k(y[i]);
      for (int l = 0; l < m; ++l) k -= I(inverse[std::size_t(l) * m + i]) * fy[l];
      for (int c = 0; c < m; ++c) {
        I a(i == c ? 1.0 : 0.0);
        for (int l = 0; l < m; ++l) a -= I(inverse[std::size_t(l) * m + i]) * jx[l * m + c];
        k += a * (I(lo[c], hi[c]) - I(y[c]));
      }
      INFO("trial " << trial << " row " << i);
      CHECK(kLower[i] == k.lower());
      CHECK(kUpper[i] == k.upper());
    }
  }
}

TEST_CASE("Interval<Mpfr> uses the current precision", "[interval][mpfr]") {
  PrecisionScope<Mpfr> scope(100);
  auto coarse = Interval<Mpfr>(Mpfr(1)).dividedBy(Mpfr(3));
  ndc::setMpfrPrecision(400);
  auto fine = Interval<Mpfr>(Mpfr(1)).dividedBy(Mpfr(3));
  CHECK(toDouble(coarse.width()) > 1e-33);
  CHECK(toDouble(coarse.width()) < 1e-29);
  CHECK(toDouble(fine.width()) < 1e-110);
  CHECK(toDouble(fine.width()) > 0);
}
