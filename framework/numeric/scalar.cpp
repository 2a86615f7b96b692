#include "framework/numeric/scalar.hpp"

#include <boost/multiprecision/detail/digits.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace ndc {

unsigned setMpfrPrecision(unsigned bits) {
  // Boost keeps the default precision in decimal digits: take the fewest digits whose
  // binary precision reaches the requested bits.
  unsigned digits10 = boost::multiprecision::detail::digits2_2_10(bits);
  while (boost::multiprecision::detail::digits10_2_2(digits10) < bits) ++digits10;
  Mpfr::default_precision(digits10);
  return mpfrPrecision();
}

unsigned mpfrPrecision() {
  return static_cast<unsigned>(
      boost::multiprecision::detail::digits10_2_2(Mpfr::default_precision()));
}

double ScalarTraits<double>::fromString(std::string_view text) {
  // strtod, not stod: a literal below DBL_MIN (1e-320) is a subnormal or 0 with ERANGE, which
  // stod reports as an error although the value is the nearest double.
  std::string s(text);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size()) throw std::invalid_argument("not a number: " + s);
  if (!std::isfinite(v)) throw std::invalid_argument("number out of range (not finite): " + s);
  return v;
}

Mpfr ScalarTraits<Mpfr>::epsilon() {
  Mpfr one = 1;
  return ldexp(one, 1 - static_cast<int>(mpfrPrecision()));
}

Mpfr ScalarTraits<Mpfr>::fromString(std::string_view text) { return Mpfr(std::string(text)); }

}  // namespace ndc
