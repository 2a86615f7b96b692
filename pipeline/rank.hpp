/// \file rank.hpp
/// The early check that the equations are independent on M: a system whose Jacobian has rank
/// below m at every point found on M (dependent equations, such as one equation a multiple or a
/// combination of others) has a zero set of dimension above k, which no connection can mesh
/// as a k-manifold. The pipeline refuses it right after the projection, before the connection
/// spends minutes on it (docs/input-limits.md, "Dependent equations").
#pragma once

#include "framework/mesh/complex.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"

namespace ndc {

/// The relative smallest singular value below which the Jacobian of the row-normalised
/// equations counts as rank deficient at a point: far above rounding (about 1e-16 times the
/// condition of the evaluation), far below any system that can be meshed in double.
inline constexpr double kDependentSigma = 1e-10;

/// Points of M the check looks at, spread evenly over the converged projections.
inline constexpr std::size_t kRankSamples = 512;

/// Throws InputError (one line naming the problem file) when every sampled converged
/// projection (every projection's last iterate when none converged) has sigma_min(J) <=
/// kDependentSigma * sigma_max(J) for the Jacobian J with its rows scaled to unit length (a zero
/// row counts as deficient). Nothing is checked for m = 1, nor without solution cells.
template <class S>
void checkRankOnM(const Problem& problem, const System<S>& system,
                  const Projections<S>& projections);

}  // namespace ndc
