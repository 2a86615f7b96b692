// Tests of the tensor-product Bernstein polynomial against independent ground truth: the
// Bernstein sum formula evaluated directly (explicit binomials and powers).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::Bernstein;
using ndc::Box;
using ndc::toDouble;
using ndc::test::relativeTolerance;
using ndc::test::uniform;

template <class S>
S absOf(const S& v) {
  using std::abs;
  return abs(v);
}

// Binomial coefficient by the multiplicative formula (exact for the small n used here).
template <class S>
S binomial(int n, int k) {
  S c = 1;
  for (int i = 1; i <= k; ++i) c = c * S(n - k + i) / S(i);
  return c;
}

template <class S>
S powInt(const S& x, int e) {
  S r = 1;
  for (int i = 0; i < e; ++i) r *= x;
  return r;
}

// Direct evaluation of sum_I b_I prod_j C(d_j,i_j) t_j^i_j (1-t_j)^(d_j-i_j); `scale` receives
// sum_I |b_I| |B_I(t)|, the natural magnitude for relative errors.
template <class S>
S directEvaluate(const Bernstein<S>& p, const std::vector<S>& x, S* scale = nullptr) {
  const int n = p.dim();
  std::vector<S> t(n);
  for (int j = 0; j < n; ++j) t[j] = (x[j] - p.domain().lo[j]) / p.domain().width(j);
  S sum = 0, mag = 0;
  std::vector<int> idx(n, 0);
  for (std::size_t lin = 0; lin < p.size(); ++lin) {
    // Linear index from the documented layout: variable 0 fastest.
    std::size_t check = 0, st = 1;
    S basis = 1;
    for (int j = 0; j < n; ++j) {
      check += static_cast<std::size_t>(idx[j]) * st;
      st *= static_cast<std::size_t>(p.degree(j) + 1);
      basis *= binomial<S>(p.degree(j), idx[j]) * powInt(t[j], idx[j]) *
               powInt(S(1 - t[j]), p.degree(j) - idx[j]);
    }
    REQUIRE(check == lin);
    const S& b = p.coefficients()[lin];
    sum += b * basis;
    mag += absOf(b) * absOf(basis);
    for (int j = 0; j < n; ++j) {
      if (++idx[j] <= p.degree(j)) break;
      idx[j] = 0;
    }
  }
  if (scale) *scale = mag;
  return sum;
}

template <class S>
S maxAbs(const Bernstein<S>& p) {
  S m = 0;
  for (const S& c : p.coefficients()) m = std::max(m, absOf(c));
  return m;
}

// |a - b| <= tol * max(scale, 1e-300-ish floor).
template <class S>
bool close(const S& a, const S& b, const S& scale, double factor = 1) {
  const S s = std::max(scale, S(1e-30));
  return absOf(S(a - b)) <= S(relativeTolerance<S>() * factor) * s;
}

template <class S>
Box<S> randomBox(std::mt19937& rng, int n) {
  Box<S> box;
  for (int j = 0; j < n; ++j) {
    box.lo.push_back(uniform<S>(rng, -2, 2));
    box.hi.push_back(box.lo.back() + uniform<S>(rng, 0.25, 3));
  }
  return box;
}

template <class S>
Bernstein<S> randomPoly(std::mt19937& rng, const Box<S>& box, int maxDegree = 4) {
  std::uniform_int_distribution<int> deg(0, maxDegree);
  std::vector<int> degrees;
  for (int j = 0; j < box.dim(); ++j) degrees.push_back(deg(rng));
  Bernstein<S> p(box, degrees);
  for (S& c : p.coefficients()) c = uniform<S>(rng, -1, 1);
  return p;
}

template <class S>
Bernstein<S> randomPoly(std::mt19937& rng, const Box<S>& box, const std::vector<int>& degrees) {
  Bernstein<S> p(box, degrees);
  for (S& c : p.coefficients()) c = uniform<S>(rng, -1, 1);
  return p;
}

// Uniform point of the box widened by `margin` widths on each side.
template <class S>
std::vector<S> randomPoint(std::mt19937& rng, const Box<S>& box, double margin = 0) {
  std::vector<S> x;
  for (int j = 0; j < box.dim(); ++j) {
    const S u = uniform<S>(rng, -margin, 1 + margin);
    x.push_back(box.lo[j] + u * box.width(j));
  }
  return x;
}

