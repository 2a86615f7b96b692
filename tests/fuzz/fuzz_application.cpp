/// \file fuzz_application.cpp
/// libFuzzer harness: the application-file reader (ndc::parseProblem with `application = ...`:
/// surfaces, weights, knot vectors, motions, and the builders of the five applications) on
/// arbitrary bytes, seeded with the application files of experiments/problems/ and B-spline
/// variants with unclamped and extreme knot vectors (tests/fuzz/seeds/fuzz_application/), and
/// the dictionary tests/fuzz/fuzz_application.dict. An accepted problem has its equations and
/// image map evaluated. `InputError` is the expected way to refuse; anything else is a finding.
/// Run: `scripts/fuzz.sh fuzz_application` (docs/testing.md).
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ndc::fuzz::problemInput(data, size);
  return 0;
}
