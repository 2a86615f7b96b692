// Rounding bounds of Bernstein forms built in double (see form_rounding.hpp).
#include "framework/numeric/form_rounding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <mpfr.h>

namespace ndc {

namespace {

constexpr double kUnit = 0x1p-53;       // u: unit round-off of double
constexpr double kTiny = 0x1p-1074;     // an underflowing product's absolute error
constexpr double kUp = 1 + 16 * kUnit;  // covers the rounding of the bound's own sums
constexpr double kInf = std::numeric_limits<double>::infinity();

/// gamma_k = k u / (1 - k u), rounded up; infinite where k u is not small (no bound).
double gamma(double k) {
  if (!(k * kUnit < 0.5)) return kInf;
  return k * kUnit / (1 - k * kUnit) * kUp;
}

double largest(const Bernstein<double>& f) {
  double m = 0;
  for (double c : f.coefficients()) m = std::max(m, std::abs(c));
  return std::isfinite(m) ? m : kInf;  // NaN counts as infinite
}

/// The largest entry of Pascal's row d (exact in double for the degrees used).
double largestBinomial(int d) {
  double c = 1;
  for (int i = 1; i <= d / 2; ++i) c = c * (d - i + 1) / i;
  return c;
}

/// Elevation of `f` (bound e, magnitude m) to `degrees`, axis by axis as Bernstein::elevate:
/// the new bound, with m updated to bound the elevated coefficients.
double elevated(const Bernstein<double>& f, double e, double& m, const std::vector<int>& degrees) {
  for (int j = 0; j < f.dim(); ++j) {
    const int d = f.degree(j);
    if (d == degrees[j] || d == 0) continue;  // from degree 0 every weight is exactly 1
    const double g = gamma(d + 2);
    e = (e + g * m + (d + 1) * kTiny) * kUp;
    m = m * (1 + g) * kUp;
  }
  return e;
}

/// |double - literal|: 0 where the double is the literal (integers, 0.5, a double's exact
/// digits), else the distance to the outward-rounded enclosure read with it.
double literalError(const TapeConstant& c) {
  if (c.literal.empty()) return 0;  // Expression::constant: the double itself
  mpfr_t v;
  mpfr_init2(v, 64);
  char* end = nullptr;
  const int inexact = mpfr_strtofr(v, c.literal.c_str(), &end, 10, MPFR_RNDN);
  const bool exact = inexact == 0 && *end == '\0' && mpfr_cmp_d(v, c.value) == 0;
  mpfr_clear(v);
  if (exact) return 0;
  // lower <= literal <= upper, so the literal is within this of the double.
  return std::max(c.value - c.lower, c.upper - c.value) * kUp;
}

}  // namespace

double FormRounding::pop() {
  const double e = errors_.back();
  errors_.pop_back();
  return e;
}

void FormRounding::constant(const TapeConstant& c) { errors_.push_back(literalError(c)); }

void FormRounding::unbounded() { errors_.push_back(kInf); }

void FormRounding::divide() {
  pop();
  errors_.back() = kInf;
}

void FormRounding::sum(const Bernstein<double>& a, const Bernstein<double>& b) {
  const double eb = pop(), ea = pop();
  std::vector<int> d(a.degrees());
  for (int j = 0; j < a.dim(); ++j) d[j] = std::max(d[j], b.degree(j));
  double ma = largest(a), mb = largest(b);
  const double e = elevated(a, ea, ma, d) + elevated(b, eb, mb, d);
  // One rounding of each coefficient of the sum, |a + b| <= ma + mb.
  errors_.push_back((e + kUnit * (ma + mb)) * kUp);
}

double FormRounding::productBound(const Bernstein<double>& a, double ea, const Bernstein<double>& b,
                                  double eb) {
  const double ma = largest(a), mb = largest(b);
  // Roundings per coefficient: scalings by rows of degree >= 3 (other rows hold only 1 and 2),
  // the N products and N - 1 additions into it, and the divisions by C(d + e, K).
  double rounding = 0, terms = 1, ca = 1, cb = 1;
  for (int j = 0; j < a.dim(); ++j) {
    const int da = a.degree(j), db = b.degree(j);
    rounding += (da >= 3) + (db >= 3) + (da + db >= 3);
    terms *= std::min(da, db) + 1;
    ca *= largestBinomial(da);
    cb *= largestBinomial(db);
  }
  rounding += terms;
  // |sum w (a + da)(b + db) - sum w a b| <= ea mb + (ma + ea) eb, the weights summing to 1;
  // an underflowing scaling (by any factor but 1, powers of 2 included), product or division
  // errs by kTiny, scaled at most by the other factor.
  const double propagated = ea * mb + (ma + ea) * eb;
  const double multiplications = 3.0 * a.dim() + terms;
  const double underflow = multiplications * kTiny * (1 + ca * ma) * (1 + cb * mb);
  return (propagated + gamma(rounding) * ma * mb + underflow) * kUp;
}

void FormRounding::product(const Bernstein<double>& a, const Bernstein<double>& b) {
  const double eb = pop(), ea = pop();
  errors_.push_back(productBound(a, ea, b, eb));
}

Bernstein<double> FormRounding::power(const Bernstein<double>& a, int exponent) {
  // The loop of pow() (bernstein.inl), with each product's bound.
  double ea = pop();
  Bernstein<double> result = Bernstein<double>::constant(a.domain(), 1.0);
  double er = 0;
  if (exponent == 0) {
    errors_.push_back(0);
    return result;
  }
  Bernstein<double> base = a;
  bool first = true;
  while (true) {
    if (exponent & 1) {
      if (first) {
        result = base;
        er = ea;
      } else {
        er = productBound(result, er, base, ea);
        result = result * base;
      }
      first = false;
    }
    exponent >>= 1;
    if (exponent == 0) break;
    ea = productBound(base, ea, base, ea);
    base = base * base;
  }
  errors_.push_back(er);
  return result;
}

double FormRounding::relative(const Bernstein<double>& form, double error) {
  const double m = largest(form);
  if (!std::isfinite(error) || !std::isfinite(m)) return kInf;
  if (m == 0 && error == 0) return 0;
  if (!(error < m)) return kInf;
  // The largest exact coefficient is at least m - error (rounded down by kUp's margin).
  return error / (m - error) * kUp * kUp;
}

}  // namespace ndc
