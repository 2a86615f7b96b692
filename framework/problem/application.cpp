// Application data: the image map in double and the span-coordinate parameter map.
#include "framework/problem/application.hpp"

#include <cmath>
#include <limits>

namespace ndc {

std::array<double, 3> RationalMap::operator()(std::span<const double> x, bool* singular) const {
  const double den = denominator.evaluate<double>(x);
  std::array<double, 3> num;
  double scale = 1;
  for (int c = 0; c < 3; ++c) {
    num[c] = numerator[c].evaluate<double>(x);
    scale = std::max(scale, std::abs(num[c]));
  }
  const bool bad = !(std::abs(den) > 1e-12 * scale);
  if (singular) *singular = bad;
  if (bad) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  return {num[0] / den, num[1] / den, num[2] / den};
}

double ApplicationData::parameter(int j, double x) const {
  if (j >= static_cast<int>(knots.size()) || knots[j].size() < 2) return x;
  const auto& k = knots[j];
  const int spans = static_cast<int>(k.size()) - 1;
  // Clamped in double: converting a NaN or a floor beyond int to int is undefined.
  const double span = std::floor(x);
  const int i = span >= spans - 1 ? spans - 1 : span > 0 ? static_cast<int>(span) : 0;
  return k[i] + (x - i) * (k[i + 1] - k[i]);
}

}  // namespace ndc
