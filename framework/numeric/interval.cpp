// Interval<double> on Boost.Interval with hardware directed rounding, Interval<Mpfr> on MPFI.
//
// The rounding-mode switches of Boost.Interval are only honoured if the compiler does not move
// or merge floating-point operations across them, so this file is compiled with
// -frounding-math (GCC) whatever the global flags say.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("rounding-math")
#endif

#include "framework/numeric/interval.hpp"

#include <mpfi.h>

#include <boost/numeric/interval.hpp>

#if defined(__x86_64__) && defined(__SSE2_MATH__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace ndc {

namespace {

namespace bi = boost::numeric::interval_lib;

#if defined(__x86_64__) && defined(__SSE2_MATH__)
/// Rounding control for double on x86-64, where double arithmetic is SSE2 and obeys MXCSR only:
/// reads and writes the MXCSR rounding bits, where fesetround (Boost's default) also reloads
/// the x87 control word, which double arithmetic never uses and which costs several times
/// more. The switches are out-of-line calls, as opaque to the optimiser as fesetround.
struct MxcsrRounding {
  using rounding_mode = unsigned;
  [[gnu::noinline]] static void set_rounding_mode(rounding_mode mode) { _mm_setcsr(mode); }
  [[gnu::noinline]] static void get_rounding_mode(rounding_mode& mode) { mode = _mm_getcsr(); }
  static void downward() { setBits(0x2000u); }
  static void upward() { setBits(0x4000u); }
  static void to_nearest() { setBits(0u); }
  static void toward_zero() { setBits(0x6000u); }
  static double force_rounding(const double& r) {
    volatile double v = r;
    return v;
  }
  static double to_int(const double& r) { return std::rint(r); }

 private:
  /// Bits 13-14 of MXCSR: 00 nearest, 01 down, 10 up, 11 toward zero.
  static void setBits(unsigned bits) {
    rounding_mode mode;
    get_rounding_mode(mode);
    set_rounding_mode((mode & ~0x6000u) | bits);
  }
};
using DoubleRounding = MxcsrRounding;
#else
using DoubleRounding = bi::rounding_control<double>;
#endif

/// Boost interval with directed hardware rounding, the rounding mode saved and set upward
/// before each operation and restored after it (the rest of the program runs in
/// round-to-nearest). Boost's "opposite" rounding computes every lower bound as
/// -RU(-x op y) = RD(x op y): the same bounds as switching down and up per bound, bit for bit,
/// with one switch fewer per operation.
using BoostInterval = boost::numeric::interval<
    double, bi::policies<bi::save_state<bi::rounded_arith_opp<double, DoubleRounding>>,
                         bi::checking_base<double>>>;
/// Boost interval for kernels that set upward rounding once (`UpwardScope` around the kernel):
/// the same operations as BoostInterval without the switch per operation.
using FastInterval = boost::numeric::interval<
    double, bi::policies<bi::save_state_nothing<bi::rounded_arith_opp<double, DoubleRounding>>,
                         bi::checking_base<double>>>;
/// Upward rounding for the lifetime of the object, then the mode before it.
using UpwardScope = bi::save_state<bi::rounded_arith_opp<double, DoubleRounding>>;

// A double literal's value when it is exactly representable, found without big-number
// arithmetic: the literal is M * 10^e with an integer significand M; it is a double iff
// M * 10^e is an integer below 2^53, or 5^-e divides M (then it is M / 5^-e / 2^-e).
std::optional<double> exactDouble(std::string_view text) {
  std::size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
  std::uint64_t m = 0;
  int digits = 0, e = 0;
  bool any = false, dot = false;
  for (; i < text.size(); ++i) {
    char c = text[i];
    if (c == '.' && !dot) {
      dot = true;
      continue;
    }
    if (c < '0' || c > '9') break;
    any = true;
    if (m == 0 && c == '0') {  // leading zeros carry no digits
      if (dot) --e;
      continue;
    }
    if (++digits > 19) return std::nullopt;
    m = m * 10 + static_cast<std::uint64_t>(c - '0');
    if (dot) --e;
  }
  if (!any) return std::nullopt;
  if (i < text.size()) {
    if (text[i] != 'e' && text[i] != 'E') return std::nullopt;
    ++i;
    bool expNegative = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) expNegative = text[i++] == '-';
    if (i == text.size()) return std::nullopt;
    int x = 0;
    for (; i < text.size(); ++i) {
      if (text[i] < '0' || text[i] > '9' || x > 100000) return std::nullopt;
      x = x * 10 + (text[i] - '0');
    }
    e += expNegative ? -x : x;
  }
  if (m == 0) return negative ? -0.0 : 0.0;
  while (m % 10 == 0) {
    m /= 10;
    ++e;
  }
  constexpr std::uint64_t kLimit = std::uint64_t(1) << 53;
  if (e >= 0) {
    for (; e > 0; --e) {
      if (m >= kLimit) return std::nullopt;
      m *= 10;
    }
    if (m > kLimit) return std::nullopt;
    double v = static_cast<double>(m);
    return negative ? -v : v;
  }
  if (e < -27) return std::nullopt;  // 5^28 exceeds 2^64
  std::uint64_t five = 1;
  for (int k = 0; k < -e; ++k) five *= 5;
  if (m % five != 0) return std::nullopt;
  m /= five;
  if (m > kLimit) return std::nullopt;
  double v = std::ldexp(static_cast<double>(m), e);
  return negative ? -v : v;
}

