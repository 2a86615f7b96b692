#include "strategies/connection/crossing/face_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "framework/numeric/inverse.hpp"
#include "framework/numeric/iteration.hpp"
#include "strategies/connection/crossing/certificate.hpp"
#include "strategies/connection/crossing/enclosure.hpp"

namespace ndc::crossing_detail {

template <class S>
FaceSolver<S>::FaceSolver(const System<S>& system, int maxDepth, std::span<const S> level,
                          S slack) {
  reset(system, maxDepth, level, std::move(slack));
}

template <class S>
void FaceSolver<S>::reset(const System<S>& system, int maxDepth, std::span<const S> level,
                          S slack) {
  system_ = &system;
  n_ = system.n();
  m_ = system.m();
  maxDepth_ = maxDepth;
  level_.assign(level.begin(), level.end());
  slack_ = std::move(slack);
  f_.resize(m_);
  jacobian_.resize(std::size_t(m_) * n_);
}

template <class S>
void FaceSolver<S>::setBernsteinCost(double coefficients, bool fallback) {
  const double boxes =
      std::min(coefficients / 16, fallback ? 1e300 : double(kUnaidedEvaluationBoxes));
  if (!(boxes > double(kEvaluationBoxes))) {
    evaluationBoxes_ = kEvaluationBoxes;
    evaluationDepth_ = kEvaluationDepth;
    return;
  }
  evaluationBoxes_ = static_cast<long>(std::min(boxes, double(kMaxEvaluationBoxes)));
  evaluationDepth_ = kLargeEvaluationDepth;
}

template <class S>
bool FaceSolver<S>::solve(std::span<const S> point, std::span<const int> freeAxes,
                          std::vector<Bernstein<S>>& patches, const FaceEnds& ends,
                          std::vector<std::vector<S>>& roots, std::span<const S> margins) {
  point_.assign(point.begin(), point.end());
  free_.assign(freeAxes.begin(), freeAxes.end());
  margins_ = margins;
  certain_ = true;
  proven_ = true;
  withinRounding_ = false;
  boxes_ = 0;
  if (m_ == 1) {
    edge(patches.front().domain(), roots);
    proven_ = edgeProven(patches.front());
    return true;
  }
  for (int i = 0; i < m_; ++i) {
    for (S& c : patches[i].coefficients()) c -= level_[i];
  }
  // Two halves per depth of the recursion, sized before it (it holds references into them).
  const auto depths = std::size_t(maxDepth_) * std::size_t(m_) + 1;
  if (halves_.size() < 2 * depths) halves_.resize(2 * depths);
  if (halfEnds_.size() < 2 * depths) halfEnds_.resize(2 * depths);
  recurse(patches, ends, 0, roots);
  return certain_;
}

template <class S>
bool FaceSolver<S>::solveByEvaluation(std::span<const S> point, std::span<const int> freeAxes,
                                      const Box<S>& face, const FaceEnds& ends,
                                      std::vector<std::vector<S>>& roots) {
  return solveByEvaluation(point, freeAxes, face, ends, roots, [] { return false; });
}

template <class S>
bool FaceSolver<S>::solveByEvaluation(std::span<const S> point, std::span<const int> freeAxes,
                                      const Box<S>& face, const FaceEnds& ends,
                                      std::vector<std::vector<S>>& roots,
                                      FunctionRef<bool()> excludesFace) {
  point_.assign(point.begin(), point.end());
  free_.assign(freeAxes.begin(), freeAxes.end());
  certain_ = true;
  proven_ = true;
  withinRounding_ = false;
  boxes_ = 0;
  faceWidth_.resize(m_);
  for (int j = 0; j < m_; ++j) faceWidth_[j] = face.hi[j] - face.lo[j];
  return evaluationRecurse(face, face, ends, 0, roots, &excludesFace);
}

template <class S>
void FaceSolver<S>::recurse(const std::vector<Bernstein<S>>& patches, const FaceEnds& ends,
                            int depth, std::vector<std::vector<S>>& roots) {
  //! [crossing-face]
  // Exclusion: a coefficient hull of one sign on the face means no root.
  const Box<S>& box = patches.front().domain();
  for (std::size_t i = 0; i < patches.size(); ++i) {
    if (!patches[i].excludesZero()) continue;
    // The exclusion is a proof when every coefficient clears the rounding margin, or when
    // interval evaluation confirms it; otherwise the decision stands but is not proven.
    if (!clearsRange(patches[i], S(0), S(0), margins_[i]) && !intervalExcludes(box, int(i)))
      proven_ = false, withinRounding_ = true;
    return;
  }
  // Krawczyk first: a box it proves root free needs no Newton iteration (on a face near M,
  // most boxes of the recursion are such, and damped Newton there runs to its limit).
  const Krawczyk k = krawczyk(patches);
  if (k == Krawczyk::kNone) return;
  std::vector<S>& root = root_;  // not needed once the recursion goes deeper
  const bool found = newton(box, root) && inside(box, ends, root);
  if (found && (k == Krawczyk::kUnique || krawczykAround(root, box) == Krawczyk::kUnique)) {
    roots.push_back(fullPoint(root));
    return;
  }
  if (k == Krawczyk::kUnique && !found) {
    // The unique root lies in the closed face; if Newton did not reach it inside the
    // half-open face, it is on an upper boundary owned by the next face, or Newton strayed.
    std::vector<S>& y = root_;
    if (newton(box, y) && insideClosed(box, y)) {
      proven_ = false;  // K proves the root interior, Newton puts it on the boundary
      return;           // owned by the neighbour face
    }
    // Newton failed, but K inside int X proves one root strictly inside this box (so inside
    // the half-open face): keep it, at the box centre (a fold of F = c, where the face
    // Jacobian is nearly singular, can stall Newton's convergence test).
    for (int j = 0; j < m_; ++j) y[j] = (box.lo[j] + box.hi[j]) / 2;
    roots.push_back(fullPoint(y));
    return;
  }
  // Undecided at the smallest face size (a tangency, or F = c with a continuum of roots on
  // the face, as on a degenerate surface patch: the depth-first recursion follows it down to
  // there first): keep Newton's root, flag the face uncertain; no finer face decides it.
  if (depth >= maxDepth_ * m_) {
    certain_ = false;
    if (found) roots.push_back(fullPoint(root));
    return;
  }
  // The face's budget of boxes spent with no box at the smallest size: a face too large to
  // decide within it (a coarse leaf's face of a surface in R^10 has 8 free axes), unproven but
  // not uncertain: its leaves fail and are refined, and smaller faces are decided (until
  // issue 42 this flagged the face uncertain, so the leaves were never refined and the
  // 2-sphere in R^10 stayed uncertified at depths 3 and 4).
  if (++boxes_ > kMaxBoxes) {
    proven_ = false;
    if (found) roots.push_back(fullPoint(root));
    return;
  }
  // Subdivide the face along its free axes in turn (half-open children).
  const int axis = depth % m_;
  std::vector<Bernstein<S>>& lower = halves_[2 * std::size_t(depth)];
  std::vector<Bernstein<S>>& upper = halves_[2 * std::size_t(depth) + 1];
  lower.resize(patches.size());
  upper.resize(patches.size());
  for (std::size_t i = 0; i < patches.size(); ++i) patches[i].halve(axis, lower[i], upper[i]);
  FaceEnds& lowerEnds = halfEnds_[2 * std::size_t(depth)];
  FaceEnds& upperEnds = halfEnds_[2 * std::size_t(depth) + 1];
  lowerEnds = ends, upperEnds = ends;
  lowerEnds.upper[axis] = false;
  upperEnds.lower[axis] = false;
  recurse(lower, lowerEnds, depth + 1, roots);
  recurse(upper, upperEnds, depth + 1, roots);
  //! [crossing-face]
}

template <class S>
bool FaceSolver<S>::evaluationRecurse(const Box<S>& owner, Box<S> search, const FaceEnds& ends,
                                      int depth, std::vector<std::vector<S>>& roots,
                                      const FunctionRef<bool()>* excludesFace) {
  for (int round = 0;; ++round) {
    // Exclusion, J(X) and F(mid X) from midpoint-radius runs of the programs.
    bool excluded = false;
    if (!enclose(search, true, excluded)) return false;  // a value that is not finite
    if (excluded) return true;
    const Krawczyk k = krawczyk(search, &fy_);
    if (k == Krawczyk::kNone) return true;
    if (k == Krawczyk::kUnique) {
      // One root in X, none elsewhere in owner: Newton from mid X finds it.
      std::vector<S> root;
      if (!newton(search, root) || !inside(owner, ends, root)) return false;
      roots.push_back(fullPoint(root));
      return true;
    }
    if (round == 0 && excludesFace && (*excludesFace)()) return true;  // no root on the face
    // Contraction: X ∩ K(X) holds every root of X; keep it while it shrinks X at least as
    // much as a halving would.
    Box<S> contracted = search;
    const bool shrinks = contract(contracted);
    if (narrowImage(search) && inflatedRoot(owner, ends, roots)) return true;
    if (round >= kContractions || !shrinks) break;
    search = std::move(contracted);
  }
  if (depth >= evaluationDepth_ * m_ || ++boxes_ > evaluationBoxes_) return false;
  // Halve along the free axis widest relative to the face (half-open children).
  int axis = 0;
  for (int j = 1; j < m_; ++j) {
    if ((search.hi[j] - search.lo[j]) * faceWidth_[axis] >
        (search.hi[axis] - search.lo[axis]) * faceWidth_[j])
      axis = j;
  }
  const S mid = (search.lo[axis] + search.hi[axis]) / 2;
  Box<S> lowerOwner = owner, upperOwner = owner, lower = search, upper = search;
  lowerOwner.hi[axis] = lower.hi[axis] = mid;
  upperOwner.lo[axis] = upper.lo[axis] = mid;
  FaceEnds lowerEnds = ends, upperEnds = ends;
  lowerEnds.upper[axis] = false;
  upperEnds.lower[axis] = false;
  const FunctionRef<bool()>* none = nullptr;
  return evaluationRecurse(lowerOwner, std::move(lower), lowerEnds, depth + 1, roots, none) &&
         evaluationRecurse(upperOwner, std::move(upper), upperEnds, depth + 1, roots, none);
}

template <class S>
bool FaceSolver<S>::narrowImage(const Box<S>& x) const {
  if (kLower_.empty()) return false;
  for (int j = 0; j < m_; ++j) {
    const S width = kUpper_[j] - kLower_[j];
    if (!(width <= (x.hi[j] - x.lo[j]) / 4 || width <= roundingWidth(j))) return false;
  }
  return true;
}

template <class S>
S FaceSolver<S>::roundingWidth(int j) const {
  using std::abs;
  const S scale = std::max<S>(abs(kLower_[j]), abs(kUpper_[j])) + faceWidth_[j];
  return S(1024) * ScalarTraits<S>::epsilon() * scale;
}

template <class S>
bool FaceSolver<S>::inflatedRoot(const Box<S>& owner, const FaceEnds& ends,
                                 std::vector<std::vector<S>>& roots) {
  Box<S> z{kLower_, kUpper_};
  for (int j = 0; j < m_; ++j) {
    const S r = (z.hi[j] - z.lo[j]) + roundingWidth(j);
    z.lo[j] -= r;
    z.hi[j] += r;
  }
  bool excluded = false;
  if (!enclose(z, false, excluded) || krawczyk(z, &fy_) != Krawczyk::kUnique) return false;
  std::vector<S> root;
  if (!newton(z, root) || !insideClosed(z, root)) return false;
  if (inside(owner, ends, root)) roots.push_back(fullPoint(root));
  return true;
}

template <class S>
bool FaceSolver<S>::contract(Box<S>& x) const {
  if (kLower_.empty()) return false;  // J(mid X) singular: no operator
  S ratio = 1;
  for (int j = 0; j < m_; ++j) {
    const S lo = std::max<S>(x.lo[j], kLower_[j]), hi = std::min<S>(x.hi[j], kUpper_[j]);
    const S width = x.hi[j] - x.lo[j];
    if (width > 0) ratio *= (hi - lo) / width;
  }
  if (!(ratio <= S(0.5))) return false;
  for (int j = 0; j < m_; ++j) {
    x.lo[j] = std::max<S>(x.lo[j], kLower_[j]);
    x.hi[j] = std::min<S>(x.hi[j], kUpper_[j]);
  }
  return true;
}

template <class S>
bool FaceSolver<S>::enclose(const Box<S>& box, bool stopWhenExcluded, bool& excluded) {
  const S up = S(1) + S(8) * ScalarTraits<S>::epsilon();
  centre_ = point_;
  radius_.assign(n_, S(0));
  for (int j = 0; j < m_; ++j) {
    const S c = (box.lo[j] + box.hi[j]) / 2;
    centre_[free_[j]] = c;
    radius_[free_[j]] = std::max<S>(box.hi[j] - c, c - box.lo[j]) * up;
  }
  return encloseSystem(threadEvaluators(*system_), std::span<const S>(centre_),
                       std::span<const S>(radius_), std::span<const S>(level_),
                       std::span<const int>(free_), jx_, fy_, excluded, stopWhenExcluded);
}

template <class S>
void FaceSolver<S>::edge(const Box<S>& box, std::vector<std::vector<S>>& roots) {
  using std::abs;
  std::vector<S> x = point_;
  const auto value = [&](const S& t) {
    x[free_[0]] = t;
    system_->evaluate(x, f_, jacobian_);
    return f_[0];
  };
  S a = box.lo[0], b = box.hi[0];
  const S fa = value(a), fb = value(b);
  const bool negativeA = fa < 0, negativeB = fb < 0;
  if (negativeA == negativeB) return;
  // Keep a bracket [a, b] with the sign change; Newton steps that leave it are bisections.
  S t = (a + b) / 2;
  const S eps = ScalarTraits<S>::epsilon();
  for (int iteration = 0; iteration < 200; ++iteration) {
    const S ft = value(t);
    if (ft == 0) break;
    if ((ft < 0) == negativeA) {
      a = t;
    } else {
      b = t;
    }
    const S slope = jacobian_[free_[0]];
    S next = slope != 0 ? t - ft / slope : (a + b) / 2;
    if (!(next > a && next < b)) next = (a + b) / 2;
    const S step = abs(next - t);
    t = next;
    if (step <= 4 * eps * (1 + abs(t)) || b - a <= 4 * eps * (1 + abs(t))) break;
  }
  x[free_[0]] = t;
  roots.push_back(std::move(x));
}

template <class S>
bool FaceSolver<S>::edgeProven(const Bernstein<S>& patch) const {
  using I = Interval<S>;
  const S& margin = margins_[0];
  const auto c = patch.coefficients();
  std::vector<I>& x = intervalX_;
  x.clear();
  for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
  const Box<S>& box = patch.domain();
  for (int end = 0; end < 2; ++end) {
    using std::abs;
    if (abs(end ? c.back() : c.front()) > margin) continue;
    x[free_[0]] = I(end ? box.hi[0] : box.lo[0]);
    const I v = system_->equations()[0].template evaluate<S>(std::span<const I>(x));
    if (v.containsZero() && !(v.lower() == 0 && v.upper() == 0)) return false;
  }
  if (clearsRange(patch, S(0), S(0), margin)) return true;
  if (!derivativeHull(patch, 0, margin).containsZero()) return true;
  // Monotone or root-free pieces with at most one sign change in all: as where the edge
  // ends on a plane of symmetry of F (dF = 0 there, the root lies inside).
  int pieces = 64;  // F = 0 along the whole edge would otherwise halve it 2^12 times
  const int roots = provenRoots(patch, 0, pieces);
  if (roots == 0 || roots == 1) return true;
  // F >= 0 on the whole edge (it may touch 0, as along a line of M on a grid line): the
  // level set F = -delta of the sign rule does not meet it.
  x[free_[0]] = I(box.lo[0], box.hi[0]);
  const I v = system_->equations()[0].template evaluate<S>(std::span<const I>(x));
  return v.lower() >= 0 || v.upper() < 0;
}

template <class S>
int FaceSolver<S>::provenRoots(const Bernstein<S>& patch, int depth, int& pieces) const {
  constexpr int kMaxEdgeDepth = 12;
  const S& margin = margins_[0];
  if (clearsRange(patch, S(0), S(0), margin)) return 0;
  if (!derivativeHull(patch, 0, margin).containsZero()) {
    using std::abs;
    const auto c = patch.coefficients();
    if (abs(c.front()) <= margin || abs(c.back()) <= margin) return -1;
    return (c.front() < 0) != (c.back() < 0) ? 1 : 0;
  }
  if (depth >= kMaxEdgeDepth || --pieces < 0) return -1;
  Bernstein<S> lower, upper;
  patch.halve(0, lower, upper);
  const int a = provenRoots(lower, depth + 1, pieces);
  if (a < 0) return -1;
  const int b = provenRoots(upper, depth + 1, pieces);
  return b < 0 ? -1 : a + b;
}

template <class S>
std::vector<S> FaceSolver<S>::fullPoint(const std::vector<S>& y) const {
  std::vector<S> x = point_;
  for (int j = 0; j < m_; ++j) x[free_[j]] = y[j];
  return x;
}

template <class S>
bool FaceSolver<S>::insideClosed(const Box<S>& box, const std::vector<S>& y) const {
  for (int j = 0; j < m_; ++j) {
    if (y[j] < box.lo[j] || y[j] > box.hi[j]) return false;
  }
  return true;
}

template <class S>
bool FaceSolver<S>::inside(const Box<S>& box, const FaceEnds& ends, const std::vector<S>& y) const {
  for (int j = 0; j < m_; ++j) {
    if (ends.lower[j] ? y[j] < box.lo[j] - slack_ : y[j] < box.lo[j]) return false;
    if (ends.upper[j] ? y[j] > box.hi[j] + slack_ : y[j] >= box.hi[j]) return false;
  }
  return true;
}

template <class S>
bool FaceSolver<S>::newton(const Box<S>& box, std::vector<S>& y) {
  const S width = newtonStart(box, y);
  const S eps = ScalarTraits<S>::epsilon();
  S r = newtonResidual(y);
  // The residuals of the last iterations: Newton converges at least linearly (by a factor 4
  // per step at a fold, where F - c is quadratic along the step); where damped steps lower
  // the residual by less than half over three iterations, y sits near a local minimum of |F - c|
  // that is not a root, as on a face M passes close to but misses.
  S history[3] = {r, r, r};
  S previous = -1;  // the last full step's size
  for (int iteration = 0; iteration < 60; ++iteration) {
    if (r == 0) return true;
    if (iteration >= 3 && !(r < history[iteration % 3] / 2)) return residualWithinRounding(y);
    history[iteration % 3] = r;
    S size = 0, scale = 1;
    if (!newtonStep(y, size, scale)) return false;
    if (size <= 64 * eps * scale) return true;
    // Where the face Jacobian is nearly singular the steps stall above 64 eps: stop when the
    // residual is at rounding level. Only a step that did not shrink to a quarter of the last
    // one can be stalling (converging steps shrink far faster), so only then is the residual
    // enclosed in interval arithmetic.
    const bool stalling = previous >= 0 && size > previous / 4;
    previous = size;
    if (stalling && size <= 1e-3 * width && residualWithinRounding(y)) return true;
    const S lambda = dampedStep(box, width, size, y, r);
    // No step lowers the residual: converged iff it is at rounding level (the interval value
    // of F - c at y contains 0), as happens where the face Jacobian is nearly singular.
    if (lambda == 0) return residualWithinRounding(y);
    if (lambda * size <= 64 * eps * scale) return true;
  }
  return false;
}

template <class S>
S FaceSolver<S>::newtonStart(const Box<S>& box, std::vector<S>& y) {
  y.resize(m_);
  S width = 0;
  for (int j = 0; j < m_; ++j) {
    y[j] = (box.lo[j] + box.hi[j]) / 2;
    width = std::max<S>(width, box.hi[j] - box.lo[j]);
  }
  newtonJ_.resize(std::size_t(m_) * m_);  // J over the free axes, m x m, column-major
  newtonRhs_.resize(m_);
  newtonStep_.resize(m_);
  newtonX_.assign(point_.begin(), point_.end());
  newtonTrial_.resize(m_);
  return width;
}

template <class S>
S FaceSolver<S>::newtonResidual(const std::vector<S>& at) {
  using std::abs;
  std::vector<S>& x = newtonX_;
  for (int j = 0; j < m_; ++j) x[free_[j]] = at[j];
  system_->evaluate(x, f_, jacobian_);
  S r = 0;
  for (int i = 0; i < m_; ++i) {
    newtonRhs_[i] = f_[i] - level_[i];
    r = std::max<S>(r, abs(newtonRhs_[i]));
  }
  return r;
}

template <class S>
bool FaceSolver<S>::newtonStep(const std::vector<S>& y, S& size, S& scale) {
  using std::abs;
  std::vector<S>& jf = newtonJ_;
  for (int i = 0; i < m_; ++i) {
    for (int j = 0; j < m_; ++j)
      jf[std::size_t(j) * m_ + i] = jacobian_[std::size_t(i) * n_ + free_[j]];
  }
  // The step J^-1 (F - c) by Gauss-Jordan with partial pivoting (no allocation; a pivot
  // below m eps of the largest entry: singular).
  if (!invertGaussJordan(m_, jf, newtonInverse_)) return false;
  for (int j = 0; j < m_; ++j) {
    S sum = 0;
    for (int i = 0; i < m_; ++i) sum += newtonInverse_[std::size_t(i) * m_ + j] * newtonRhs_[i];
    newtonStep_[j] = sum;
    size = std::max<S>(size, abs(sum));
    scale = std::max<S>(scale, abs(y[j]));
  }
  return true;
}

template <class S>
S FaceSolver<S>::dampedStep(const Box<S>& box, const S& width, const S& size, std::vector<S>& y,
                            S& r) {
  std::vector<S>& trial = newtonTrial_;
  return halveStep<S>(30, [&](const S& t, int halving) {
    for (int j = 0; j < m_; ++j) {
      trial[j] = y[j] - t * newtonStep_[j];
      // Within two face widths (false for NaN).
      if (!(trial[j] >= box.lo[j] - 2 * width && trial[j] <= box.hi[j] + 2 * width)) return false;
    }
    const S rt = newtonResidual(trial);
    // Near the root the residual is at rounding level: accept the full step there.
    if (!(rt < r || (halving == 0 && size <= 1e-6 * width))) return false;
    y = trial;
    r = rt;
    return true;
  });
}

template <class S>
bool FaceSolver<S>::residualWithinRounding(const std::vector<S>& y) const {
  using I = Interval<S>;
  std::vector<I>& xi = roundingX_;
  xi.clear();
  for (int j = 0; j < n_; ++j) xi.emplace_back(point_[j]);
  // The free coordinates widened by two units in the last place: the root itself need not
  // be representable (F - c is then never exactly 0 at a floating-point y).
  const S ulp = 2 * ScalarTraits<S>::epsilon();
  for (int j = 0; j < m_; ++j) {
    using std::abs;
    xi[free_[j]] = I(y[j] - ulp * abs(y[j]), y[j] + ulp * abs(y[j]));
  }
  for (int i = 0; i < m_; ++i) {
    const I f = system_->equations()[i].template evaluate<S>(std::span<const I>(xi)) - I(level_[i]);
    // Twice the enclosure's width: the evaluation order of F differs from the tape's.
    const S slack = f.upper() - f.lower();
    if (f.lower() - slack > 0 || f.upper() + slack < 0) return false;
  }
  return true;
}

template <class S>
Krawczyk FaceSolver<S>::krawczyk(const std::vector<Bernstein<S>>& patches) {
  // J(X) from the hulls of the derivative patches, widened by the rounding margin.
  const Box<S>& box = patches.front().domain();
  jx_.resize(std::size_t(m_) * m_);
  for (int i = 0; i < m_; ++i) {
    for (int j = 0; j < m_; ++j)
      jx_[std::size_t(i) * m_ + j] = derivativeHull(patches[i], j, margins_[i]);
  }
  return krawczyk(box);
}

template <class S>
void FaceSolver<S>::intervalJacobian(const Box<S>& box) {
  using I = Interval<S>;
  std::vector<I>& x = intervalX_;
  x.clear();
  for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
  for (int j = 0; j < m_; ++j) x[free_[j]] = I(box.lo[j], box.hi[j]);
  std::vector<I>& gradient = gradient_;
  gradient.resize(n_);
  jx_.resize(std::size_t(m_) * m_);
  for (int i = 0; i < m_; ++i) {
    system_->equations()[i].template evaluate<S>(std::span<const I>(x), std::span<I>(gradient));
    for (int j = 0; j < m_; ++j) jx_[std::size_t(i) * m_ + j] = gradient[free_[j]];
  }
}

template <class S>
bool FaceSolver<S>::intervalExcludes(const Box<S>& box, int i) const {
  using I = Interval<S>;
  std::vector<I>& x = intervalX_;
  x.clear();
  for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
  for (int j = 0; j < m_; ++j) x[free_[j]] = I(box.lo[j], box.hi[j]);
  const I f = system_->equations()[i].template evaluate<S>(std::span<const I>(x)) - I(level_[i]);
  return !f.containsZero();
}

template <class S>
Box<S> FaceSolver<S>::aroundRoot(const std::vector<S>& root, const Box<S>& face) const {
  Box<S> box{root, root};
  for (int j = 0; j < m_; ++j) {
    const S w = face.hi[j] - face.lo[j];
    box.lo[j] -= w;
    box.hi[j] += w;
  }
  return box;
}

template <class S>
Krawczyk FaceSolver<S>::krawczykAround(const std::vector<S>& root, const Box<S>& face) {
  const Box<S> box = aroundRoot(root, face);
  intervalJacobian(box);
  return krawczyk(box);
}

template <class S>
Krawczyk FaceSolver<S>::krawczyk(const Box<S>& box, const std::vector<Interval<S>>* given) {
  using I = Interval<S>;
  std::vector<S>& y = krawczykY_;
  y.resize(m_);
  for (int j = 0; j < m_; ++j) y[j] = (box.lo[j] + box.hi[j]) / 2;
  std::vector<S>& x = krawczykX_;
  x.assign(point_.begin(), point_.end());
  for (int j = 0; j < m_; ++j) x[free_[j]] = y[j];
  system_->evaluate(x, f_, jacobian_);
  std::vector<S>& jy = krawczykJ_;  // column-major
  jy.resize(std::size_t(m_) * m_);
  for (int i = 0; i < m_; ++i) {
    for (int j = 0; j < m_; ++j)
      jy[std::size_t(j) * m_ + i] = jacobian_[std::size_t(i) * n_ + free_[j]];
  }
  kLower_.clear(), kUpper_.clear();  // no operator (contract() needs one)
  std::vector<S>& inverse = krawczykInverse_;
  if (!invertGaussJordan(m_, jy, inverse)) return Krawczyk::kUnknown;
  // F(y) by interval evaluation at the point (unless given), so its rounding is enclosed.
  std::vector<I>& fy = krawczykFy_;
  if (given) {
    fy.assign(given->begin(), given->end());
  } else {
    fy.clear();
    std::vector<I>& xi = krawczykXi_;
    xi.clear();
    for (int j = 0; j < n_; ++j) xi.emplace_back(x[j]);
    for (int i = 0; i < m_; ++i) {
      fy.push_back(system_->equations()[i].template evaluate<S>(std::span<const I>(xi)) -
                   I(level_[i]));
    }
  }
  krawczykOperator(box, y, inverse, fy);
  bool unique = true;
  for (int i = 0; i < m_; ++i) {
    if (kUpper_[i] < box.lo[i] || kLower_[i] > box.hi[i]) return Krawczyk::kNone;
    if (!(kLower_[i] > box.lo[i] && kUpper_[i] < box.hi[i])) unique = false;
  }
  return unique ? Krawczyk::kUnique : Krawczyk::kUnknown;
}

template <class S>
void FaceSolver<S>::krawczykOperator(const Box<S>& box, const std::vector<S>& y,
                                     const std::vector<S>& inverse,
                                     const std::vector<Interval<S>>& fy) {
  using I = Interval<S>;
  kLower_.resize(m_);
  kUpper_.resize(m_);
  if constexpr (std::is_same_v<S, double>) {
    ndc::krawczykOperator(m_, y, std::span<const double>(inverse.data(), inverse.size()), fy, jx_,
                          box.lo, box.hi, kLower_, kUpper_);
    return;
  }
  for (int i = 0; i < m_; ++i) {
    I k(y[i]);
    for (int l = 0; l < m_; ++l) k -= I(inverse[std::size_t(l) * m_ + i]) * fy[l];
    for (int j = 0; j < m_; ++j) {
      I c(S(i == j ? 1 : 0));
      for (int l = 0; l < m_; ++l)
        c -= I(inverse[std::size_t(l) * m_ + i]) * jx_[std::size_t(l) * m_ + j];
      k += c * (I(box.lo[j], box.hi[j]) - I(y[j]));  // X - y, outward
    }
    kLower_[i] = k.lower();
    kUpper_[i] = k.upper();
  }
}

template class FaceSolver<double>;
template class FaceSolver<Mpfr>;

}  // namespace ndc::crossing_detail
