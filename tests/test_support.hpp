// Shared helpers for the generic (per-scalar) test bodies.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "applications/load.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/problem.hpp"

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

/// Precision of the "exact" ground-truth values the tests compare against.
inline constexpr unsigned kExactBits = 2000;

/// An exact kExactBits copy of a scalar (arithmetic on two such copies is done at that
/// precision, whatever the current default).
inline Mpfr exact(const double& v) {
  Mpfr r;
  mpfr_set_prec(r.backend().data(), kExactBits);
  mpfr_set_d(r.backend().data(), v, MPFR_RNDN);
  return r;
}
inline Mpfr exact(const Mpfr& v) {
  Mpfr r;
  mpfr_set_prec(r.backend().data(), kExactBits);
  mpfr_set(r.backend().data(), v.backend().data(), MPFR_RNDN);
  return r;
}

/// A problem named "test" in variables x0..x{n-1} on [-half, half]^n.
inline Problem makeProblem(int n, const std::vector<std::string>& equations, double half = 3) {
  std::string text = "name = \"test\"\nvariables = [";
  for (int j = 0; j < n; ++j) text += (j ? ", \"x" : "\"x") + std::to_string(j) + "\"";
  text += "]\ndomain = [";
  for (int j = 0; j < n; ++j) {
    text += (j ? ", [" : "[") + std::to_string(-half) + ", " + std::to_string(half) + "]";
  }
  text += "]\nequations = [";
  for (std::size_t i = 0; i < equations.size(); ++i) {
    text += (i ? ", \"" : "\"") + equations[i] + "\"";
  }
  text += "]\n";
  return parseProblem(text, "test");
}

/// Path of the built command-line tool and of the source tree (set by CMake).
inline std::string binaryPath() { return NDC_BINARY; }
inline std::string sourceDir() { return NDC_SOURCE_DIR; }

}  // namespace ndc::test
