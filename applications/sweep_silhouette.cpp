// Perspective silhouette of a general swept volume (paper Sec. 3.2): the points of the
// characteristic curve K_t (equation (4)) that also lie on the silhouette S_t of the instance
// A(t)[O] seen from the eye point P (equation (5)); two equations in (u, v, t), a 1-manifold
// (k = 1). The cleared forms and their derivation are in sweep_common.cpp.
#include "applications/applications.hpp"
#include "applications/sweep_common.hpp"

namespace ndc {

Problem buildSweepSilhouette(const ApplicationInput& in) {
  // Sec. 3.2: one body, one motion and the eye point P.
  const SweepSetup sweep = makeSweep(in, /*needsEye=*/true);
  // Eqs. (4) and (5): K_t intersected with S_t.
  return sweepProblem(in, sweep, {envelopeEquation(sweep), silhouetteEquation(sweep, *in.eye)});
}

}  // namespace ndc
