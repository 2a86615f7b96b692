/// \file sweep_common.hpp
/// What the two sweep systems of the paper share (Sec. 3.2, perspective silhouettes of a general
/// swept volume, and Sec. 3.4, general sweep envelopes): a moving body S(u, v) under a rigid
/// motion A(t)[x] = R(t) x + T(t), the cleared form of the envelope condition (4), the image
/// A(t)[S(u, v)] and the input geometry. The derivation is in sweep_common.cpp.
#pragma once
#include <array>
#include <vector>

#include "applications/applications.hpp"
#include "applications/freeform.hpp"
#include "framework/problem/problem.hpp"

namespace ndc {

/// The body and motion of a sweep problem as expressions in the problem variables
/// (u, v, t) = (0, 1, 2).
struct SweepSetup {
  const SurfaceSpec* spec = nullptr;   ///< the body's boundary surface (`[[surfaces]]`)
  const MotionSpec* motion = nullptr;  ///< the motion (`[motion]`)
  SurfaceExpr S;                       ///< S = P / W
  MotionExpr A;                        ///< T, q, M, w = |q|^2 with R = M / w
  std::array<Expression, 3> N;         ///< the polynomial normal W^4 (S_u x S_v)
};

/// Number of problem variables of a sweep system: u, v, t.
inline constexpr int kSweepVariables = 3;

/// Whether w(t) = |q(t)|^2 of the motion's quaternion Bezier curve is positive on the whole time
/// range: its Bernstein coefficients are positive, after de Casteljau subdivision where some are
/// not (w >= 0 always; a zero or a near-zero value, below 1e-12 of the largest coefficient, returns
/// false).
bool quaternionNeverZero(const MotionSpec& motion);

/// Validates a sweep problem file and forms S, A and N. Exactly one surface, a motion whose
/// quaternion curve never vanishes on the time range, and an eye point exactly when `needsEye`
/// (sweep-silhouette); anything else fails through ApplicationInput::fail (exit 2).
SweepSetup makeSweep(const ApplicationInput& in, bool needsEye);

/// M^T x for the 3 x 3 expression matrix M (row-major) and a 3-vector x.
std::array<Expression, 3> transposeTimes(const std::array<std::array<Expression, 3>, 3>& M,
                                         const std::array<Expression, 3>& x);

/// The envelope condition (4), det[A'(t)[S], A(t)[S_u], A(t)[S_v]] = 0, cleared of the positive
/// factor w W^5: (Omega x P + W M^T T') . N, with Omega = 2 vec(conj(q) q').
Expression envelopeEquation(const SweepSetup& sweep);

/// The silhouette condition (5), <A(t)[S] - E, A(t)[N]> = 0 for the eye point E, cleared of the
/// positive factor w W: <w P + W M^T (T - E), N>.
Expression silhouetteEquation(const SweepSetup& sweep, const std::array<double, 3>& eye);

/// The problem of a sweep system: variables (u, v, t), the domain (the surface's variable ranges
/// and the motion's time range), `equations`, and the application data (`application` names it):
/// the image A(t)[S(u, v)] = (M P + w W T) / (w W), the body tessellated at five instants of the
/// motion (part = instant index) and the knots of u and v. Sets the B-spline patches (setPatches).
Problem sweepProblem(const ApplicationInput& in, const SweepSetup& sweep,
                     std::vector<Expression> equations);

}  // namespace ndc
