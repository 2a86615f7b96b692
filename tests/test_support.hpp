// Shared helpers for the generic (per-scalar) test bodies.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "scalar.hpp"

namespace ndc::test {

/// The scalar types every numeric test body runs over.
#define NDC_SCALARS double, ::ndc::Mpfr

/// Sets the working precision for a test of scalar S (Mpfr: `bits`; double: nothing) and
/// restores the previous one at scope exit.
template <class S>
class PrecisionScope {
 public:
  explicit PrecisionScope(unsigned bits = 160) : saved_(mpfrPrecision()) {
    if constexpr (!std::is_same_v<S, double>) setMpfrPrecision(bits);
  }
  ~PrecisionScope() { setMpfrPrecision(saved_); }

 private:
  unsigned saved_;
};

/// Relative tolerance the tests demand of S: 1e-12 in double, 1e-35 in Mpfr at 160 bits.
template <class S>
double relativeTolerance() {
  return std::is_same_v<S, double> ? 1e-12 : 1e-35;
}

/// Uniform random scalar in [lo, hi] from a double draw (exactly representable in both S).
template <class S>
S uniform(std::mt19937& rng, double lo, double hi) {
  std::uniform_real_distribution<double> d(lo, hi);
  return S(d(rng));
}

/// Path of the built command-line tool and of the source tree (set by CMake).
inline std::string binaryPath() { return NDC_BINARY; }
inline std::string sourceDir() { return NDC_SOURCE_DIR; }

}  // namespace ndc::test