// An MPFR view of an Mpfr (Boost keeps the mpfr_t inside the backend).
mpfr_srcptr fr(const Mpfr& v) { return v.backend().data(); }
mpfr_ptr fr(Mpfr& v) { return v.backend().data(); }

mpfr_prec_t currentPrecision() { return static_cast<mpfr_prec_t>(mpfrPrecision()); }

// Checks that `text` is a complete decimal literal for MPFR and returns it null-terminated.
std::string checkedLiteral(std::string_view text) {
  std::string s(text);
  // A decimal literal starts (after its sign) with a digit or a point: no "inf", "nan".
  std::size_t first = !s.empty() && (s[0] == '+' || s[0] == '-') ? 1 : 0;
  if (first >= s.size() || !(std::isdigit(static_cast<unsigned char>(s[first])) || s[first] == '.'))
    throw std::invalid_argument("not a decimal number: '" + s + "'");
  mpfr_t probe;
  mpfr_init2(probe, 8);
  char* end = nullptr;
  mpfr_strtofr(probe, s.c_str(), &end, 10, MPFR_RNDN);
  bool ok = !s.empty() && end == s.c_str() + s.size() && !mpfr_nan_p(probe);
  mpfr_clear(probe);
  if (!ok) throw std::invalid_argument("not a decimal number: '" + s + "'");
  return s;
}

// ---- Backends: one struct of static operations per scalar type ----------------------------

