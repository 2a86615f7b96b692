// The sweep systems of the paper's Sec. 3.2 and 3.4, shared parts.
//
// Derivation (checked numerically in tests/applications/test_app_sweep.cpp against finite
// differences). The motion is A(t)[x] = R(t) x + T(t) with R = M(q) / w, w = |q|^2, for a
// quaternion curve q(t) that never vanishes; R is a rotation (R^T R = I, det R = 1). A point S of
// the body moves with velocity A'(t)[S] = R' S + T', and a direction (a tangent S_u, S_v or a
// normal) is only rotated: A(t)[S_u] = R S_u. The envelope condition (4) of the paper is then
//   F = det[R' S + T', R S_u, R S_v] = det R * det[R^T R' S + R^T T', S_u, S_v]
//     = (R^T R' S + R^T T') . (S_u x S_v).
// R^T R' is skew: R^T R' x = omega x x with the body angular velocity omega. With p = q / |q|
// (a unit quaternion, R = R(p)), omega = 2 vec(conj(p) p'); since
// conj(p) p' = conj(q) q' / w - (|q|' / |q|^3) conj(q) q and conj(q) q = w is real,
// omega = Omega / w with the polynomial Omega = 2 vec(conj(q) q')
// (MotionExpr::bodyAngularVelocity). With S = P / W, S_u x S_v = N / W^4
// (N = SurfaceExpr::normal()) and R^T = M^T / w:
//   F = (Omega x P / (w W) + M^T T' / w) . N / W^4 = [(Omega x P + W M^T T') . N] / (w W^5),
// and w W^5 > 0, so the cleared equation (Omega x P + W M^T T') . N = 0 has the same zero set.
// The silhouette condition (5) for the eye point E, with A(t)[N] = R N:
//   G = <R S + T - E, R N> = <S + R^T (T - E), N> = <w P + W M^T (T - E), N> / (w W),
// cleared: <w P + W M^T (T - E), N> = 0. The image of a solution (u, v, t) is
//   A(t)[S(u, v)] = M P / (w W) + T = (M P + w W T) / (w W).
// All of it is formed in Bernstein arithmetic on the input control points (Expression leaves).
#include "applications/sweep_common.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "framework/problem/application.hpp"