template <class S>
int randomDim(std::mt19937& rng, int lo = 1, int hi = 5) {
  return std::uniform_int_distribution<int>(lo, hi)(rng);
}

template <class S>
int trials() {
  return std::is_same_v<S, double> ? 300 : 60;
}

}  // namespace

TEMPLATE_TEST_CASE("evaluate matches the Bernstein sum formula", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(1);
  for (int trial = 0; trial < trials<S>(); ++trial) {
    const Box<S> box = randomBox<S>(rng, randomDim<S>(rng));
    const Bernstein<S> p = randomPoly(rng, box);
    for (int k = 0; k < 8; ++k) {
      // Inside the domain, and outside (extrapolation) for half of the points.
      const std::vector<S> x = randomPoint(rng, box, k % 2 ? 0.5 : 0.0);
      S scale;
      const S expected = directEvaluate(p, x, &scale);
      const S got = p.evaluate(x);
      INFO("dim " << p.dim() << " got " << toDouble(got) << " expected " << toDouble(expected));
      CHECK(close(got, expected, scale, 4));
    }
  }
}

TEMPLATE_TEST_CASE("constants, variables and zero variables", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(2);
  const Bernstein<S> zero;
  CHECK(zero.dim() == 0);
  CHECK(zero.size() == 1);
  CHECK(zero.evaluate(std::vector<S>{}) == 0);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = randomDim<S>(rng);
    const Box<S> box = randomBox<S>(rng, n);
    const S value = uniform<S>(rng, -5, 5);
    const auto c = Bernstein<S>::constant(box, value);
    CHECK(c.size() == 1);
    for (int axis = 0; axis < n; ++axis) {
      const auto v = Bernstein<S>::variable(box, axis);
      CHECK(v.degree(axis) == 1);
      for (int k = 0; k < 5; ++k) {
        const std::vector<S> x = randomPoint(rng, box, 1.0);
        CHECK(close(v.evaluate(x), x[axis], S(absOf(x[axis]) + 1)));
        CHECK(c.evaluate(x) == value);
      }
    }
  }
  const Box<S> empty;
  const auto c0 = Bernstein<S>::constant(empty, S(3));
  CHECK(c0.dim() == 0);
  CHECK(c0.evaluate(std::vector<S>{}) == 3);
}

TEMPLATE_TEST_CASE("coefficient layout and multi-index access", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  Box<S> box{{S(0), S(0), S(0)}, {S(1), S(1), S(1)}};
  Bernstein<S> p(box, {2, 0, 3});
  CHECK(p.size() == 12);
  CHECK(p.stride(0) == 1);
  CHECK(p.stride(1) == 3);
  CHECK(p.stride(2) == 3);
  const std::vector<int> idx{1, 0, 2};
  p.coefficient(idx) = 7;
  CHECK(p.coefficients()[1 + 2 * 3] == 7);
  CHECK(std::as_const(p).coefficient(idx) == 7);
}

//! [bernstein-halve]
TEMPLATE_TEST_CASE("split and halve reproduce the polynomial on both halves", "[bernstein]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(3);
  Bernstein<S> left, right;  // reused across trials, like the subdivision loop
  for (int trial = 0; trial < trials<S>(); ++trial) {
    const Box<S> box = randomBox<S>(rng, randomDim<S>(rng));
    const Bernstein<S> p = randomPoly(rng, box);
    const int axis = std::uniform_int_distribution<int>(0, p.dim() - 1)(rng);
    const bool half = trial % 2 == 0;
    const S t = half ? S(0.5) : uniform<S>(rng, 0.05, 0.95);
    if (half)
      p.halve(axis, left, right);
    else
      p.split(axis, t, left, right);
    // Domains: the split point in domain coordinates, shared by both halves.
    const S mid = box.lo[axis] + t * box.width(axis);
    CHECK(close(left.domain().hi[axis], mid, S(absOf(mid) + 1)));
    CHECK(left.domain().hi[axis] == right.domain().lo[axis]);
    CHECK(left.domain().lo[axis] == box.lo[axis]);
    CHECK(right.domain().hi[axis] == box.hi[axis]);
    CHECK(left.degrees() == p.degrees());
    const S scale = maxAbs(p);
    for (const Bernstein<S>* part : {&left, &right})
      for (int k = 0; k < 6; ++k) {
        const std::vector<S> x = randomPoint(rng, part->domain());
        CHECK(close(part->evaluate(x), directEvaluate(p, x), scale, 4));
      }
  }
}
//! [bernstein-halve]