// Interval<double>: Boost.Interval.
struct DoubleBackend {
  using Value = BoostInterval;
  static void initZero(Value* p) { new (p) Value(0.0); }
  static void initPoint(Value* p, double x) { new (p) Value(x); }
  static void initPair(Value* p, double lo, double hi) { new (p) Value(lo, hi); }
  static void initCopy(Value* p, const Value& o) { new (p) Value(o); }
  static void initString(Value* p, std::string_view text) {
    if (auto exact = exactDouble(text)) return initPoint(p, *exact);
    std::string s = checkedLiteral(text);
    // strtod rounds to nearest, so the literal lies within one ulp of the result.
    double v = std::strtod(s.c_str(), nullptr);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    initPair(p, std::nextafter(v, -kInf), std::nextafter(v, kInf));
  }
  static void destroy(Value& v) { v.~Value(); }
  static void assign(Value& v, const Value& o) { v = o; }
  static void moveAssign(Value& v, Value& o) { v = o; }
  static double lower(const Value& v) { return v.lower(); }
  static double upper(const Value& v) { return v.upper(); }
  // Boost's median switches to round-to-nearest and back; the program already runs in
  // round-to-nearest outside the kernels below (every switch is scoped), so (l + u) / 2 is the
  // same value without the switches.
  static double midpoint(const Value& v) {
    if (bi::detail::test_input(v)) return std::numeric_limits<double>::quiet_NaN();
    return (v.lower() + v.upper()) / 2;
  }
  static double width(const Value& v) { return boost::numeric::width(v); }
  static bool contains(const Value& v, double x) { return boost::numeric::in(x, v); }
  // A NaN end (inf - inf after an overflow) is no information, not an empty set: such an
  // interval may hold zero, so no test concludes from it that F has no root or J is regular.
  static bool containsZero(const Value& v) {
    return std::isnan(v.lower()) || std::isnan(v.upper()) || boost::numeric::zero_in(v);
  }
  static void add(Value& v, const Value& o) { v += o; }
  static void sub(Value& v, const Value& o) { v -= o; }
  static void mul(Value& v, const Value& o) { v *= o; }
  static void neg(Value& r, const Value& v) { r = -v; }
  static void pow(Value& r, const Value& v, int n) { r = boost::numeric::pow(v, n); }
  static void divide(Value& r, const Value& v, double d) { r = v / d; }
  static void hull(Value& r, const Value& a, const Value& b) { r = boost::numeric::hull(a, b); }
};

// Interval<Mpfr>: MPFI. Every interval is created at the current Mpfr precision; copies keep
// their source's.
struct MpfrBackend {
  using Value = __mpfi_struct;
  static void initZero(Value* p) {
    mpfi_init2(p, currentPrecision());
    mpfi_set_ui(p, 0);
  }
  static void initPoint(Value* p, const Mpfr& x) {
    mpfi_init2(p, currentPrecision());
    mpfi_set_fr(p, fr(x));
  }
  static void initPair(Value* p, const Mpfr& lo, const Mpfr& hi) {
    mpfi_init2(p, currentPrecision());
    mpfi_interv_fr(p, fr(lo), fr(hi));
  }
  static void initCopy(Value* p, const Value& o) {
    mpfi_init2(p, mpfi_get_prec(&o));
    mpfi_set(p, &o);
  }
  static void initString(Value* p, std::string_view text) {
    std::string s = checkedLiteral(text);
    initZero(p);
    // Each end parsed with its own directed rounding: the tightest enclosure.
    mpfr_strtofr(&p->left, s.c_str(), nullptr, 10, MPFR_RNDD);
    mpfr_strtofr(&p->right, s.c_str(), nullptr, 10, MPFR_RNDU);
  }
  static void destroy(Value& v) { mpfi_clear(&v); }
  static void assign(Value& v, const Value& o) {
    if (&v == &o) return;
    if (mpfi_get_prec(&v) != mpfi_get_prec(&o)) mpfi_set_prec(&v, mpfi_get_prec(&o));
    mpfi_set(&v, &o);
  }
  static void moveAssign(Value& v, Value& o) { mpfi_swap(&v, &o); }
  static Mpfr lower(const Value& v) {
    Mpfr r;
    mpfi_get_left(fr(r), &v);
    return r;
  }
  static Mpfr upper(const Value& v) {
    Mpfr r;
    mpfi_get_right(fr(r), &v);
    return r;
  }
  static Mpfr midpoint(const Value& v) {
    Mpfr r;
    mpfi_mid(fr(r), &v);
    // Rounding to a lower precision than the interval's could step outside it.
    if (mpfr_less_p(fr(r), &v.left)) mpfr_set(fr(r), &v.left, MPFR_RNDU);
    if (mpfr_greater_p(fr(r), &v.right)) mpfr_set(fr(r), &v.right, MPFR_RNDD);
    return r;
  }
  static Mpfr width(const Value& v) {
    Mpfr r;
    mpfr_sub(fr(r), &v.right, &v.left, MPFR_RNDU);
    return r;
  }
  static bool contains(const Value& v, const Mpfr& x) { return mpfi_is_inside_fr(fr(x), &v) != 0; }
  // As for double: a NaN end may hold zero.
  static bool containsZero(const Value& v) { return mpfi_nan_p(&v) || mpfi_has_zero(&v) != 0; }
  static void add(Value& v, const Value& o) { mpfi_add(&v, &v, &o); }
  static void sub(Value& v, const Value& o) { mpfi_sub(&v, &v, &o); }
  static void mul(Value& v, const Value& o) { mpfi_mul(&v, &v, &o); }
  static void neg(Value& r, const Value& v) { mpfi_neg(&r, &v); }
  static void pow(Value& r, const Value& v, int exponent) {
    unsigned long n = static_cast<unsigned long>(exponent);
    if (n == 0) {
      mpfi_set_ui(&r, 1);
    } else if (n % 2 == 1 || mpfr_sgn(&v.left) >= 0) {
      // Increasing on the whole interval: map the ends with directed rounding.
      mpfr_pow_ui(&r.left, &v.left, n, MPFR_RNDD);
      mpfr_pow_ui(&r.right, &v.right, n, MPFR_RNDU);
    } else if (mpfr_sgn(&v.right) <= 0) {
      // Even power of a non-positive interval: decreasing.
      mpfr_pow_ui(&r.left, &v.right, n, MPFR_RNDD);
      mpfr_pow_ui(&r.right, &v.left, n, MPFR_RNDU);
    } else {
      // Even power across zero: [0, max(|lo|, |hi|)^n].
      mpfr_srcptr far = mpfr_cmpabs(&v.left, &v.right) > 0 ? &v.left : &v.right;
      mpfr_pow_ui(&r.right, far, n, MPFR_RNDU);
      mpfr_set_ui(&r.left, 0, MPFR_RNDD);
    }
  }
  static void divide(Value& r, const Value& v, const Mpfr& d) { mpfi_div_fr(&r, &v, fr(d)); }
  static void hull(Value& r, const Value& a, const Value& b) { mpfi_union(&r, &a, &b); }
};

