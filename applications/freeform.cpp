// Freeform input: Bezier and B-spline surfaces (Bezier extraction by knot insertion), motions,
// vector helpers, tessellation and the B-spline patches of a problem.
#include "applications/freeform.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace ndc {

namespace {

using Vec4 = std::array<double, 4>;  // homogeneous control point (w x, w y, w z, w)

/// Boehm knot insertion of `t` into a B-spline curve of degree p with control points `ctrl`.
void insertKnot(std::vector<double>& knots, std::vector<Vec4>& ctrl, int p, double t) {
  // The span k with knots[k] <= t < knots[k + 1]; at the upper end of the parameter range of an
  // unclamped knot vector that span has no control points, so there k is the span with
  // knots[k] < t <= knots[k + 1] (both give the same curve; each stays inside the arrays).
  int k = static_cast<int>(std::upper_bound(knots.begin(), knots.end(), t) - knots.begin()) - 1;
  if (k > static_cast<int>(ctrl.size()) - 1)
    k = static_cast<int>(std::lower_bound(knots.begin(), knots.end(), t) - knots.begin()) - 1;
  std::vector<Vec4> out(ctrl.size() + 1);
  for (int i = 0; i < static_cast<int>(out.size()); ++i) {
    if (i <= k - p) {
      out[i] = ctrl[i];
    } else if (i > k) {
      out[i] = ctrl[i - 1];
    } else {
      const double a = (t - knots[i]) / (knots[i + p] - knots[i]);
      for (int c = 0; c < 4; ++c) out[i][c] = a * ctrl[i][c] + (1 - a) * ctrl[i - 1][c];
    }
  }
  knots.insert(knots.begin() + k + 1, t);
  ctrl = std::move(out);
}

/// Bezier extraction of one B-spline curve: every distinct knot of the parameter range gets
/// multiplicity at least p, then span s (of nonzero length, in order) has the Bezier points
/// ctrl[j - p .. j], j the last index of its lower knot. Returns one (p + 1)-point net per span.
std::vector<std::vector<Vec4>> extract(std::vector<double> knots, std::vector<Vec4> ctrl, int p) {
  const double a = knots[p], b = knots[ctrl.size()];
  std::vector<double> distinct;
  for (double k : knots)
    if (k >= a && k <= b && (distinct.empty() || k != distinct.back())) distinct.push_back(k);
  for (double v : distinct) {
    while (std::count(knots.begin(), knots.end(), v) < p) insertKnot(knots, ctrl, p, v);
  }
  std::vector<std::vector<Vec4>> spans;
  for (std::size_t s = 0; s + 1 < distinct.size(); ++s) {
    const int j = static_cast<int>(std::upper_bound(knots.begin(), knots.end(), distinct[s]) -
                                   knots.begin()) -
                  1;
    spans.emplace_back(ctrl.begin() + (j - p), ctrl.begin() + j + 1);
  }
  return spans;
}

/// de Casteljau of a Bezier curve of homogeneous points at local parameter t in [0, 1].
Vec4 deCasteljau(std::vector<Vec4> pts, double t) {
  for (std::size_t r = 1; r < pts.size(); ++r)
    for (std::size_t i = 0; i + r < pts.size(); ++i)
      for (int c = 0; c < 4; ++c) pts[i][c] += t * (pts[i + 1][c] - pts[i][c]);
  return pts[0];
}

/// The homogeneous control net of a surface (u fastest), w x, w y, w z, w.
std::vector<Vec4> homogeneousNet(const SurfaceSpec& s) {
  std::vector<Vec4> net(s.points.size());
  for (std::size_t i = 0; i < net.size(); ++i) {
    const double w = s.rational() ? s.weights[i] : 1.0;
    net[i] = {w * s.points[i][0], w * s.points[i][1], w * s.points[i][2], w};
  }
  return net;
}

/// Bezier pieces of the surface: nets[su + spansU * sv] of (degreeU + 1) x (degreeV + 1) points,
/// u fastest, and the number of spans per direction.
struct Extracted {
  int spansU = 1, spansV = 1;
  std::vector<std::vector<Vec4>> nets;
};

Extracted extractSurface(const SurfaceSpec& s) {
  const std::vector<Vec4> net = homogeneousNet(s);
  const int p = s.degreeU, q = s.degreeV;
  // Along u, row by row: rows[v][span] = p + 1 points.
  std::vector<std::vector<std::vector<Vec4>>> rows(s.countV);
  for (int j = 0; j < s.countV; ++j) {
    std::vector<Vec4> row(net.begin() + j * s.countU, net.begin() + (j + 1) * s.countU);
    rows[j] = s.bspline() ? extract(s.knotsU, row, p) : std::vector<std::vector<Vec4>>{row};
  }
  Extracted e;
  e.spansU = static_cast<int>(rows[0].size());
  // Along v, column by column of every u span.
  std::vector<std::vector<std::vector<Vec4>>> columns(e.spansU * (p + 1));  // [su (p+1) + i][sv]
  for (int su = 0; su < e.spansU; ++su)
    for (int i = 0; i <= p; ++i) {
      std::vector<Vec4> column(s.countV);
      for (int j = 0; j < s.countV; ++j) column[j] = rows[j][su][i];
      columns[su * (p + 1) + i] =
          s.knotsV.empty() ? std::vector<std::vector<Vec4>>{column} : extract(s.knotsV, column, q);
    }
  e.spansV = static_cast<int>(columns[0].size());
  for (int sv = 0; sv < e.spansV; ++sv)
    for (int su = 0; su < e.spansU; ++su) {
      std::vector<Vec4> piece((p + 1) * (q + 1));
      for (int j = 0; j <= q; ++j)
        for (int i = 0; i <= p; ++i) piece[j * (p + 1) + i] = columns[su * (p + 1) + i][sv][j];
      e.nets.push_back(std::move(piece));
    }
  return e;
}

/// Span-coordinate breaks 0, 1, ..., spans (B-spline) or the Bezier box ends.
std::vector<double> breaksOf(const SurfaceSpec& s, int d, int spans) {
  if (d == 0 ? s.knotsU.empty() : s.knotsV.empty()) return {s.box[2 * d], s.box[2 * d + 1]};
  std::vector<double> b(spans + 1);
  for (int i = 0; i <= spans; ++i) b[i] = i;
  return b;
}

Expression leafOf(int n, std::shared_ptr<const PiecewiseBernstein> leaf) {
  return Expression::polynomial(n, std::move(leaf));
}

Expression derivativeOf(int n, const PiecewiseBernstein& leaf, int a) {
  return leafOf(n, std::make_shared<const PiecewiseBernstein>(leaf.derivative(a)));
}

/// A univariate Bezier leaf on [t0, t1] in variable t from component c of the points.
template <std::size_t D>
std::shared_ptr<const PiecewiseBernstein> curveLeaf(const std::string& name,
                                                    const std::vector<std::array<double, D>>& pts,
                                                    std::size_t c, int t,
                                                    const std::array<double, 2>& time) {
  auto leaf = std::make_shared<PiecewiseBernstein>();
  leaf->name = name;
  leaf->axes = {t};
  leaf->breaks = {{time[0], time[1]}};
  Bernstein<double> piece(Box<double>{{time[0]}, {time[1]}}, {static_cast<int>(pts.size()) - 1});
  for (std::size_t i = 0; i < pts.size(); ++i) piece.coefficients()[i] = pts[i][c];
  leaf->pieces.push_back(std::move(piece));
  return leaf;
}

template <std::size_t D>
std::array<double, D> evaluateCurve(const std::vector<std::array<double, D>>& pts, double s) {
  std::vector<std::array<double, D>> w = pts;
  for (std::size_t r = 1; r < w.size(); ++r)
    for (std::size_t i = 0; i + r < w.size(); ++i)
      for (std::size_t c = 0; c < D; ++c) w[i][c] += s * (w[i + 1][c] - w[i][c]);
  return w[0];
}

}  // namespace

