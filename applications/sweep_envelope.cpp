// General sweep envelope (paper Sec. 3.4): the envelope of A(t)[S(u, v)] for a <= t <= b is the set
// of points A(t)[S(u, v)] with equation (4), det[A'(t)[S], A(t)[S_u], A(t)[S_v]] = 0; one equation
// in (u, v, t), a 2-manifold (k = 2). The cleared form and its derivation are in sweep_common.cpp.
#include "applications/applications.hpp"
#include "applications/sweep_common.hpp"

namespace ndc {

Problem buildSweepEnvelope(const ApplicationInput& in) {
  // Sec. 3.4: one body, one motion, no eye point.
  const SweepSetup sweep = makeSweep(in, /*needsEye=*/false);
  // Eq. (4): the velocity of the point lies in the tangent plane of the moving surface.
  return sweepProblem(in, sweep, {envelopeEquation(sweep)});
}

}  // namespace ndc