template <class S>
using Backend = std::conditional_t<std::is_same_v<S, double>, DoubleBackend, MpfrBackend>;

}  // namespace

// The backend value lives in the object's own storage: no heap object per interval.
template <class S>
struct Interval<S>::Impl {
  typename Backend<S>::Value v;
};

template <class S>
typename Interval<S>::Impl& Interval<S>::impl() {
  return *std::launder(reinterpret_cast<Impl*>(storage_));
}
template <class S>
const typename Interval<S>::Impl& Interval<S>::impl() const {
  return *std::launder(reinterpret_cast<const Impl*>(storage_));
}

template <class S>
Interval<S>::Interval() {
  static_assert(sizeof(Impl) <= sizeof(storage_) && alignof(Impl) <= 16);
  Backend<S>::initZero(&reinterpret_cast<Impl*>(storage_)->v);
}
template <class S>
Interval<S>::Interval(const S& point) {
  Backend<S>::initPoint(&reinterpret_cast<Impl*>(storage_)->v, point);
}
template <class S>
Interval<S>::Interval(const S& lower, const S& upper) {
  if (!(lower <= upper)) throw std::invalid_argument("Interval: lower > upper (or NaN)");
  Backend<S>::initPair(&reinterpret_cast<Impl*>(storage_)->v, lower, upper);
}
template <class S>
Interval<S> Interval<S>::fromString(std::string_view text) {
  Interval r;
  Backend<S>::destroy(r.impl().v);
  try {
    Backend<S>::initString(&r.impl().v, text);
  } catch (...) {
    Backend<S>::initZero(&r.impl().v);  // keep r destructible
    throw;
  }
  return r;
}
template <class S>
Interval<S>::Interval(const Interval& o) {
  Backend<S>::initCopy(&reinterpret_cast<Impl*>(storage_)->v, o.impl().v);
}
template <class S>
Interval<S>::Interval(Interval&& o) noexcept {
  // MPFI has no cheap "empty" state to leave behind, so a move constructs a copy.
  Backend<S>::initCopy(&reinterpret_cast<Impl*>(storage_)->v, o.impl().v);
}
template <class S>
Interval<S>& Interval<S>::operator=(const Interval& o) {
  Backend<S>::assign(impl().v, o.impl().v);
  return *this;
}
template <class S>
Interval<S>& Interval<S>::operator=(Interval&& o) noexcept {
  Backend<S>::moveAssign(impl().v, o.impl().v);
  return *this;
}
template <class S>
Interval<S>::~Interval() {
  Backend<S>::destroy(impl().v);
}