// ---- Surfaces
// ------------------------------------------------------------------------------------

std::array<double, 2> SurfaceSpec::range(int d) const {
  const auto& knots = d == 0 ? knotsU : knotsV;
  if (knots.empty()) return {box[2 * d], box[2 * d + 1]};
  const int p = d == 0 ? degreeU : degreeV, count = d == 0 ? countU : countV;
  return {knots[p], knots[count]};
}

namespace {

/// The surface point at (u, v) from its Bezier pieces `e`: locate the piece, then de Casteljau.
std::array<double, 3> evaluateExtracted(const SurfaceSpec& s, const Extracted& e, double u,
                                        double v) {
  const auto locate = [&](int d, double x, int spans, double& local) {
    const auto& knots = d == 0 ? s.knotsU : s.knotsV;
    if (knots.empty()) {
      local = (x - s.box[2 * d]) / (s.box[2 * d + 1] - s.box[2 * d]);
      return 0;
    }
    const std::vector<double> distinct = distinctKnots(s, d);
    int span = 0;
    while (span + 1 < spans && x >= distinct[span + 1]) ++span;
    local = (x - distinct[span]) / (distinct[span + 1] - distinct[span]);
    return span;
  };
  double lu, lv;
  const int su = locate(0, u, e.spansU, lu), sv = locate(1, v, e.spansV, lv);
  const auto& net = e.nets[sv * e.spansU + su];
  std::vector<Vec4> column;
  for (int j = 0; j <= s.degreeV; ++j) {
    std::vector<Vec4> row(net.begin() + j * (s.degreeU + 1),
                          net.begin() + (j + 1) * (s.degreeU + 1));
    column.push_back(deCasteljau(row, lu));
  }
  const Vec4 h = deCasteljau(column, lv);
  return {h[0] / h[3], h[1] / h[3], h[2] / h[3]};
}

}  // namespace

