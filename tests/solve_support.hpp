/// \file solve_support.hpp
/// A whole run of the pipeline at a depth with default settings otherwise, in either scalar
/// (MPFR at 128 bits), for the tests that check results end to end.
#pragma once

#include <type_traits>

#include "pipeline/pipeline.hpp"
#include "tests/test_support.hpp"

namespace ndc::test {

/// ndc::runPipeline on `problem` at `depth`, default settings otherwise; for ndc::Mpfr with
/// 128 bits.
template <class S>
RunResult solveAt(const Problem& problem, int depth) {
  PrecisionScope<S> scope(128);
  Settings s;
  s.depth = depth;
  if constexpr (!std::is_same_v<S, double>) {
    s.scalar = "mpfr";
    s.precisionBits = 128;
  }
  return runPipeline(problem, s);
}

}  // namespace ndc::test