namespace ndc {

namespace {

/// Bernstein coefficients of the product of two Bezier polynomials of degrees
/// a.size() - 1 and b.size() - 1 (on the same interval).
std::vector<double> bernsteinProduct(const std::vector<double>& a, const std::vector<double>& b) {
  const int p = static_cast<int>(a.size()) - 1, q = static_cast<int>(b.size()) - 1;
  auto binomial = [](int n, int k) {
    double r = 1;
    for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
    return r;
  };
  std::vector<double> c(p + q + 1, 0.0);
  for (int i = 0; i <= p; ++i)
    for (int j = 0; j <= q; ++j)
      c[i + j] += binomial(p, i) * binomial(q, j) / binomial(p + q, i + j) * a[i] * b[j];
  return c;
}

/// Whether the Bernstein polynomial `c` is positive on its interval: all
/// coefficients above `floor` proves it; an end value at or below `floor`
/// disproves it; otherwise halve.
bool positive(const std::vector<double>& c, double floor, int depth) {
  if (std::all_of(c.begin(), c.end(), [&](double x) { return x > floor; })) return true;
  if (c.front() <= floor || c.back() <= floor || depth == 0) return false;
  // de Casteljau at 1/2: left half from the first, right half from the last of
  // each row.
  std::vector<double> row = c, left, right(c.size());
  const std::size_t n = c.size();
  for (std::size_t r = 0; r < n; ++r) {
    left.push_back(row.front());
    right[n - 1 - r] = row.back();
    for (std::size_t i = 0; i + 1 < row.size(); ++i) row[i] = 0.5 * (row[i] + row[i + 1]);
    row.pop_back();
  }
  return positive(left, floor, depth - 1) && positive(right, floor, depth - 1);
}

}  // namespace

bool quaternionNeverZero(const MotionSpec& motion) {
  // w = q0^2 + q1^2 + q2^2 + q3^2 in the Bernstein basis of the time range.
  std::vector<double> w;
  for (int c = 0; c < 4; ++c) {
    std::vector<double> qc;
    for (const auto& q : motion.rotation) qc.push_back(q[c]);
    const std::vector<double> sq = bernsteinProduct(qc, qc);
    if (w.empty()) w.assign(sq.size(), 0.0);
    for (std::size_t i = 0; i < sq.size(); ++i) w[i] += sq[i];
  }
  double largest = 0;
  for (double x : w) largest = std::max(largest, std::abs(x));
  if (!(largest > 0)) return false;
  return positive(w, 1e-12 * largest, 40);
}

SweepSetup makeSweep(const ApplicationInput& in, bool needsEye) {
  const std::string& app = in.application;
  // Sec. 3.2 / 3.4: one object O bounded by one freeform surface S(u, v), moved
  // by A(t).
  if (in.surfaces.size() != 1)
    in.fail(app + " needs exactly one [[surfaces]] (the moving body's boundary), got " +
            std::to_string(in.surfaces.size()));
  if (!in.motion) in.fail(app + " needs a [motion] (translation, rotation, time)");
  if (needsEye && !in.eye) in.fail(app + " needs the eye point: eye = [x, y, z]");
  if (!needsEye && in.eye) in.fail("eye is only used by sweep-silhouette, not by " + app);
  // R = M(q) / |q|^2 must be defined at every instant of the motion.
  if (!quaternionNeverZero(*in.motion)) {
    const std::string range = "[" + TomlReader::format(in.motion->time[0]) + ", " +
                              TomlReader::format(in.motion->time[1]) + "]";
    in.fail(
        "motion.rotation: the quaternion curve q(t) vanishes (or nearly) "
        "on the time range " +
        range + ", where the rotation is undefined");
  }

  SweepSetup s;
  s.spec = &in.surfaces[0];
  s.motion = &*in.motion;
  s.S = makeSurface(*s.spec, kSweepVariables, 0, 1);
  s.A = makeMotion(*s.motion, kSweepVariables, 2);
  s.N = s.S.normal();
  return s;
}

std::array<Expression, 3> transposeTimes(const std::array<std::array<Expression, 3>, 3>& M,
                                         const std::array<Expression, 3>& x) {
  std::array<Expression, 3> y;
  for (int c = 0; c < 3; ++c) y[c] = M[0][c] * x[0] + M[1][c] * x[1] + M[2][c] * x[2];
  return y;
}

Expression envelopeEquation(const SweepSetup& sweep) {
  const SurfaceExpr& S = sweep.S;
  const MotionExpr& A = sweep.A;
  // Eq. (4) in the body frame: the velocity of the point, R^T A'(t)[S] = omega
  // x S + R^T T', times w W, dotted with the normal N (the multiple W^4 of S_u
  // x S_v).
  std::array<Expression, 3> translational = transposeTimes(A.M, A.dT);
  if (S.rational) translational = scale(S.W, translational);
  const std::array<Expression, 3> velocity = cross(A.bodyAngularVelocity(), S.P) + translational;
  Expression F = dot(velocity, sweep.N);
  F.setText("envelope (4), cleared: (Omega x P + W M^T T') . N");
  return F;
}

Expression silhouetteEquation(const SweepSetup& sweep, const std::array<double, 3>& eye) {
  const SurfaceExpr& S = sweep.S;
  const MotionExpr& A = sweep.A;
  // Eq. (5) in the body frame: the point seen from the eye, R^T (A(t)[S] - E) =
  // S + R^T (T - E), times w W, dotted with the normal N.
  const std::array<Expression, 3> T = A.T - constantVector(kSweepVariables, eye);
  std::array<Expression, 3> offset = transposeTimes(A.M, T);
  if (S.rational) offset = scale(S.W, offset);
  Expression G = dot(scale(A.w, S.P) + offset, sweep.N);
  G.setText("silhouette (5), cleared: <w P + W M^T (T - E), N>");
  return G;
}

Problem sweepProblem(const ApplicationInput& in, const SweepSetup& sweep,
                     std::vector<Expression> equations) {
  const SurfaceSpec& spec = *sweep.spec;
  const MotionSpec& motion = *sweep.motion;
  const SurfaceExpr& S = sweep.S;
  const MotionExpr& A = sweep.A;

  Problem p;
  p.name = in.name;
  p.description = in.description;
  p.variables = {"u", "v", "t"};
  // Domain: the surface's parameter ranges (span coordinates for B-splines) and
  // the time range.
  const auto ru = variableRange(spec, 0), rv = variableRange(spec, 1);
  p.domain.lo = {ru[0], rv[0], motion.time[0]};
  p.domain.hi = {ru[1], rv[1], motion.time[1]};
  p.equations = std::move(equations);
  p.expect = in.expect;

  auto app = std::make_shared<ApplicationData>();
  app->name = in.application;
  // Image A(t)[S(u, v)] = (M P + w W T) / (w W).
  const Expression wW = S.rational ? A.w * S.W : A.w;
  const std::array<Expression, 3> MP{dot(A.M[0], S.P), dot(A.M[1], S.P), dot(A.M[2], S.P)};
  app->image.numerator = MP + scale(wW, A.T);
  app->image.denominator = wW;
  app->singularName = "image denominator w W (quaternion norm times surface weight)";
  // Input: the body at five instants of the motion, like the paper's Fig. 9(a).
  constexpr int kInstants = 5, kGrid = 24;
  for (int i = 0; i < kInstants; ++i) {
    const double t = motion.time[0] + (motion.time[1] - motion.time[0]) * i / (kInstants - 1);
    tessellate(spec, i, kGrid, app->input, &motion, t);
  }
  app->knots = {distinctKnots(spec, 0), distinctKnots(spec, 1), {}};
  p.application = std::move(app);
  setPatches(p);
  return p;
}

}  // namespace ndc
