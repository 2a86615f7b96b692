/// \file face_solver.hpp
/// The crossings of the level set F = c with one face of a leaf of the crossing connection: a
/// square system in the face's free variables, solved from the equations' programs by Krawczyk
/// contraction and halving, or from Bernstein face slices (docs/crossing.md, "Faces by
/// evaluation"). Internal to the crossing connection; a header of its own so that tests can
/// drive it on faces with planted roots.
#pragma once

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

#include "framework/core/bernstein.hpp"
#include "framework/core/box.hpp"
#include "framework/core/interval.hpp"
#include "framework/core/inverse.hpp"
#include "framework/core/iteration.hpp"
#include "framework/core/midrad.hpp"
#include "framework/core/scalar.hpp"
#include "framework/core/system.hpp"

namespace ndc::crossing_detail {

template <class S>
using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// Outcome of the Krawczyk test on a face box.
enum class Krawczyk { kUnique, kNone, kUnknown };

/// Which ends of a face's free axes lie on the domain boundary. There the face has no
/// neighbour to share a crossing with, so it is closed, and it keeps crossings up to `slack`
/// outside (the perturbed level set F = c leaves the domain by that much where M touches it).
struct FaceEnds {
  std::vector<bool> lower, upper;
};

/// The midpoint-radius evaluators of `system`'s equations for the calling thread, built on first
/// use and kept while the same programs (at the same MPFR precision) come back: faces are
/// solved on the pool's threads, and an evaluator's scratch must not be shared.
template <class S>
std::vector<MidRadEvaluator<S>>& threadEvaluators(const System<S>& system) {
  thread_local std::vector<std::shared_ptr<const Tape>> tapes;
  thread_local unsigned bits = 0;
  thread_local std::vector<MidRadEvaluator<S>> evaluators;
  thread_local std::vector<S> origin;
  const auto& equations = system.equations();
  bool same = tapes.size() == equations.size() && bits == ScalarTraits<S>::precisionBits() &&
              origin == system.origin();
  for (std::size_t i = 0; same && i < equations.size(); ++i)
    same = tapes[i].get() == equations[i].sharedTape().get();
  if (!same) {
    tapes.clear();
    evaluators.clear();
    origin = system.origin();
    for (const Expression& e : equations) {
      tapes.push_back(e.sharedTape());
      evaluators.emplace_back(e.sharedTape(), std::span<const S>(origin));
    }
    bits = ScalarTraits<S>::precisionBits();
  }
  return evaluators;
}

/// An interval holding [mid - rad, mid + rad] although both ends are rounded to nearest: widened
/// by two units of the arithmetic relative to each end and by the smallest normal double.
template <class S>
Interval<S> enclosingInterval(const S& mid, const S& rad) {
  using std::abs;
  const S eps = 2 * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  const S lo = mid - rad, hi = mid + rad;
  return Interval<S>(lo - (abs(lo) * eps + tiny), hi + (abs(hi) * eps + tiny));
}

/// Midpoint-radius enclosures of the system F over the box centre +- radius (radius 0 on the
/// axes it fixes), with the thread's `evaluators`: J(X) restricted to the variables `columns`
/// into `jacobian` (m x columns.size(), row-major) and F(centre) - level into `fy`. `excluded`
/// tells whether some F_i - level_i provably has no zero on the box: its value over the box, or
/// its mean-value form F_i(centre) + sum_j J_ij(X) (X_j - centre_j), excludes 0 (the columns
/// must then hold every axis the box is wide in). With `stopWhenExcluded` it returns at the first
/// such equation with `jacobian` and `fy` incomplete. False when a run fails (a value that is not
/// finite): then nothing is proven.
template <class S>
bool encloseSystem(std::vector<MidRadEvaluator<S>>& evaluators, std::span<const S> centre,
                   std::span<const S> radius, std::span<const S> level,
                   std::span<const int> columns, std::vector<Interval<S>>& jacobian,
                   std::vector<Interval<S>>& fy, bool& excluded, bool stopWhenExcluded) {
  using I = Interval<S>;
  using std::abs;
  const std::size_t m = evaluators.size(), width = columns.size();
  const S up = S(1) + S(8 * (centre.size() + m + 8)) * ScalarTraits<S>::epsilon();
  jacobian.resize(m * width);
  fy.resize(m);
  excluded = false;
  for (std::size_t i = 0; i < m; ++i) {
    MidRadEvaluator<S>& e = evaluators[i];
    const I c(level[i]);
    // Over the box with the gradient: the value and J(X); and the value at the centre.
    if (!e.runWithCentre(centre, radius)) return false;
    const bool natural = !(enclosingInterval(e.mid(0), e.rad(0)) - c).containsZero();
    S spread = 0;  // sum_j mag J_ij(X) radius_j
    for (std::size_t j = 0; j < width; ++j) {
      const int q = columns[j] + 1;
      jacobian[i * width + j] = enclosingInterval(e.mid(q), e.rad(q));
      spread += (abs(e.mid(q)) + e.rad(q)) * radius[columns[j]];
    }
    fy[i] = enclosingInterval(e.centreMid(), e.centreRad()) - c;
    const I meanValue = fy[i] + I(-spread * up, spread * up);
    excluded = excluded || natural || !meanValue.containsZero();
    if (excluded && stopWhenExcluded) return true;
  }
  return true;
}

/// Finds the crossings of the level set F = c with one m-face: the roots of the m constraints
/// minus the level c (docs/crossing.md, "General position"), restricted to the face, a square
/// system in the face's m free variables. For m = 1 the level is 0 and the sign rule decides.
template <class S>
class FaceSolver {
 public:
  FaceSolver(const System<S>& system, int maxDepth, std::span<const S> level, S slack) {
    reset(system, maxDepth, level, std::move(slack));
  }
  /// A solver to reset() before use.
  FaceSolver() = default;

