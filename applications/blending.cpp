// Blending of two freeform surfaces (paper Sec. 3.5): equations (7)-(8), 4 equations in
// (u, v, s, t, a1, a2), a 2-manifold in R^6.
#include <memory>
#include <optional>

#include "applications/applications.hpp"
#include "applications/two_surface.hpp"

namespace ndc {

namespace {

/// The paper's normal N_i of a surface: the polynomial normal twosurface::surfaceNormal, with
/// B-spline directions' span-coordinate derivatives turned into parameter derivatives, so that
/// the blend is continuous across knots (its offset length is |N_i|: unnormalised, as in the
/// paper).
std::array<Expression, 3> paperNormal(const SurfaceSpec& spec, const SurfaceExpr& s, int n, int u,
                                      int v) {
  std::array<Expression, 3> normal = twosurface::surfaceNormal(s);
  if (auto g = twosurface::parameterScale(spec, 0, n, u)) normal = scale(*g, normal);
  if (auto g = twosurface::parameterScale(spec, 1, n, v)) normal = scale(*g, normal);
  return normal;
}

}  // namespace

Problem buildBlending(const ApplicationInput& in) {
  // Sec. 3.5: two surfaces and the ranges of alpha1, alpha2.
  twosurface::checkInput(in, /*wantsAlpha=*/true);
  constexpr int n = 6;
  const std::array<double, 4> alpha = *in.alpha;
  Problem problem =
      twosurface::skeleton(in, {"a1", "a2"}, {{alpha[0], alpha[1]}, {alpha[2], alpha[3]}});
  const SurfaceExpr s1 = makeSurface(in.surfaces[0], n, 0, 1);
  const SurfaceExpr s2 = makeSurface(in.surfaces[1], n, 2, 3);
  const Expression a1 = Expression::variable(n, 4, "a1");
  const Expression a2 = Expression::variable(n, 5, "a2");
  const std::array<Expression, 3> n1 = paperNormal(in.surfaces[0], s1, n, 0, 1);
  const std::array<Expression, 3> n2 = paperNormal(in.surfaces[1], s2, n, 2, 3);

  // (7) S1 + a1 N1 = S2 + a2 N2, three scalar equations; multiplied by W1 W2 > 0:
  //   W2 P1 + a1 W1 W2 N1 - W1 P2 - a2 W1 W2 N2 = 0.
  const std::array<Expression, 3> side1 =
      twosurface::weighted(s2, s1.P + scale(a1, twosurface::weighted(s1, n1)));
  const std::array<Expression, 3> side2 =
      twosurface::weighted(s1, s2.P + scale(a2, twosurface::weighted(s2, n2)));
  const std::array<Expression, 3> e = side1 - side2;
  const char* axis[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    Expression eq = e[i];
    eq.setText(std::string("blending (7) ") + axis[i] + ": S1 + a1 N1 = S2 + a2 N2, cleared");
    problem.equations.push_back(std::move(eq));
  }

  // (8) a1^2 + a2^2 + 1 - 2 a1 - 2 a2 = 0: the circle of radius 1 about (1, 1).
  const Expression one = Expression::constant(n, 1.0), two = Expression::constant(n, 2.0);
  Expression circle = a1 * a1 + a2 * a2 + one - two * a1 - two * a2;
  circle.setText("blending (8): a1^2 + a2^2 + 1 - 2 a1 - 2 a2");
  problem.equations.push_back(std::move(circle));

  // The 3-D image: S1 + a1 N1 = (P1 + a1 W1 N1) / W1.
  auto data = twosurface::applicationData(in, n);
  data->image = RationalMap{s1.P + scale(a1, twosurface::weighted(s1, n1)), s1.W};
  problem.application = std::move(data);
  setPatches(problem);
  return problem;
}

}  // namespace ndc
