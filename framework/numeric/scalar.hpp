/// \file scalar.hpp
/// The two scalar types of ndcontour: `double` and the run-time-precision MPFR float.
#pragma once

#include <boost/multiprecision/mpfr.hpp>

#include <string>
#include <string_view>

namespace ndc {

/// Multiprecision scalar: MPFR backend, precision chosen at run time, no expression templates.
using Mpfr = boost::multiprecision::number<boost::multiprecision::mpfr_float_backend<0>,
                                           boost::multiprecision::et_off>;

/// Sets the precision of every Mpfr created afterwards on this thread (in bits; Boost stores
/// decimal digits, so the effective precision is rounded up to the next representable value).
/// Returns the effective precision in bits.
unsigned setMpfrPrecision(unsigned bits);

/// The precision, in bits, that a newly created Mpfr has.
unsigned mpfrPrecision();

/// Properties of a scalar type used by the numeric code.
template <class S>
struct ScalarTraits;

template <>
struct ScalarTraits<double> {
  static constexpr const char* kName = "double";
  /// Unit round-off of the working precision.
  static double epsilon() { return 0x1p-52; }
  static unsigned precisionBits() { return 53; }
  /// Parses a decimal literal to the nearest scalar; throws std::invalid_argument.
  static double fromString(std::string_view text);
  static double toDouble(double v) { return v; }
};

template <>
struct ScalarTraits<Mpfr> {
  static constexpr const char* kName = "mpfr";
  static Mpfr epsilon();
  static unsigned precisionBits() { return mpfrPrecision(); }
  static Mpfr fromString(std::string_view text);
  static double toDouble(const Mpfr& v) { return v.convert_to<double>(); }
};

/// Converts any scalar to double (for output and diagnostics).
template <class S>
double toDouble(const S& v) {
  return ScalarTraits<S>::toDouble(v);
}

}  // namespace ndc
