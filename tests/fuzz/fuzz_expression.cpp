/// \file fuzz_expression.cpp
/// libFuzzer harness: the expression parser ndc::Expression::parse on arbitrary text in the
/// variables x, y, z, seeded with tests/fuzz/seeds/fuzz_expression/ and the dictionary
/// tests/fuzz/fuzz_expression.dict. An expression that parses within the degree cap is
/// evaluated: value and gradient at a point, interval value and gradient on a box, the Bernstein
/// form on the box (when it has at most kFuzzCoefficients coefficients) with a split and a
/// derivative, and the value in MPFR. `ExpressionError` is the expected way to refuse; anything
/// else is a finding. Run: `scripts/fuzz.sh fuzz_expression` (docs/testing.md).
#include <array>
#include <string_view>

#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::array<std::string, 3> variables = {"x", "y", "z"};
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ndc::Expression e;
  try {
    e = ndc::Expression::parse(text, variables);
  } catch (const ndc::ExpressionError&) {
    return 0;
  }
  ndc::fuzz::require(e.dim() == 3, "an expression in another number of variables");
  // A small box away from the origin and one across it, as problem domains are.
  ndc::fuzz::exercise(e, ndc::Box<double>{{0.25, -1, -0.5}, {0.75, 2, 0.5}});
  ndc::fuzz::exercise(e, ndc::Box<double>{{-1e-3, -1e3, 1}, {1e-3, 1e3, 1 + 0x1p-40}});
  // The exact literal text in MPFR (Mpfr::fromString), at a point.
  const std::array<ndc::Mpfr, 3> point = {ndc::Mpfr(0.5), ndc::Mpfr(-0.75), ndc::Mpfr(3)};
  e.evaluate<ndc::Mpfr>(std::span<const ndc::Mpfr>(point));
  return 0;
}