TEMPLATE_TEST_CASE("split and halve reuse the output storage", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(4);
  const Box<S> box = randomBox<S>(rng, 3);
  const Bernstein<S> p = randomPoly(rng, box, std::vector<int>{3, 2, 4});
  Bernstein<S> left, right;
  p.halve(1, left, right);
  const S* lp = left.coefficients().data();
  const S* rp = right.coefficients().data();
  auto limbs = [](const Bernstein<S>& b) {
    std::vector<const void*> out;
    if constexpr (!std::is_same_v<S, double>)
      for (const S& c : b.coefficients()) out.push_back(c.backend().data()[0]._mpfr_d);
    return out;
  };
  const auto leftLimbs = limbs(left), rightLimbs = limbs(right);
  for (int axis = 0; axis < 3; ++axis) {
    p.split(axis, S(0.3), left, right);
    p.halve(axis, left, right);
  }
  CHECK(left.coefficients().data() == lp);
  CHECK(right.coefficients().data() == rp);
  CHECK(limbs(left) == leftLimbs);
  CHECK(limbs(right) == rightLimbs);
  // Splitting into itself is allowed (works on a copy).
  Bernstein<S> q = p, other;
  q.halve(0, q, other);
  const std::vector<S> x = randomPoint(rng, q.domain());
  CHECK(close(q.evaluate(x), p.evaluate(x), maxAbs(p), 4));
}

TEMPLATE_TEST_CASE("restrict to sub-boxes inside and partly outside", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(5);
  for (int trial = 0; trial < trials<S>(); ++trial) {
    const Box<S> box = randomBox<S>(rng, randomDim<S>(rng));
    const Bernstein<S> p = randomPoly(rng, box);
    const double margin = trial % 2 ? 0.5 : 0.0;
    Box<S> sub;
    for (int j = 0; j < box.dim(); ++j) {
      double u1 = std::uniform_real_distribution<double>(-margin, 1 + margin)(rng);
      double u2 = std::uniform_real_distribution<double>(-margin, 1 + margin)(rng);
      if (u1 > u2) std::swap(u1, u2);
      if (u2 - u1 < 0.01) u2 = u1 + 0.01;
      sub.lo.push_back(box.lo[j] + S(u1) * box.width(j));
      sub.hi.push_back(box.lo[j] + S(u2) * box.width(j));
    }
    const Bernstein<S> r = p.restrict(sub);
    CHECK(r.domain().lo == sub.lo);
    CHECK(r.domain().hi == sub.hi);
    const S scale = std::max(maxAbs(p), maxAbs(r));
    for (int k = 0; k < 6; ++k) {
      const std::vector<S> x = randomPoint(rng, sub);
      S mag;
      const S expected = directEvaluate(p, x, &mag);
      CHECK(close(r.evaluate(x), expected, std::max(scale, mag), 16));
    }
  }
}

TEMPLATE_TEST_CASE("restrictInto gives restrict's form and reuses the output storage",
                   "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(15);
  // One output for forms of every dimension and degree in turn: whatever it held before, it
  // must come out as restrict's form, coefficient for coefficient.
  Bernstein<S> out;
  for (int trial = 0; trial < trials<S>(); ++trial) {
    const Box<S> box = randomBox<S>(rng, randomDim<S>(rng));
    const Bernstein<S> p = randomPoly(rng, box);
    Box<S> sub;
    for (int j = 0; j < box.dim(); ++j) {
      double u1 = std::uniform_real_distribution<double>(-0.25, 1.25)(rng);
      double u2 = std::uniform_real_distribution<double>(-0.25, 1.25)(rng);
      if (u1 > u2) std::swap(u1, u2);
      if (u2 - u1 < 0.01) u2 = u1 + 0.01;
      sub.lo.push_back(box.lo[j] + S(u1) * box.width(j));
      sub.hi.push_back(box.lo[j] + S(u2) * box.width(j));
    }
    const Bernstein<S> expected = p.restrict(sub);
    p.restrictInto(sub, out);
    CHECK(out.degrees() == expected.degrees());
    CHECK(out.domain().lo == expected.domain().lo);
    CHECK(out.domain().hi == expected.domain().hi);
    const auto same = [&] {
      return std::equal(out.coefficients().begin(), out.coefficients().end(),
                        expected.coefficients().begin(), expected.coefficients().end());
    };
    CHECK(same());
    // The same shape again: no new coefficient storage.
    const S* data = out.coefficients().data();
    p.restrictInto(sub, out);
    CHECK(out.coefficients().data() == data);
    CHECK(same());
  }
}

