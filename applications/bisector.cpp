// Bisectors of two freeform surfaces (paper Sec. 3.3): equations (6), 2 equations in
// (u, v, s, t), a 2-manifold, after eliminating the bisector point with Cramer's rule.
#include <memory>

#include "applications/applications.hpp"
#include "applications/two_surface.hpp"

namespace ndc {

Problem buildBisector(const ApplicationInput& in) {
  // Sec. 3.3: two surfaces S1(u, v) and S2(s, t), nothing else.
  twosurface::checkInput(in, /*wantsAlpha=*/false);
  constexpr int n = 4;
  Problem problem = twosurface::skeleton(in, {}, {});
  const SurfaceExpr s1 = makeSurface(in.surfaces[0], n, 0, 1);
  const SurfaceExpr s2 = makeSurface(in.surfaces[1], n, 2, 3);

  // The bisector point P is on the normal line of S1 at (u, v) and equidistant from S1(u, v)
  // and S2(s, t): three equations linear in P,
  //   <P - S1, S1_u> = 0,  <P - S1, S1_v> = 0,  2 <P - S1, S2 - S1> = |S2 - S1|^2
  // (the last is |P - S1|^2 = |P - S2|^2). With Q = P - S1 and D = W1 W2 (S2 - S1) the rows
  // of A are Tu1, Tv1 (the tangent numerators) and 2 D, scaled by positive factors, and the
  // right-hand side is (0, 0, |D|^2 / (W1 W2)). Cramer's rule: only the third column of adj(A)
  // is needed, Tu1 x Tv1 = N1 (a positive multiple of S1_u x S1_v), and
  // det(A) = 2 <D, N1>, so Q = |D|^2 N1 / (2 W1 W2 <D, N1>).
  const std::array<Expression, 3> d = twosurface::difference(s1, s2);
  const std::array<Expression, 3> normal = twosurface::surfaceNormal(s1);
  const Expression dn = dot(d, normal);
  const Expression dd = dot(d, d);
  const Expression two = Expression::constant(n, 2.0);

  // The remaining two equations (6): P - S2 = Q - D / (W1 W2) is normal to S2,
  //   <P - S2, S2_s> = 0,  <P - S2, S2_t> = 0,
  // multiplied by det(A) W1 W2 > 0 (away from det(A) = 0) to be polynomial:
  //   F_i = <|D|^2 N1 - 2 <D, N1> D, T2_i> = |D|^2 <N1, T2_i> - 2 <D, N1> <D, T2_i>,
  // with T2_s, T2_t the tangent numerators of S2 (the expanded form references fewer leaves).
  const auto cleared = [&](const std::array<Expression, 3>& tangent) {
    return dd * dot(normal, tangent) - two * dn * dot(d, tangent);
  };
  Expression f1 = cleared(s2.tangentU());
  f1.setText("bisector F1 = det(A) <P - S2, S2_s> (6), Cramer, cleared");
  Expression f2 = cleared(s2.tangentV());
  f2.setText("bisector F2 = det(A) <P - S2, S2_t> (6), Cramer, cleared");
  problem.equations = {std::move(f1), std::move(f2)};

  // The 3-D image: P = S1 + Q = (2 W2 <D, N1> P1 + |D|^2 N1) / (2 W1 W2 <D, N1>), undefined
  // where the determinant vanishes (the normal line of S1 is parallel to the plane of
  // equidistant points).
  auto data = twosurface::applicationData(in, n);
  const Expression det = two * dn;
  data->image.numerator = scale(det, twosurface::weighted(s2, s1.P)) + scale(dd, normal);
  data->image.denominator = s1.rational || s2.rational ? det * s1.W * s2.W : det;
  data->singularName = "bisector determinant";
  problem.application = std::move(data);
  setPatches(problem);
  return problem;
}

}  // namespace ndc