std::array<double, 3> SurfaceSpec::evaluate(double u, double v) const {
  return evaluateExtracted(*this, extractSurface(*this), u, v);
}

std::vector<double> distinctKnots(const SurfaceSpec& spec, int d) {
  const auto& knots = d == 0 ? spec.knotsU : spec.knotsV;
  if (knots.empty()) return {};
  const auto r = spec.range(d);
  std::vector<double> out;
  for (double k : knots)
    if (k >= r[0] && k <= r[1] && (out.empty() || k != out.back())) out.push_back(k);
  return out;
}

std::array<double, 2> variableRange(const SurfaceSpec& spec, int d) {
  const auto& knots = d == 0 ? spec.knotsU : spec.knotsV;
  if (knots.empty()) return {spec.box[2 * d], spec.box[2 * d + 1]};
  // Span coordinates, padded to a power of two spans so every span is a dyadic grid cell.
  const int spans = static_cast<int>(distinctKnots(spec, d).size()) - 1;
  int padded = 1;
  while (padded < spans) padded *= 2;
  return {0.0, static_cast<double>(padded)};
}

SurfaceExpr makeSurface(const SurfaceSpec& spec, int n, int u, int v) {
  const Extracted e = extractSurface(spec);
  const std::vector<double> bu = breaksOf(spec, 0, e.spansU), bv = breaksOf(spec, 1, e.spansV);
  const char* names[4] = {"x", "y", "z", "w"};
  std::shared_ptr<const PiecewiseBernstein> leaves[4];
  for (int c = 0; c < 4; ++c) {
    auto leaf = std::make_shared<PiecewiseBernstein>();
    leaf->name = spec.name + "." + names[c];
    leaf->axes = {u, v};
    leaf->breaks = {bu, bv};
    for (int sv = 0; sv < e.spansV; ++sv)
      for (int su = 0; su < e.spansU; ++su) {
        Bernstein<double> piece(Box<double>{{bu[su], bv[sv]}, {bu[su + 1], bv[sv + 1]}},
                                {spec.degreeU, spec.degreeV});
        const auto& net = e.nets[sv * e.spansU + su];
        for (std::size_t i = 0; i < net.size(); ++i) piece.coefficients()[i] = net[i][c];
        leaf->pieces.push_back(std::move(piece));
      }
    leaves[c] = std::move(leaf);
  }
  SurfaceExpr s;
  s.rational = spec.rational();
  for (int c = 0; c < 3; ++c) {
    s.P[c] = leafOf(n, leaves[c]);
    s.Pu[c] = derivativeOf(n, *leaves[c], 0);
    s.Pv[c] = derivativeOf(n, *leaves[c], 1);
  }
  if (s.rational) {
    s.W = leafOf(n, leaves[3]);
    s.Wu = derivativeOf(n, *leaves[3], 0);
    s.Wv = derivativeOf(n, *leaves[3], 1);
  } else {
    s.W = Expression::constant(n, 1);
    s.Wu = s.Wv = Expression::constant(n, 0);
  }
  return s;
}