TEMPLATE_TEST_CASE("derivative: finite differences, product rule, variables", "[bernstein]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  constexpr bool kDouble = std::is_same_v<S, double>;
  std::mt19937 rng(6);
  for (int trial = 0; trial < trials<S>() / 2; ++trial) {
    const int n = randomDim<S>(rng, 1, 4);
    const Box<S> box = randomBox<S>(rng, n);
    const Bernstein<S> a = randomPoly(rng, box, 3), b = randomPoly(rng, box, 3);
    const int axis = std::uniform_int_distribution<int>(0, n - 1)(rng);
    const Bernstein<S> da = a.derivative(axis);
    CHECK(da.degree(axis) == std::max(0, a.degree(axis) - 1));
    // Central finite difference: loose in double, tight in Mpfr.
    const S h = S(kDouble ? 1e-6 : 1e-15) * box.width(axis);
    const S fdTol = S(kDouble ? 1e-6 : 1e-25);
    const S fdScale = (maxAbs(a) + 1) * S(4) / box.width(axis);
    // Product rule: d(ab) = a'b + ab'.
    const Bernstein<S> ab = a * b;
    const Bernstein<S> lhs = ab.derivative(axis);
    const Bernstein<S> rhs = da * b + a * b.derivative(axis);
    const S prScale =
        maxAbs(lhs) + maxAbs(da) * maxAbs(b) + maxAbs(a) * maxAbs(b.derivative(axis)) + 1;
    for (int k = 0; k < 5; ++k) {
      std::vector<S> x = randomPoint(rng, box), xp = x, xm = x;
      xp[axis] += h;
      xm[axis] -= h;
      const S fd = (a.evaluate(xp) - a.evaluate(xm)) / (2 * h);
      CHECK(absOf(S(da.evaluate(x) - fd)) <= fdTol * fdScale);
      CHECK(close(lhs.evaluate(x), rhs.evaluate(x), prScale, 32));
    }
    // d x_j / d x_axis = [j == axis].
    for (int j = 0; j < n; ++j) {
      const Bernstein<S> dv = Bernstein<S>::variable(box, j).derivative(axis);
      for (const S& c : dv.coefficients()) CHECK(close(c, S(j == axis ? 1 : 0), S(1)));
    }
  }
}

TEMPLATE_TEST_CASE("sum, difference, scaling, product and power identities", "[bernstein]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(7);
  for (int trial = 0; trial < trials<S>() / 2; ++trial) {
    const int n = randomDim<S>(rng, 1, 4);
    const Box<S> box = randomBox<S>(rng, n);
    const Bernstein<S> a = randomPoly(rng, box, 3), b = randomPoly(rng, box, 3);
    const S s = uniform<S>(rng, -3, 3);
    const Bernstein<S> sum = a + b, diff = a - b, prod = a * b, scaled = s * a, neg = -a;
    const Bernstein<S> cube = pow(a, 3), aaa = a * a * a;
    for (int j = 0; j < n; ++j) {
      CHECK(sum.degree(j) == std::max(a.degree(j), b.degree(j)));
      CHECK(prod.degree(j) == a.degree(j) + b.degree(j));
      CHECK(cube.degree(j) == 3 * a.degree(j));
    }
    const Bernstein<S> zero = a - a;
    CHECK(zero.degrees() == a.degrees());
    for (const S& c : zero.coefficients()) CHECK(c == 0);
    const S ma = maxAbs(a), mb = maxAbs(b);
    for (int k = 0; k < 5; ++k) {
      const std::vector<S> x = randomPoint(rng, box);
      const S av = directEvaluate(a, x), bv = directEvaluate(b, x);
      CHECK(close(sum.evaluate(x), S(av + bv), S(ma + mb), 8));
      CHECK(close(diff.evaluate(x), S(av - bv), S(ma + mb), 8));
      CHECK(close(prod.evaluate(x), S(av * bv), S(ma * mb), 32));
      CHECK(close(scaled.evaluate(x), S(s * av), S(absOf(s) * ma), 8));
      CHECK(close(neg.evaluate(x), S(-av), ma, 8));
      CHECK(close(cube.evaluate(x), S(av * av * av), S(ma * ma * ma), 64));
    }
    for (std::size_t i = 0; i < cube.size(); ++i)
      CHECK(close(cube.coefficients()[i], aaa.coefficients()[i], S(ma * ma * ma), 64));
    CHECK(pow(a, 0).evaluate(randomPoint(rng, box)) == 1);
    // In-place forms.
    Bernstein<S> acc = a;
    acc += b;
    acc -= b;
    acc *= S(2);
    const std::vector<S> x = randomPoint(rng, box);
    CHECK(close(acc.evaluate(x), S(2 * directEvaluate(a, x)), ma, 16));
  }
}

