/// \file iteration.hpp
/// What the Newton-type iterations share: the projection's minimum-norm Newton
/// (strategies/projection/newton.cpp), the crossing connection's square face Newton
/// (strategies/connection/crossing/face_solver.cpp) and the singular point search's Gauss-Newton
/// (pipeline/singular.cpp). They solve different systems (m x n for the minimum-norm
/// step, m x m on a face, 2n + m - 1 unknowns for a singular point), so each keeps its step; the
/// stopping rules and the step-halving line search are these, once.
#pragma once

#include <algorithm>
#include <cmath>
#include <span>

#include "framework/numeric/scalar.hpp"

namespace ndc {

/// Whether `v` is finite (neither infinite nor NaN), in any scalar.
template <class S>
bool isFinite(const S& v) {
  using std::isfinite;
  return isfinite(v);
}

/// max_j |x_j|.
template <class S>
S normInf(std::span<const S> x) {
  using std::abs;
  S worst = 0;
  for (const S& v : x) worst = std::max<S>(worst, abs(v));
  return worst;
}

/// The stopping rules of a Newton-type iteration started at a point of size |x0|_inf.
template <class S>
class IterationGuard {
 public:
  explicit IterationGuard(std::span<const S> start) : divergence_(S(1e4) * (1 + normInf(start))) {}

  /// The iterate of size `size` (|x|_inf) ran away: overflow, NaN, or more than 1e4 times the
  /// start's size (the iteration is heading to another root far off, or to none).
  bool diverged(const S& size) const { return !isFinite(size) || !(size <= divergence_); }

  /// A step of size `step` (|s|_inf) at an iterate of size `size` is at the rounding floor of
  /// the run's scalar: 16 eps (1 + |x|_inf). Further steps only move within rounding.
  static bool stagnated(const S& step, const S& size) {
    return step <= S(16) * ScalarTraits<S>::epsilon() * (1 + size);
  }

 private:
  S divergence_;
};

/// Step halving: calls `accept(lambda, halving)` for lambda = 1, 1/2, 1/4, ... (at most
/// `halvings` calls) and returns the first lambda it accepts, or 0 when none is. `accept`
/// evaluates the trial iterate x - lambda s (and keeps it when it returns true).
template <class S, class Accept>
S halveStep(int halvings, Accept&& accept) {
  S lambda = 1;
  for (int halving = 0; halving < halvings; ++halving, lambda /= 2)
    if (accept(lambda, halving)) return lambda;
  return 0;
}

}  // namespace ndc