template <class S>
S Interval<S>::lower() const {
  return Backend<S>::lower(impl().v);
}
template <class S>
S Interval<S>::upper() const {
  return Backend<S>::upper(impl().v);
}
template <class S>
S Interval<S>::midpoint() const {
  return Backend<S>::midpoint(impl().v);
}
template <class S>
S Interval<S>::width() const {
  return Backend<S>::width(impl().v);
}
template <class S>
bool Interval<S>::contains(const S& v) const {
  return Backend<S>::contains(impl().v, v);
}
template <class S>
bool Interval<S>::containsZero() const {
  return Backend<S>::containsZero(impl().v);
}

template <class S>
Interval<S>& Interval<S>::operator+=(const Interval& o) {
  Backend<S>::add(impl().v, o.impl().v);
  return *this;
}
template <class S>
Interval<S>& Interval<S>::operator-=(const Interval& o) {
  Backend<S>::sub(impl().v, o.impl().v);
  return *this;
}
template <class S>
Interval<S>& Interval<S>::operator*=(const Interval& o) {
  Backend<S>::mul(impl().v, o.impl().v);
  return *this;
}
template <class S>
Interval<S> Interval<S>::operator-() const {
  Interval r(*this);
  Backend<S>::neg(r.impl().v, impl().v);
  return r;
}
template <class S>
Interval<S> Interval<S>::pow(int exponent) const {
  if (exponent < 0) throw std::invalid_argument("Interval::pow: negative exponent");
  Interval r(*this);
  Backend<S>::pow(r.impl().v, impl().v, exponent);
  return r;
}
template <class S>
Interval<S> Interval<S>::dividedBy(const S& divisor) const {
  if (divisor == 0) throw std::domain_error("Interval::dividedBy: division by zero");
  Interval r(*this);
  Backend<S>::divide(r.impl().v, impl().v, divisor);
  return r;
}
template <class S>
Interval<S> Interval<S>::hull(const Interval& o) const {
  Interval r(*this);
  Backend<S>::hull(r.impl().v, impl().v, o.impl().v);
  return r;
}

template class Interval<double>;
template class Interval<Mpfr>;

// ---- Kernels with one rounding-mode switch ------------------------------------------------------

Interval<double> tensorDeCasteljauEnclosure(std::span<const double> coefficients,
                                            std::span<const int> degrees,
                                            const Interval<double>* t) {
  constexpr std::size_t kMaxAxes = 16;
  if (degrees.size() > kMaxAxes) throw std::invalid_argument("tensorDeCasteljauEnclosure: axes");
  double tLower[kMaxAxes], tUpper[kMaxAxes];
  for (std::size_t a = 0; a < degrees.size(); ++a)
    tLower[a] = t[a].lower(), tUpper[a] = t[a].upper();
  using Fast = FastInterval;
  thread_local std::vector<Fast> work;
  work.assign(coefficients.begin(), coefficients.end());
  double lower = 0, upper = 0;
  {
    const UpwardScope upward;
    std::size_t count = work.size();
    for (std::size_t a = 0; a < degrees.size(); ++a) {
      // Axis a is the fastest axis of what is left: blocks of d + 1 values, each reduced to one.
      const Fast ta(tLower[a], tUpper[a]);
      const int d = degrees[a];
      const std::size_t block = static_cast<std::size_t>(d) + 1, blocks = count / block;
      for (std::size_t b = 0; b < blocks; ++b) {
        Fast* w = &work[b * block];
        for (int r = 1; r <= d; ++r)
          for (int i = 0; i + r <= d; ++i) {
            Fast difference = w[i + 1];
            difference -= w[i];
            Fast step = ta;
            step *= difference;
            w[i] += step;
          }
        if (b) work[b] = w[0];
      }
      count = blocks;
    }
    lower = work[0].lower();
    upper = work[0].upper();
  }
  // An overflow (inf - inf) leaves a NaN end: the only enclosure left is the whole line.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (std::isnan(lower) || std::isnan(upper)) return Interval<double>(-kInf, kInf);
  return Interval<double>(lower, upper);
}