  /// Solves on `system` from now on, as if constructed so; the working storage of earlier
  /// solves is kept (a solver reused face after face allocates nothing once warm).
  void reset(const System<S>& system, int maxDepth, std::span<const S> level, S slack) {
    system_ = &system;
    n_ = system.n();
    m_ = system.m();
    maxDepth_ = maxDepth;
    level_.assign(level.begin(), level.end());
    slack_ = std::move(slack);
    f_.resize(m_);
    jacobian_.resize(std::size_t(m_) * n_);
  }

  /// Solves on the face whose fixed coordinates are given in `point` (free ones are
  /// overwritten); `patches` are the face slices of F (m variables, domain = the face box),
  /// shifted here by the level; `ends` marks the free axes' domain ends. Appends the roots
  /// (full n-dim points) to `roots`; returns false if some root could not be proven unique.
  /// `margins[i]`: coefficients of F_i smaller than this in magnitude may have the wrong sign
  /// (the rounding bound of the Bernstein forms, docs/certificate.md).
  bool solve(std::span<const S> point, std::span<const int> freeAxes,
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

  /// Solves on the face as solve() does, from the equations' programs alone (docs/crossing.md,
  /// "Faces by evaluation"): a box is excluded when the interval value of some F_i - c_i (the
  /// natural extension intersected with the mean-value form) excludes 0, and a root is kept
  /// when Newton finds it and the Krawczyk test with the interval Jacobian proves it unique.
  /// Its cost is polynomial in m, where a face slice of a Bernstein form has (d + 1)^m
  /// coefficients; every decision is a proof. Returns false, leaving `roots` unspecified, when
  /// some box is not decided within kEvaluationDepth halvings of the face or kEvaluationBoxes
  /// boxes, or when the Krawczyk test proves a root that Newton does not find inside: then
  /// solve() with the Bernstein slices decides the face (with its handling of tangencies and
  /// rounding). `face` is the box of the free coordinates; m >= 2.
  bool solveByEvaluation(std::span<const S> point, std::span<const int> freeAxes,
                         const Box<S>& face, const FaceEnds& ends,
                         std::vector<std::vector<S>>& roots) {
    return solveByEvaluation(point, freeAxes, face, ends, roots, [] { return false; });
  }

  /// solveByEvaluation with a test of the caller's, `excludesFace()` (true: the face holds no
  /// root, a proof), asked once, when the first enclosure of the whole face neither excludes
  /// it nor proves a root unique: a face that one round decides never pays for the test.
  template <class ExcludesFace>
  bool solveByEvaluation(std::span<const S> point, std::span<const int> freeAxes,
                         const Box<S>& face, const FaceEnds& ends,
                         std::vector<std::vector<S>>& roots, const ExcludesFace& excludesFace) {
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

  /// Whether every decision of the last solve is a proof: exclusions by coefficient signs
  /// beyond the rounding margin or by interval evaluation, uniqueness and existence by the
  /// Krawczyk test in interval arithmetic, edge signs by interval values.
  bool proven() const { return proven_ && certain_; }
  /// Whether an exclusion of the last solve was left unproven because F comes within rounding
  /// of zero on the face (M touches it): no finer face can prove it either.
  bool withinRounding() const { return withinRounding_; }

 private:
  void recurse(const std::vector<Bernstein<S>>& patches, const FaceEnds& ends, int depth,
               std::vector<std::vector<S>>& roots) {
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
    // Undecided at the smallest face size, or after the face's budget of boxes (where F = c
    // has a continuum of roots on the face, as on a degenerate surface patch, the recursion
    // would otherwise visit up to 2^(maxDepth m) boxes): keep Newton's root, flag the face
    // uncertain.
    if (depth >= maxDepth_ * m_ || ++boxes_ > kMaxBoxes) {
      certain_ = false;
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

  /// One box of solveByEvaluation: false when it is left undecided. `owner` is the half-open
  /// part of the face the box answers for (its crossings are the roots inside it); `search`,
  /// inside it, holds all of owner's roots: the Krawczyk operator contracts it, since every
  /// root in X lies in K(X), before it is halved.
  /// `excludesFace` (null below the whole face): solveByEvaluation's.
  template <class ExcludesFace>
  bool evaluationRecurse(const Box<S>& owner, Box<S> search, const FaceEnds& ends, int depth,
                         std::vector<std::vector<S>>& roots, const ExcludesFace* excludesFace) {
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
    if (depth >= kEvaluationDepth * m_ || ++boxes_ > kEvaluationBoxes) return false;
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
    const ExcludesFace* none = nullptr;
    return evaluationRecurse(lowerOwner, std::move(lower), lowerEnds, depth + 1, roots, none) &&
           evaluationRecurse(upperOwner, std::move(upper), upperEnds, depth + 1, roots, none);
  }

  /// Whether K(X) from the last krawczyk() on X is narrower than a quarter of X on every axis,
  /// as it is near a regular root, or at most roundingWidth (contraction has converged there).
  bool narrowImage(const Box<S>& x) const {
    if (kLower_.empty()) return false;
    for (int j = 0; j < m_; ++j) {
      const S width = kUpper_[j] - kLower_[j];
      if (!(width <= (x.hi[j] - x.lo[j]) / 4 || width <= roundingWidth(j))) return false;
    }
    return true;
  }

  /// A width on free axis j at which rounding in F(y) dominates K(X): 1024 ulps of the face's
  /// coordinates.
  S roundingWidth(int j) const {
    using std::abs;
    const S scale = std::max<S>(abs(kLower_[j]), abs(kUpper_[j])) + faceWidth_[j];
    return S(1024) * ScalarTraits<S>::epsilon() * scale;
  }

  /// Epsilon-inflation (Rump): Z, K(X) widened by its width and roundingWidth on each side,
  /// holds every root of X but, unlike X ∩ K(X), has a root near X's boundary inside it; K(Z)
  /// inside int Z proves Z's one root, which Newton finds, and so X's only root (kept when it
  /// lies in owner, the neighbour's otherwise). True when that decides X; K(X) from the last
  /// krawczyk() on X.
  bool inflatedRoot(const Box<S>& owner, const FaceEnds& ends, std::vector<std::vector<S>>& roots) {
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

  /// X <- X ∩ K(X) with K from the last krawczyk() on X; true when the volume at least halved.
  bool contract(Box<S>& x) const {
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

  /// Encloses, over the face box X, J(X) into jx_ and F(y) - c at its centre y into fy_ (y as
  /// krawczyk takes it), in midpoint-radius arithmetic (no rounding-mode switch; encloseSystem);
  /// `excluded`: some F_i - c_i provably has no zero in X. False when a run fails.
  bool enclose(const Box<S>& box, bool stopWhenExcluded, bool& excluded) {
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

  /// m = 1 (hypersurfaces, k = n - 1): the face is a grid edge, and the parity of its roots is
  /// the sign change of F between its ends (sign 0 counts as +), exactly as in 3-D dual
  /// contouring. The grid vertices are shared by all their edges, so the result is closed
  /// whatever the roots inside do. An odd edge gets one crossing, found by safeguarded Newton.
  void edge(const Box<S>& box, std::vector<std::vector<S>>& roots) {
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

  /// The sign rule on an edge is a proof when the signs of F at both ends are (the end
  /// coefficients clear the rounding margin, or interval values exclude 0 or are exactly 0,
  /// which counts as +) and the edge holds at most one root of F: the coefficients, or the
  /// differences of consecutive ones (the derivative), have one strict sign.
  bool edgeProven(const Bernstein<S>& patch) const {
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

  /// The number of roots of F on the edge patch, proven by halving into pieces that are root
  /// free (coefficients clear 0) or monotone (derivative hull clears 0; then the end signs
  /// count the root); -1 when a piece stays undecided at 2^-kMaxEdgeDepth of the edge or
  /// after `pieces` pieces.
  int provenRoots(const Bernstein<S>& patch, int depth, int& pieces) const {
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

  std::vector<S> fullPoint(const std::vector<S>& y) const {
    std::vector<S> x = point_;
    for (int j = 0; j < m_; ++j) x[free_[j]] = y[j];
    return x;
  }

  bool insideClosed(const Box<S>& box, const std::vector<S>& y) const {
    for (int j = 0; j < m_; ++j) {
      if (y[j] < box.lo[j] || y[j] > box.hi[j]) return false;
    }
    return true;
  }

  /// Half-open `[lo, hi)` inside the grid, closed and widened by the slack at domain ends.
  bool inside(const Box<S>& box, const FaceEnds& ends, const std::vector<S>& y) const {
    for (int j = 0; j < m_; ++j) {
      if (ends.lower[j] ? y[j] < box.lo[j] - slack_ : y[j] < box.lo[j]) return false;
      if (ends.upper[j] ? y[j] > box.hi[j] + slack_ : y[j] >= box.hi[j]) return false;
    }
    return true;
  }

  /// Square Newton on the face from its centre, damped (the step is halved until the residual
  /// drops, and the iterate stays within two face widths), so that it also converges near a
  /// fold of M where the face Jacobian is nearly singular; true if it converged.
  bool newton(const Box<S>& box, std::vector<S>& y) {
    using std::abs;
    using std::sqrt;
    y.resize(m_);
    S width = 0;
    for (int j = 0; j < m_; ++j) {
      y[j] = (box.lo[j] + box.hi[j]) / 2;
      width = std::max<S>(width, box.hi[j] - box.lo[j]);
    }
    const S eps = ScalarTraits<S>::epsilon();
    std::vector<S>& jf = newtonJ_;  // J over the free axes, m x m, column-major
    std::vector<S>& rhs = newtonRhs_;
    std::vector<S>& step = newtonStep_;
    std::vector<S>& x = newtonX_;
    std::vector<S>& trial = newtonTrial_;
    jf.resize(std::size_t(m_) * m_);
    rhs.resize(m_);
    step.resize(m_);
    x.assign(point_.begin(), point_.end());
    trial.resize(m_);
    // max_i |F_i - c_i| at the free coordinates `at`; the Jacobian into jacobian_.
    const auto residual = [&](const std::vector<S>& at) {
      for (int j = 0; j < m_; ++j) x[free_[j]] = at[j];
      system_->evaluate(x, f_, jacobian_);
      S r = 0;
      for (int i = 0; i < m_; ++i) {
        rhs[i] = f_[i] - level_[i];
        r = std::max<S>(r, abs(rhs[i]));
      }
      return r;
    };
    S r = residual(y);
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
      for (int i = 0; i < m_; ++i) {
        for (int j = 0; j < m_; ++j)
          jf[std::size_t(j) * m_ + i] = jacobian_[std::size_t(i) * n_ + free_[j]];
      }
      // The step J^-1 (F - c) by Gauss-Jordan with partial pivoting (no allocation; a pivot
      // below m eps of the largest entry: singular).
      if (!invertGaussJordan(m_, jf, newtonInverse_)) return false;
      S size = 0, scale = 1;
      for (int j = 0; j < m_; ++j) {
        S sum = 0;
        for (int i = 0; i < m_; ++i) sum += newtonInverse_[std::size_t(i) * m_ + j] * rhs[i];
        step[j] = sum;
        size = std::max<S>(size, abs(sum));
        scale = std::max<S>(scale, abs(y[j]));
      }
      if (size <= 64 * eps * scale) return true;
      // Where the face Jacobian is nearly singular the steps stall above 64 eps: stop when the
      // residual is at rounding level. Only a step that did not shrink to a quarter of the last
      // one can be stalling (converging steps shrink far faster), so only then is the residual
      // enclosed in interval arithmetic.
      const bool stalling = previous >= 0 && size > previous / 4;
      previous = size;
      if (stalling && size <= 1e-3 * width && residualWithinRounding(y)) return true;
      // Damping: halve the step until it stays near the face and lowers the residual.
      const S lambda = halveStep<S>(30, [&](const S& t, int halving) {
        for (int j = 0; j < m_; ++j) {
          trial[j] = y[j] - t * step[j];
          // Within two face widths (false for NaN).
          if (!(trial[j] >= box.lo[j] - 2 * width && trial[j] <= box.hi[j] + 2 * width))
            return false;
        }
        const S rt = residual(trial);
        // Near the root the residual is at rounding level: accept the full step there.
        if (!(rt < r || (halving == 0 && size <= 1e-6 * width))) return false;
        y = trial;
        r = rt;
        return true;
      });
      // No step lowers the residual: converged iff it is at rounding level (the interval value
      // of F - c at y contains 0), as happens where the face Jacobian is nearly singular.
      if (lambda == 0) return residualWithinRounding(y);
      if (lambda * size <= 64 * eps * scale) return true;
    }
    return false;
  }

  /// Whether F - c on the free coordinates y, widened by rounding, encloses 0 in outward-rounded
  /// interval arithmetic.
  bool residualWithinRounding(const std::vector<S>& y) const {
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
      const I f =
          system_->equations()[i].template evaluate<S>(std::span<const I>(xi)) - I(level_[i]);
      // Twice the enclosure's width: the evaluation order of F differs from the tape's.
      const S slack = f.upper() - f.lower();
      if (f.lower() - slack > 0 || f.upper() + slack < 0) return false;
    }
    return true;
  }

  /// Krawczyk operator on the face box X with y = mid X, Y = J(y)^-1:
  /// K = y - Y F(y) + (I - Y J(X)) (X - y). K inside int X proves one root in X;
  /// K disjoint from X proves none. J(X) comes from the Bernstein derivative hulls.
  Krawczyk krawczyk(const std::vector<Bernstein<S>>& patches) {
    // J(X) from the hulls of the derivative patches, widened by the rounding margin.
    const Box<S>& box = patches.front().domain();
    jx_.resize(std::size_t(m_) * m_);
    for (int i = 0; i < m_; ++i) {
      for (int j = 0; j < m_; ++j)
        jx_[std::size_t(i) * m_ + j] = derivativeHull(patches[i], j, margins_[i]);
    }
    return krawczyk(box);
  }

  /// J(X) on a box (free coordinates) into jx_, by interval evaluation of the gradients
  /// (outward rounded; for boxes that are not a face patch's).
  void intervalJacobian(const Box<S>& box) {
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

  /// Whether F_i - c_i, evaluated in interval arithmetic over the face box, excludes 0.
  bool intervalExcludes(const Box<S>& box, int i) const {
    using I = Interval<S>;
    std::vector<I>& x = intervalX_;
    x.clear();
    for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
    for (int j = 0; j < m_; ++j) x[free_[j]] = I(box.lo[j], box.hi[j]);
    const I f = system_->equations()[i].template evaluate<S>(std::span<const I>(x)) - I(level_[i]);
    return !f.containsZero();
  }

  /// The box `root +- width` (the face's width per free axis) around a Newton root.
  Box<S> aroundRoot(const std::vector<S>& root, const Box<S>& face) const {
    Box<S> box{root, root};
    for (int j = 0; j < m_; ++j) {
      const S w = face.hi[j] - face.lo[j];
      box.lo[j] -= w;
      box.hi[j] += w;
    }
    return box;
  }

  /// Krawczyk on the box `root +- width` around a Newton root, with J(X) from the interval
  /// gradient; it contains the whole current face when `width` is the face's width, so
  /// kUnique proves the root is the face's only one even when it lies near the face boundary.
  Krawczyk krawczykAround(const std::vector<S>& root, const Box<S>& face) {
    const Box<S> box = aroundRoot(root, face);
    intervalJacobian(box);
    return krawczyk(box);
  }

  /// Krawczyk operator on the box X with y = mid X, Y = J(y)^-1 and J(X) enclosed by jx_:
  /// K = y - Y F(y) + (I - Y J(X)) (X - y). K inside int X proves one root in X;
  /// K disjoint from X proves none.
  Krawczyk krawczyk(const Box<S>& box, const std::vector<Interval<S>>* given = nullptr) {
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

  /// K(X) = y - Y F(y) + (I - Y J(X)) (X - y), row i into kLower_[i], kUpper_[i]; in double one
  /// kernel with one rounding-mode switch (ndc::krawczykOperator), the same operations.
  void krawczykOperator(const Box<S>& box, const std::vector<S>& y, const std::vector<S>& inverse,
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

  const System<S>* system_ = nullptr;
  int n_ = 0, m_ = 0, maxDepth_ = 0;
  std::vector<S> level_;  ///< c: the crossings are those of F = c
  S slack_;               ///< how far outside the domain a crossing is still kept
  std::vector<S> point_;
  std::vector<int> free_;
  std::vector<S> f_, jacobian_;
  std::vector<Interval<S>> jx_;
  std::vector<Interval<S>> fy_;            ///< F(y) - c at the centre of enclose()'s box
  std::vector<S> centre_, radius_, zero_;  ///< enclose()'s evaluation point and radii
  std::vector<S> kLower_, kUpper_;         ///< the Krawczyk operator's rows
  std::span<const S> margins_;
  bool certain_ = true;
  bool proven_ = true;
  bool withinRounding_ = false;
  /// Boxes of the current face subdivided so far, and the most one face may take: an isolated
  /// root needs about 2 maxDepth m boxes, a fold a few times that.
  long boxes_ = 0;
  static constexpr long kMaxBoxes = 4096;
  /// solveByEvaluation's limits: beyond them the face goes to the Bernstein solve, which
  /// handles what evaluation alone cannot decide (tangencies, roots within rounding).
  static constexpr int kEvaluationDepth = 3;
  static constexpr long kEvaluationBoxes = 64;
  /// Krawczyk contractions of one box before it is halved.
  static constexpr int kContractions = 8;
  std::vector<S> faceWidth_;  ///< solveByEvaluation's face widths, to pick the axis to halve
  // Working storage kept across solves; no function holds one of these while it calls another
  // function that uses the same one.
  std::vector<std::vector<Bernstein<S>>> halves_;  ///< recurse's halves, two per depth
  std::vector<FaceEnds> halfEnds_;                 ///< and their ends
  std::vector<S> root_;                            ///< recurse's Newton root
  std::vector<S> newtonX_, newtonTrial_;           ///< newton's point and trial step
  std::vector<S> newtonJ_, newtonInverse_;         ///< newton's J and its inverse, column-major
  std::vector<S> newtonRhs_, newtonStep_;
  std::vector<S> krawczykJ_, krawczykInverse_;  // column-major
  std::vector<S> krawczykY_, krawczykX_;
  std::vector<Interval<S>> krawczykFy_, krawczykXi_;
  mutable std::vector<Interval<S>> intervalX_, roundingX_, gradient_;
};

}  // namespace ndc::crossing_detail
