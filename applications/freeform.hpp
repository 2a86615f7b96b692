/// \file freeform.hpp
/// Freeform input of application problems (paper Sec. 3): tensor-product Bezier and B-spline
/// surfaces, polynomial and rational, and affine motions, as expressions whose leaves are
/// piecewise Bernstein polynomials (framework/numeric/piecewise.hpp), so every constraint system
/// built from them is formed in Bernstein arithmetic.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "framework/problem/application.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/problem.hpp"

namespace ndc {

/// A tensor-product surface as given in a problem file (`[[surfaces]]`).
struct SurfaceSpec {
  std::string name;
  int degreeU = 0, degreeV = 0;
  int countU = 0, countV = 0;                 ///< control points per direction
  std::vector<std::array<double, 3>> points;  ///< countU * countV, u fastest
  std::vector<double> weights;                ///< empty (polynomial) or one per point, all > 0
  std::vector<double> knotsU, knotsV;         ///< empty: Bezier (count = degree + 1)
  /// Bezier only: the parameter box, default [0, 1]^2 (a B-spline's is its knot range).
  std::array<double, 4> box{0, 1, 0, 1};  ///< u0, u1, v0, v1

  bool rational() const { return !weights.empty(); }
  bool bspline() const { return !knotsU.empty(); }
  /// The point S(u, v) in R^3 at surface parameters (de Boor / de Casteljau), for tessellation
  /// and tests.
  std::array<double, 3> evaluate(double u, double v) const;
  /// The parameter range along direction d (0 = u, 1 = v).
  std::array<double, 2> range(int d) const;
};

/// A surface over two problem variables as expressions: S = P / W with P = (X, Y, Z) the
/// homogeneous numerators and W > 0 the weight (the constant 1 when polynomial). Partial
/// derivatives are leaves of their own (each piece differentiated in Bernstein form).
struct SurfaceExpr {
  std::array<Expression, 3> P, Pu, Pv;
  Expression W, Wu, Wv;
  bool rational = false;
  /// Numerator of S_u: S_u = Tu / W^2 with Tu = Pu W - P Wu (Tu = Pu when polynomial).
  std::array<Expression, 3> tangentU() const;
  /// Numerator of S_v, likewise.
  std::array<Expression, 3> tangentV() const;
  /// A polynomial normal N = Tu x Tv: a positive multiple (W^4) of S_u x S_v.
  std::array<Expression, 3> normal() const;
};

/// The surface `spec` on problem variables `u` and `v` of `n`. A B-spline direction is solved
/// in span coordinates: knot span i (of nonzero length) is the interval [i, i + 1] (Bezier
/// extraction gives one polynomial piece per span); `variableRange` gives the problem-variable
/// range and ApplicationData::knots maps back.
SurfaceExpr makeSurface(const SurfaceSpec& spec, int n, int u, int v);
/// The problem-variable range of direction d of `spec`: its parameter box for Bezier, [0, spans]
/// for B-spline.
std::array<double, 2> variableRange(const SurfaceSpec& spec, int d);
/// The distinct knots of direction d (empty for Bezier): ApplicationData::knots entries.
std::vector<double> distinctKnots(const SurfaceSpec& spec, int d);

/// An affine (rigid) motion A(t)[x] = R(t) x + T(t) (`[motion]`): T a Bezier curve, R the
/// rotation of a Bezier quaternion curve q(t) = (q0, q1, q2, q3) (scalar part first), never 0:
/// R = M(q) / |q|^2 with M quadratic in q, so A is rational in t.
struct MotionSpec {
  std::vector<std::array<double, 3>> translation;  ///< Bezier control points of T(t)
  std::vector<std::array<double, 4>> rotation;     ///< Bezier control points of q(t)
  std::array<double, 2> time{0, 1};                ///< the t range
  /// A(t)[x] in double (for input.ply and tests).
  std::array<double, 3> apply(double t, const std::array<double, 3>& x) const;
};

/// A motion on problem variable `t` of `n` as expressions.
struct MotionExpr {
  std::array<Expression, 3> T, dT;  ///< translation and its t-derivative
  std::array<Expression, 4> q, dq;  ///< quaternion and its t-derivative
  Expression w;                     ///< |q|^2 (> 0)
  /// M(q) with R = M / w, row-major: M[r][c].
  std::array<std::array<Expression, 3>, 3> M;
  /// The angular velocity numerator in the body frame: omega = 2 vec(conj(q) q') / w, so
  /// R^T R' x = (Omega / w) x Omega... returned as the vector Omega = 2 vec(conj(q) q').
  std::array<Expression, 3> bodyAngularVelocity() const;
};

MotionExpr makeMotion(const MotionSpec& spec, int n, int t);

/// Cross and dot products and scaling of expression 3-vectors (helpers for the systems).
std::array<Expression, 3> cross(const std::array<Expression, 3>& a,
                                const std::array<Expression, 3>& b);
Expression dot(const std::array<Expression, 3>& a, const std::array<Expression, 3>& b);
std::array<Expression, 3> scale(const Expression& s, const std::array<Expression, 3>& a);
std::array<Expression, 3> operator+(const std::array<Expression, 3>& a,
                                    const std::array<Expression, 3>& b);
std::array<Expression, 3> operator-(const std::array<Expression, 3>& a,
                                    const std::array<Expression, 3>& b);
/// A constant vector in n variables.
std::array<Expression, 3> constantVector(int n, const std::array<double, 3>& c);

/// Tessellates a surface into `input` as part `part` (a (k+1) x (k+1) grid of points).
void tessellate(const SurfaceSpec& spec, int part, int k, TriangleSoup& input,
                const MotionSpec* motion = nullptr, double t = 0);

/// After a builder has set variables, domain and equations: the B-spline patches of the
/// problem (Problem::roots, rootLevel) from the breaks of the equations' leaves. Every break
/// must lie on a dyadic grid line of the domain; throws InputError otherwise.
void setPatches(Problem& problem);

}  // namespace ndc
