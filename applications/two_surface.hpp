/// \file two_surface.hpp
/// Shared steps of the three two-surface systems of the paper's Sec. 3 (convex hull, bisector,
/// blending): input checks, the problem skeleton over (u, v, s, t[, a1, a2]) and the geometric
/// building blocks in Bernstein arithmetic. Private to applications/.
#pragma once
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "applications/applications.hpp"
#include "applications/freeform.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/problem.hpp"

namespace ndc::twosurface {

/// Grid resolution of each input surface in input.ply ((k + 1) x (k + 1) points).
inline constexpr int kTessellation = 24;

/// Checks that the file holds what a two-surface system needs: exactly two `[[surfaces]]`, no
/// `[motion]` or `eye`, and `alpha` exactly when `wantsAlpha` (blending). Fails (exit 2) with a
/// one-line message naming the application otherwise.
inline void checkInput(const ApplicationInput& in, bool wantsAlpha) {
  const std::string& app = in.application;
  if (in.surfaces.size() != 2) {
    in.fail(app + " needs exactly 2 [[surfaces]] (S1 and S2), the file has " +
            std::to_string(in.surfaces.size()));
  }
  if (in.motion) in.fail(app + " takes no [motion] (only sweep-silhouette and sweep-envelope do)");
  if (in.eye) in.fail(app + " takes no eye point (only sweep-silhouette does)");
  if (wantsAlpha && !in.alpha) {
    in.fail(app + " needs alpha = [[lo1, hi1], [lo2, hi2]], the ranges of alpha1 and alpha2");
  }
  if (!wantsAlpha && in.alpha) in.fail(app + " takes no alpha (only blending does)");
  if (in.alpha) {
    const auto& a = *in.alpha;
    if (!(a[0] < a[1]) || !(a[2] < a[3])) in.fail("alpha: every range needs lo < hi");
  }
}

/// The problem skeleton: name, description, expectation, variables u, v (S1), s, t (S2) and
/// `extra` after them, and the domain (each surface direction's variable range; `extraDomain`
/// for the extra variables).
inline Problem skeleton(const ApplicationInput& in, const std::vector<std::string>& extra,
                        const std::vector<std::array<double, 2>>& extraDomain) {
  Problem problem;
  problem.name = in.name;
  problem.description = in.description;
  problem.expect = in.expect;
  problem.variables = {"u", "v", "s", "t"};
  problem.variables.insert(problem.variables.end(), extra.begin(), extra.end());
  std::vector<std::array<double, 2>> ranges;
  for (const SurfaceSpec& spec : in.surfaces) {
    ranges.push_back(variableRange(spec, 0));
    ranges.push_back(variableRange(spec, 1));
  }
  ranges.insert(ranges.end(), extraDomain.begin(), extraDomain.end());
  for (const auto& r : ranges) {
    problem.domain.lo.push_back(r[0]);
    problem.domain.hi.push_back(r[1]);
  }
  return problem;
}

/// The application data common to the three systems: name, input surfaces tessellated (part =
/// surface index) and the knots of each variable (none for the extra ones).
inline std::shared_ptr<ApplicationData> applicationData(const ApplicationInput& in, int n) {
  auto data = std::make_shared<ApplicationData>();
  data->name = in.application;
  for (std::size_t i = 0; i < in.surfaces.size(); ++i) {
    tessellate(in.surfaces[i], static_cast<int>(i), kTessellation, data->input);
  }
  data->knots.assign(n, {});
  for (std::size_t i = 0; i < in.surfaces.size(); ++i) {
    for (int d = 0; d < 2; ++d) data->knots[2 * i + d] = distinctKnots(in.surfaces[i], d);
  }
  return data;
}

/// A polynomial normal of S = P / W of lower degree than SurfaceExpr::normal(): the positive
/// multiple W^3 (S_u x S_v) = W (P_u x P_v) - W_u (P x P_v) - W_v (P_u x P), which is P_u x P_v
/// when S is polynomial. Bidegree (3 du - 1, 3 dv - 1) instead of (4 du - 1, 4 dv - 1).
inline std::array<Expression, 3> surfaceNormal(const SurfaceExpr& s) {
  if (!s.rational) return cross(s.Pu, s.Pv);
  return scale(s.W, cross(s.Pu, s.Pv)) - scale(s.Wu, cross(s.P, s.Pv)) -
         scale(s.Wv, cross(s.Pu, s.P));
}

/// W1 W2 (S2 - S1) = W1 P2 - W2 P1 (P2 - P1 when both are polynomial).
inline std::array<Expression, 3> difference(const SurfaceExpr& s1, const SurfaceExpr& s2) {
  const std::array<Expression, 3> p2 = s1.rational ? scale(s1.W, s2.P) : s2.P;
  const std::array<Expression, 3> p1 = s2.rational ? scale(s2.W, s1.P) : s1.P;
  return p2 - p1;
}

/// `w * a`, or `a` itself when `w` is the constant weight 1 of a polynomial surface (keeps the
/// degrees and the expression trees small).
inline std::array<Expression, 3> weighted(const SurfaceExpr& s,
                                          const std::array<Expression, 3>& a) {
  return s.rational ? scale(s.W, a) : a;
}

/// For a B-spline direction d of `spec` on problem variable `var` (solved in span coordinates,
/// span i = [i, i + 1], so d/dx = h_i d/du with h_i the knot span length): the piecewise
/// constant 1 / h_i that turns a span-coordinate derivative into the parameter derivative.
/// Empty for a Bezier direction (its variable is the parameter itself).
inline std::optional<Expression> parameterScale(const SurfaceSpec& spec, int d, int n, int var) {
  const std::vector<double> knots = distinctKnots(spec, d);
  if (knots.size() < 2) return std::nullopt;
  auto leaf = std::make_shared<PiecewiseBernstein>();
  leaf->name = spec.name + (d == 0 ? ".du/dx" : ".dv/dy");
  leaf->axes = {var};
  leaf->breaks.emplace_back();
  for (std::size_t i = 0; i < knots.size(); ++i) leaf->breaks[0].push_back(double(i));
  for (std::size_t i = 0; i + 1 < knots.size(); ++i) {
    const Box<double> span{{double(i)}, {double(i + 1)}};
    leaf->pieces.push_back(Bernstein<double>::constant(span, 1.0 / (knots[i + 1] - knots[i])));
  }
  return Expression::polynomial(n, std::move(leaf));
}

}  // namespace ndc::twosurface