std::array<Expression, 3> SurfaceExpr::tangentU() const {
  if (!rational) return Pu;
  return scale(W, Pu) - scale(Wu, P);
}

std::array<Expression, 3> SurfaceExpr::tangentV() const {
  if (!rational) return Pv;
  return scale(W, Pv) - scale(Wv, P);
}

std::array<Expression, 3> SurfaceExpr::normal() const { return cross(tangentU(), tangentV()); }

// ---- Motions
// -------------------------------------------------------------------------------------

std::array<double, 3> MotionSpec::apply(double t, const std::array<double, 3>& x) const {
  const double s = (t - time[0]) / (time[1] - time[0]);
  const auto T = evaluateCurve(translation, s);
  const auto q = evaluateCurve(rotation, s);
  const double a = q[0], b = q[1], c = q[2], d = q[3], w = a * a + b * b + c * c + d * d;
  const double M[3][3] = {
      {a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
      {2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)},
      {2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d}};
  std::array<double, 3> y;
  for (int r = 0; r < 3; ++r) y[r] = (M[r][0] * x[0] + M[r][1] * x[1] + M[r][2] * x[2]) / w + T[r];
  return y;
}

MotionExpr makeMotion(const MotionSpec& spec, int n, int t) {
  MotionExpr m;
  const char* axis[3] = {"x", "y", "z"};
  for (int c = 0; c < 3; ++c) {
    auto leaf = curveLeaf("T." + std::string(axis[c]), spec.translation, c, t, spec.time);
    m.T[c] = leafOf(n, leaf);
    m.dT[c] = derivativeOf(n, *leaf, 0);
  }
  for (int c = 0; c < 4; ++c) {
    auto leaf = curveLeaf("q" + std::to_string(c), spec.rotation, c, t, spec.time);
    m.q[c] = leafOf(n, leaf);
    m.dq[c] = derivativeOf(n, *leaf, 0);
  }
  const Expression &a = m.q[0], &b = m.q[1], &c = m.q[2], &d = m.q[3];
  const Expression two = Expression::constant(n, 2);
  m.w = a * a + b * b + c * c + d * d;
  m.M[0] = {a * a + b * b - c * c - d * d, two * (b * c - a * d), two * (b * d + a * c)};
  m.M[1] = {two * (b * c + a * d), a * a - b * b + c * c - d * d, two * (c * d - a * b)};
  m.M[2] = {two * (b * d - a * c), two * (c * d + a * b), a * a - b * b - c * c + d * d};
  return m;
}

std::array<Expression, 3> MotionExpr::bodyAngularVelocity() const {
  // vec(conj(q) q') = a v' - a' v - v x v' with q = (a, v), q' = (a', v').
  const std::array<Expression, 3> v{q[1], q[2], q[3]}, dv{dq[1], dq[2], dq[3]};
  const std::array<Expression, 3> vec = scale(q[0], dv) - scale(dq[0], v) - cross(v, dv);
  return scale(Expression::constant(q[0].dim(), 2), vec);
}

// ---- Vector helpers
// ------------------------------------------------------------------------------