double identityResidualNorm(int m, std::span<const double> y,
                            std::span<const Interval<double>> matrix, std::size_t stride,
                            std::span<const int> columns) {
  // A's entries read once (no rounding involved), then row by row the operations of the
  // per-operation reference, under one switch to upward rounding.
  // Per-thread scratch: no allocation once warm, any m.
  thread_local std::vector<double> lower, upper;
  lower.resize(std::size_t(m) * m);
  upper.resize(std::size_t(m) * m);
  for (int l = 0; l < m; ++l)
    for (int j = 0; j < m; ++j) {
      const Interval<double>& a = matrix[std::size_t(l) * stride + std::size_t(columns[j])];
      lower[l * m + j] = a.lower();
      upper[l * m + j] = a.upper();
    }
  const UpwardScope upward;
  double norm = 0;
  for (int i = 0; i < m; ++i) {
    FastInterval row(0.0);
    for (int j = 0; j < m; ++j) {
      FastInterval r(i == j ? 1.0 : 0.0);
      for (int l = 0; l < m; ++l) {
        FastInterval product(y[std::size_t(l) * m + i]);
        product *= FastInterval(lower[l * m + j], upper[l * m + j]);
        r -= product;
      }
      row += FastInterval(std::max<double>(std::abs(r.lower()), std::abs(r.upper())));
    }
    const double bound = row.upper();
    if (std::isnan(bound)) return bound;
    norm = std::max(norm, bound);
  }
  return norm;
}

Interval<double> scaledQuotient(const Interval<double>& a, double factor, double divisor) {
  if (divisor == 0) throw std::domain_error("Interval::dividedBy: division by zero");
  FastInterval r(a.lower(), a.upper());
  {
    const UpwardScope upward;
    r *= FastInterval(factor);
    r = r / divisor;
  }
  if (std::isnan(r.lower()) || std::isnan(r.upper())) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    return Interval<double>(-kInf, kInf);
  }
  return Interval<double>(r.lower(), r.upper());
}

void krawczykOperator(int m, std::span<const double> y, std::span<const double> inverse,
                      std::span<const Interval<double>> fy, std::span<const Interval<double>> jx,
                      std::span<const double> lo, std::span<const double> hi,
                      std::span<double> kLower, std::span<double> kUpper) {
  // The interval inputs read once (no rounding involved), into per-thread scratch: no
  // allocation once warm, any m.
  thread_local std::vector<FastInterval> f, j, shift;
  f.resize(std::size_t(m));
  j.resize(std::size_t(m) * m);
  shift.resize(std::size_t(m));
  for (int l = 0; l < m; ++l) f[l] = FastInterval(fy[l].lower(), fy[l].upper());
  for (int e = 0; e < m * m; ++e) j[e] = FastInterval(jx[e].lower(), jx[e].upper());
  const UpwardScope upward;
  // X - y, outward.
  for (int c = 0; c < m; ++c) shift[c] = FastInterval(lo[c], hi[c]) - FastInterval(y[c]);
  for (int i = 0; i < m; ++i) {
    FastInterval k(y[i]);
    for (int l = 0; l < m; ++l) k -= FastInterval(inverse[std::size_t(l) * m + i]) * f[l];
    for (int c = 0; c < m; ++c) {
      FastInterval a(i == c ? 1.0 : 0.0);
      for (int l = 0; l < m; ++l) a -= FastInterval(inverse[std::size_t(l) * m + i]) * j[l * m + c];
      k += a * shift[c];
    }
    kLower[i] = k.lower();
    kUpper[i] = k.upper();
  }
}

}  // namespace ndc
