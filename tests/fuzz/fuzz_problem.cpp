/// \file fuzz_problem.cpp
/// libFuzzer harness: the problem-file reader ndc::parseProblem (TOML, validation, equations)
/// on arbitrary bytes, seeded with plain problem files (tests/fuzz/seeds/fuzz_problem/) and the
/// dictionary tests/fuzz/fuzz_problem.dict. An accepted problem has its equations evaluated on
/// its domain (plain, gradient, interval, Bernstein form). `InputError` is the expected way to
/// refuse; anything else is a finding. Run: `scripts/fuzz.sh fuzz_problem` (docs/testing.md).
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ndc::fuzz::problemInput(data, size);
  return 0;
}