TEMPLATE_TEST_CASE("elevate keeps values; embed maps variables", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(8);
  for (int trial = 0; trial < trials<S>() / 2; ++trial) {
    const int n = randomDim<S>(rng, 1, 4);
    const Box<S> box = randomBox<S>(rng, n);
    const Bernstein<S> p = randomPoly(rng, box, 3);
    std::vector<int> degrees = p.degrees();
    for (int& d : degrees) d += std::uniform_int_distribution<int>(0, 3)(rng);
    const Bernstein<S> e = p.elevate(degrees);
    CHECK(e.degrees() == degrees);
    const S scale = maxAbs(p);
    // Degree elevation is a convex combination: the hull can only shrink.
    const auto [plo, phi] = p.coefficientRange();
    const auto [elo, ehi] = e.coefficientRange();
    CHECK(elo >= plo - S(relativeTolerance<S>()) * scale);
    CHECK(ehi <= phi + S(relativeTolerance<S>()) * scale);
    for (int k = 0; k < 5; ++k) {
      const std::vector<S> x = randomPoint(rng, box, 0.3);
      CHECK(close(e.evaluate(x), directEvaluate(p, x), scale, 16));
    }

    // Embed into N >= n variables at random distinct positions.
    const int N = n + std::uniform_int_distribution<int>(0, 2)(rng);
    std::vector<int> perm(N);
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    const std::vector<int> positions(perm.begin(), perm.begin() + n);
    Box<S> big = randomBox<S>(rng, N);
    for (int j = 0; j < n; ++j) {
      big.lo[positions[j]] = box.lo[j];
      big.hi[positions[j]] = box.hi[j];
    }
    const Bernstein<S> q = p.embed(big, positions);
    CHECK(q.dim() == N);
    for (int k = 0; k < 5; ++k) {
      const std::vector<S> y = randomPoint(rng, big);
      std::vector<S> x(n);
      for (int j = 0; j < n; ++j) x[j] = y[positions[j]];
      CHECK(close(q.evaluate(y), directEvaluate(p, x), scale, 4));
    }
  }
}