std::array<Expression, 3> cross(const std::array<Expression, 3>& a,
                                const std::array<Expression, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

Expression dot(const std::array<Expression, 3>& a, const std::array<Expression, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

std::array<Expression, 3> scale(const Expression& s, const std::array<Expression, 3>& a) {
  return {s * a[0], s * a[1], s * a[2]};
}

std::array<Expression, 3> operator+(const std::array<Expression, 3>& a,
                                    const std::array<Expression, 3>& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

std::array<Expression, 3> operator-(const std::array<Expression, 3>& a,
                                    const std::array<Expression, 3>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

std::array<Expression, 3> constantVector(int n, const std::array<double, 3>& c) {
  return {Expression::constant(n, c[0]), Expression::constant(n, c[1]),
          Expression::constant(n, c[2])};
}

// ---- Tessellation and patches
// --------------------------------------------------------------------

void tessellate(const SurfaceSpec& spec, int part, int k, TriangleSoup& input,
                const MotionSpec* motion, double t) {
  const auto ru = spec.range(0), rv = spec.range(1);
  const int base = static_cast<int>(input.vertices.size());
  // Extract the Bezier pieces once, not per point: a 64 x 64 net of degree 12 took minutes.
  const Extracted pieces = extractSurface(spec);
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i <= k; ++i) {
      auto x = evaluateExtracted(spec, pieces, ru[0] + (ru[1] - ru[0]) * i / k,
                                 rv[0] + (rv[1] - rv[0]) * j / k);
      if (motion) x = motion->apply(t, x);
      input.vertices.push_back(x);
    }
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const int a = base + j * (k + 1) + i, b = a + 1, c = a + k + 1, d = c + 1;
      input.triangles.push_back({a, b, d});
      input.triangles.push_back({a, d, c});
      input.part.push_back(part);
      input.part.push_back(part);
    }
}

void setPatches(Problem& problem) {
  const int n = problem.n();
  // Per variable: every break of every leaf, and the range the leaves cover.
  std::vector<std::vector<double>> breaks(n);
  std::vector<double> lo(problem.domain.lo), hi(problem.domain.hi);
  bool interior = false;
  for (int j = 0; j < n; ++j) {
    for (const Expression& e : problem.equations) {
      const std::vector<double> b = e.breaks(j);
      breaks[j].insert(breaks[j].end(), b.begin(), b.end());
    }
    if (breaks[j].empty()) continue;
    const auto [mn, mx] = std::minmax_element(breaks[j].begin(), breaks[j].end());
    lo[j] = std::max(lo[j], *mn);
    hi[j] = std::min(hi[j], *mx);
    for (double b : breaks[j]) interior = interior || (b > lo[j] && b < hi[j]);
    interior = interior || lo[j] > problem.domain.lo[j] || hi[j] < problem.domain.hi[j];
  }
  problem.roots.clear();
  problem.rootLevel = 0;
  if (!interior) return;
  // The coarsest level J at which every break lies on a grid plane.
  int level = 0;
  for (int j = 0; j < n; ++j)
    for (double b : breaks[j]) {
      const double r = (b - problem.domain.lo[j]) / problem.domain.width(j);
      int J = 0;
      while (J <= 16 && std::abs(r * std::ldexp(1.0, J) - std::round(r * std::ldexp(1.0, J))) >
                            1e-12 * std::ldexp(1.0, J))
        ++J;
      if (J > 16)
        throw InputError("the knot " + std::to_string(b) +
                         " does not lie on a dyadic grid plane of the domain");
      level = std::max(level, J);
    }
  // Root cells: the cells of level J inside the range the leaves cover, on every axis.
  const std::int64_t cells = std::int64_t{1} << level;
  std::vector<std::vector<std::int64_t>> keep(n);
  for (int j = 0; j < n; ++j)
    for (std::int64_t i = 0; i < cells; ++i) {
      const double a = problem.domain.lo[j] + problem.domain.width(j) * i / cells;
      const double b = problem.domain.lo[j] + problem.domain.width(j) * (i + 1) / cells;
      if (a >= lo[j] - 1e-12 && b <= hi[j] + 1e-12) keep[j].push_back(i);
    }
  std::size_t total = 1;
  for (int j = 0; j < n; ++j) total *= keep[j].size();
  if (total == 0 || total > 100000)
    throw InputError("the B-spline patches give " + std::to_string(total) +
                     " root boxes (at most 100000 are supported)");
  for (std::size_t r = 0; r < total; ++r) {
    Box<double> box;
    std::size_t rest = r;
    for (int j = 0; j < n; ++j) {
      const std::int64_t i = keep[j][rest % keep[j].size()];
      rest /= keep[j].size();
      box.lo.push_back(problem.domain.lo[j] + problem.domain.width(j) * i / cells);
      box.hi.push_back(problem.domain.lo[j] + problem.domain.width(j) * (i + 1) / cells);
    }
    problem.roots.push_back(std::move(box));
  }
  problem.rootLevel = level;
}

}  // namespace ndc
