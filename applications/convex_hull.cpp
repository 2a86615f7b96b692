// Convex hulls of freeform surfaces (paper Sec. 3.1): the bitangent planes of two surfaces,
// equations (1)-(3), 3 equations in (u, v, s, t), a 1-manifold.
#include <memory>

#include "applications/applications.hpp"
#include "applications/two_surface.hpp"

namespace ndc {

Problem buildConvexHull(const ApplicationInput& in) {
  // Sec. 3.1: two surfaces S1(u, v) and S2(s, t), nothing else.
  twosurface::checkInput(in, /*wantsAlpha=*/false);
  constexpr int n = 4;
  Problem problem = twosurface::skeleton(in, {}, {});
  const SurfaceExpr s1 = makeSurface(in.surfaces[0], n, 0, 1);
  const SurfaceExpr s2 = makeSurface(in.surfaces[1], n, 2, 3);

  // N(u, v): a polynomial normal of S1, a positive multiple of S1_u x S1_v.
  const std::array<Expression, 3> normal = twosurface::surfaceNormal(s1);

  // (1) F = <S(u, v) - S(s, t), N(u, v)>, denominators cleared: S1 - S2 = (W2 P1 - W1 P2) /
  // (W1 W2) and W1 W2 > 0, so F = <W2 P1 - W1 P2, N> has the same zero set.
  Expression f = -dot(twosurface::difference(s1, s2), normal);
  f.setText("convex-hull F = <W2 P1 - W1 P2, N1> (1)");

  // (2), (3) G = F_s, H = F_t, differentiated symbolically:
  // G = <W2_s P1 - W1 P2_s, N>, H = <W2_t P1 - W1 P2_t, N> (G = -<P2_s, N> when polynomial).
  // On F = 0 they vanish exactly where S2_s and S2_t are orthogonal to N (tangency at S2).
  auto partial = [&](const Expression& w2d, const std::array<Expression, 3>& p2d) {
    const std::array<Expression, 3> first = twosurface::weighted(s1, p2d);
    if (!s2.rational) return -dot(first, normal);
    return dot(scale(w2d, s1.P) - first, normal);
  };
  Expression g = partial(s2.Wu, s2.Pu);
  g.setText("convex-hull G = F_s (2)");
  Expression h = partial(s2.Wv, s2.Pv);
  h.setText("convex-hull H = F_t (3)");
  problem.equations = {std::move(f), std::move(g), std::move(h)};

  // The 3-D image: the contact point S1(u, v) on the first surface and, for the ruled surface
  // of bitangent segments, the contact point S2(s, t) on the second.
  auto data = twosurface::applicationData(in, n);
  data->image = RationalMap{s1.P, s1.W};
  data->secondImage = RationalMap{s2.P, s2.W};
  problem.application = std::move(data);
  setPatches(problem);
  return problem;
}

}  // namespace ndc