//! [bernstein-hull]
TEMPLATE_TEST_CASE("coefficient range encloses the restriction; excludesZero agrees", "[bernstein]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(9);
  int excluded = 0, notExcluded = 0;
  for (int trial = 0; trial < trials<S>(); ++trial) {
    const int n = randomDim<S>(rng, 1, 3);
    const Box<S> box = randomBox<S>(rng, n);
    // Offset the polynomial so that some restrictions exclude zero and some do not.
    Bernstein<S> p = randomPoly(rng, box, 3);
    p += Bernstein<S>::constant(box, uniform<S>(rng, -0.5, 0.5));
    Box<S> sub;
    const double margin = trial % 3 == 0 ? 0.3 : 0.0;
    const double maxWidth = trial % 2 ? 0.1 : 1.0;
    for (int j = 0; j < n; ++j) {
      const double w = std::uniform_real_distribution<double>(0.01, maxWidth)(rng);
      const double u = std::uniform_real_distribution<double>(-margin, 1 + margin - w)(rng);
      sub.lo.push_back(box.lo[j] + S(u) * box.width(j));
      sub.hi.push_back(box.lo[j] + S(u + w) * box.width(j));
    }
    const Bernstein<S> r = p.restrict(sub);
    const auto [lo, hi] = r.coefficientRange();
    const S slack = S(relativeTolerance<S>()) * (maxAbs(r) + 1);
    bool positive = false, negative = false;
    for (int k = 0; k < 200; ++k) {
      const std::vector<S> x = randomPoint(rng, sub);
      const S v = directEvaluate(p, x);
      CHECK(v >= lo - slack);
      CHECK(v <= hi + slack);
      positive |= v > slack;
      negative |= v < -slack;
    }
    if (r.excludesZero()) {
      ++excluded;
      CHECK(!(positive && negative));
      CHECK((lo > 0 || hi < 0));
    } else {
      ++notExcluded;
      CHECK((lo <= 0 && hi >= 0));
    }
    if (positive && negative) CHECK_FALSE(r.excludesZero());
  }
  // Both outcomes were exercised.
  CHECK(excluded > 0);
  CHECK(notExcluded > 0);
}
//! [bernstein-hull]

TEMPLATE_TEST_CASE("faceSlice fixes an axis at its lower or upper end", "[bernstein]",
                   NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(10);
  for (int trial = 0; trial < trials<S>() / 2; ++trial) {
    const int n = randomDim<S>(rng);
    const Box<S> box = randomBox<S>(rng, n);
    const Bernstein<S> p = randomPoly(rng, box);
    const int axis = std::uniform_int_distribution<int>(0, n - 1)(rng);
    for (bool upper : {false, true}) {
      const Bernstein<S> f = p.faceSlice(axis, upper);
      CHECK(f.dim() == n - 1);
      for (int k = 0; k < 4; ++k) {
        const std::vector<S> x = randomPoint(rng, box);
        std::vector<S> y = x;
        y.erase(y.begin() + axis);
        std::vector<S> xf = x;
        xf[axis] = upper ? box.hi[axis] : box.lo[axis];
        CHECK(close(f.evaluate(y), directEvaluate(p, xf), maxAbs(p), 4));
      }
    }
  }
}

TEMPLATE_TEST_CASE("faceSliceInto slices into an output of any earlier shape and reuses it",
                   "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(16);
  // One output for slices of every dimension and degree in turn: whatever it held before, it
  // must come out as the face's form (checked against p evaluated on the face).
  Bernstein<S> out;
  for (int trial = 0; trial < trials<S>() / 2; ++trial) {
    const int n = randomDim<S>(rng);
    const Box<S> box = randomBox<S>(rng, n);
    const Bernstein<S> p = randomPoly(rng, box);
    const int axis = std::uniform_int_distribution<int>(0, n - 1)(rng);
    const bool upper = rng() % 2 == 1;
    p.faceSliceInto(axis, upper, out);
    std::vector<int> degrees = p.degrees();
    degrees.erase(degrees.begin() + axis);
    CHECK(out.degrees() == degrees);
    for (int k = 0; k < 4; ++k) {
      const std::vector<S> x = randomPoint(rng, box);
      std::vector<S> y = x, xf = x;
      y.erase(y.begin() + axis);
      xf[axis] = upper ? box.hi[axis] : box.lo[axis];
      CHECK(close(out.evaluate(y), directEvaluate(p, xf), maxAbs(p), 4));
    }
    // The same slice again: no new coefficient storage, the same coefficients.
    const std::vector<S> first(out.coefficients().begin(), out.coefficients().end());
    const S* data = out.coefficients().data();
    p.faceSliceInto(axis, upper, out);
    CHECK(out.coefficients().data() == data);
    CHECK(std::equal(first.begin(), first.end(), out.coefficients().begin(),
                     out.coefficients().end()));
  }
}

TEMPLATE_TEST_CASE("misuse throws std::invalid_argument", "[bernstein]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(160);
  using S = TestType;
  std::mt19937 rng(11);
  const Box<S> box = randomBox<S>(rng, 2), other = randomBox<S>(rng, 2),
               box3 = randomBox<S>(rng, 3);
  const Bernstein<S> p = randomPoly(rng, box, std::vector<int>{2, 3});
  Bernstein<S> l, r;
  CHECK_THROWS_AS(Bernstein<S>(box, {1}), std::invalid_argument);
  CHECK_THROWS_AS(Bernstein<S>(box, {1, -1}), std::invalid_argument);
  CHECK_THROWS_AS((Bernstein<S>(Box<S>{{S(1)}, {S(1)}}, {1})), std::invalid_argument);
  CHECK_THROWS_AS(Bernstein<S>::variable(box, 2), std::invalid_argument);
  CHECK_THROWS_AS(p.stride(-1), std::invalid_argument);
  CHECK_THROWS_AS(p.coefficient(std::vector<int>{0}), std::invalid_argument);
  CHECK_THROWS_AS(p.coefficient(std::vector<int>{3, 0}), std::invalid_argument);
  CHECK_THROWS_AS(p.evaluate(std::vector<S>{S(0)}), std::invalid_argument);
  CHECK_THROWS_AS(p.derivative(2), std::invalid_argument);
  CHECK_THROWS_AS(p.split(-1, S(0.5), l, r), std::invalid_argument);
  CHECK_THROWS_AS(p.split(0, S(1), l, r), std::invalid_argument);
  CHECK_THROWS_AS(p.split(0, S(0.5), l, l), std::invalid_argument);
  CHECK_THROWS_AS(p.halve(5, l, r), std::invalid_argument);
  CHECK_THROWS_AS(p.restrict(box3), std::invalid_argument);
  CHECK_THROWS_AS(p.restrict(Box<S>{box.hi, box.lo}), std::invalid_argument);
  CHECK_THROWS_AS(p.faceSlice(2, true), std::invalid_argument);
  Bernstein<S> self = p;
  CHECK_THROWS_AS(self.faceSliceInto(0, true, self), std::invalid_argument);
  CHECK_THROWS_AS(p.elevate(std::vector<int>{1, 3}), std::invalid_argument);
  CHECK_THROWS_AS(p.elevate(std::vector<int>{2}), std::invalid_argument);
  CHECK_THROWS_AS(p.embed(box3, std::vector<int>{0, 0}), std::invalid_argument);
  CHECK_THROWS_AS(p.embed(box3, std::vector<int>{0, 3}), std::invalid_argument);
  CHECK_THROWS_AS(p.embed(box3, std::vector<int>{0, 1}), std::invalid_argument);  // box differs
  const Bernstein<S> q = randomPoly(rng, other, 2), q3 = randomPoly(rng, box3, 2);
  Bernstein<S> acc = p;
  CHECK_THROWS_AS(acc += q, std::invalid_argument);
  CHECK_THROWS_AS(acc -= q3, std::invalid_argument);
  CHECK_THROWS_AS(p * q, std::invalid_argument);
  CHECK_THROWS_AS(p * q3, std::invalid_argument);
  CHECK_THROWS_AS(pow(p, -1), std::invalid_argument);
}

TEST_CASE("Mpfr: results follow a raised working precision", "[bernstein][mpfr]") {
  using S = ndc::Mpfr;
  ndc::test::PrecisionScope<S> outer(64);
  Box<S> box{{S(0), S(0)}, {S(1), S(3)}};
  {
    // Warm the per-thread temporaries at low precision.
    Bernstein<S> p(box, {2, 2}), l, r;
    p.halve(0, l, r);
    (void)p.evaluate(std::vector<S>{S(0.5), S(0.5)});
  }
  ndc::test::PrecisionScope<S> inner(400);
  const S third = S(1) / 3;
  Bernstein<S> p(box, {3, 2});
  for (S& c : p.coefficients()) c = third;  // the constant 1/3
  const std::vector<S> x{S(1) / 7, S(2) / 7};
  Bernstein<S> l, r;
  p.split(1, S(1) / 3, l, r);
  const S tol = ldexp(S(1), -380);
  CHECK(abs(p.evaluate(x) - third) < tol);
  CHECK(abs(l.evaluate(x) - third) < tol);
  CHECK(abs(p.restrict(Box<S>{{S(1) / 9, S(1) / 5}, {S(1) / 2, S(2)}}).evaluate(x) - third) < tol);
}
