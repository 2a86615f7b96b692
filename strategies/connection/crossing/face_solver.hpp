/// \file face_solver.hpp
/// The crossings of the level set F = c with one face of a leaf of the crossing connection: a
/// square system in the face's free variables, solved from the equations' programs by Krawczyk
/// contraction and halving, or from Bernstein face slices (docs/crossing.md, "Faces by
/// evaluation"). Internal to the crossing connection; a header of its own so that tests can
/// drive it on faces with planted roots.
#pragma once

#include <span>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/system.hpp"
#include "strategies/connection/crossing/function_ref.hpp"

namespace ndc::crossing_detail {

/// Outcome of the Krawczyk test on a face box.
enum class Krawczyk { kUnique, kNone, kUnknown };

/// Which ends of a face's free axes lie on the domain boundary. There the face has no
/// neighbour to share a crossing with, so it is closed, and it keeps crossings up to `slack`
/// outside (the perturbed level set F = c leaves the domain by that much where M touches it).
struct FaceEnds {
  std::vector<bool> lower, upper;
};

/// Finds the crossings of the level set F = c with one m-face: the roots of the m constraints
/// minus the level c (docs/crossing.md, "General position"), restricted to the face, a square
/// system in the face's m free variables. For m = 1 the level is 0 and the sign rule decides.
template <class S>
class FaceSolver {
 public:
  FaceSolver(const System<S>& system, int maxDepth, std::span<const S> level, S slack);
  /// A solver to reset() before use.
  FaceSolver() = default;
  /// Solves on `system` from now on, as if constructed so; the working storage of earlier
  /// solves is kept (a solver reused face after face allocates nothing once warm).
  void reset(const System<S>& system, int maxDepth, std::span<const S> level, S slack);
  /// Solves on the face whose fixed coordinates are given in `point` (free ones are
  /// overwritten); `patches` are the face slices of F (m variables, domain = the face box),
  /// shifted here by the level; `ends` marks the free axes' domain ends. Appends the roots
  /// (full n-dim points) to `roots`; returns false if some root could not be proven unique.
  /// `margins[i]`: coefficients of F_i smaller than this in magnitude may have the wrong sign
  /// (the rounding bound of the Bernstein forms, docs/certificate.md).
  bool solve(std::span<const S> point, std::span<const int> freeAxes,
             std::vector<Bernstein<S>>& patches, const FaceEnds& ends,
             std::vector<std::vector<S>>& roots, std::span<const S> margins);
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
                         std::vector<std::vector<S>>& roots);
  /// solveByEvaluation with a test of the caller's, `excludesFace()` (true: the face holds no
  /// root, a proof), asked once, when the first enclosure of the whole face neither excludes
  /// it nor proves a root unique: a face that one round decides never pays for the test.
  bool solveByEvaluation(std::span<const S> point, std::span<const int> freeAxes,
                         const Box<S>& face, const FaceEnds& ends,
                         std::vector<std::vector<S>>& roots, FunctionRef<bool()> excludesFace);
  /// Sets solveByEvaluation's budget from what one box of the Bernstein solve would cost:
  /// `coefficients`, the Bernstein coefficients of the face slices of all m equations (each box
  /// of the Bernstein solve bounds m derivatives of each, m (d + 1)^m operations per equation,
  /// where a box by evaluation costs a run of the programs, polynomial in m). While the forms
  /// are small (up to 16 kEvaluationBoxes coefficients) the budget is kEvaluationBoxes boxes of
  /// depth kEvaluationDepth per axis; beyond, coefficients / 16 boxes (at most
  /// kMaxEvaluationBoxes) of depth kLargeEvaluationDepth per axis, so that a face whose slices
  /// have (d + 1)^m coefficients is decided by evaluation (docs/performance.md, "Without
  /// dense forms"). Without `fallback` (the caller will not solve the face on its slices; it
  /// stays unproven, and its leaves may be refined) at most kUnaidedEvaluationBoxes: a smaller
  /// face is cheaper to decide than a large one that evaluation cannot. Kept across reset().
  void setBernsteinCost(double coefficients, bool fallback);
  /// Whether every decision of the last solve is a proof: exclusions by coefficient signs
  /// beyond the rounding margin or by interval evaluation, uniqueness and existence by the
  /// Krawczyk test in interval arithmetic, edge signs by interval values.
  bool proven() const { return proven_ && certain_; }
  /// Whether an exclusion of the last solve was left unproven because F comes within rounding
  /// of zero on the face (M touches it): no finer face can prove it either.
  bool withinRounding() const { return withinRounding_; }

 private:
  void recurse(const std::vector<Bernstein<S>>& patches, const FaceEnds& ends, int depth,
               std::vector<std::vector<S>>& roots);
  /// One box of solveByEvaluation: false when it is left undecided. `owner` is the half-open
  /// part of the face the box answers for (its crossings are the roots inside it); `search`,
  /// inside it, holds all of owner's roots: the Krawczyk operator contracts it, since every
  /// root in X lies in K(X), before it is halved.
  /// `excludesFace` (null below the whole face): solveByEvaluation's.
  bool evaluationRecurse(const Box<S>& owner, Box<S> search, const FaceEnds& ends, int depth,
                         std::vector<std::vector<S>>& roots,
                         const FunctionRef<bool()>* excludesFace);
  /// Whether K(X) from the last krawczyk() on X is narrower than a quarter of X on every axis,
  /// as it is near a regular root, or at most roundingWidth (contraction has converged there).
  bool narrowImage(const Box<S>& x) const;
  /// A width on free axis j at which rounding in F(y) dominates K(X): 1024 ulps of the face's
  /// coordinates.
  S roundingWidth(int j) const;
  /// Epsilon-inflation (Rump): Z, K(X) widened by its width and roundingWidth on each side,
  /// holds every root of X but, unlike X ∩ K(X), has a root near X's boundary inside it; K(Z)
  /// inside int Z proves Z's one root, which Newton finds, and so X's only root (kept when it
  /// lies in owner, the neighbour's otherwise). True when that decides X; K(X) from the last
  /// krawczyk() on X.
  bool inflatedRoot(const Box<S>& owner, const FaceEnds& ends, std::vector<std::vector<S>>& roots);
  /// X <- X ∩ K(X) with K from the last krawczyk() on X; true when the volume at least halved.
  bool contract(Box<S>& x) const;
  /// Encloses, over the face box X, J(X) into jx_ and F(y) - c at its centre y into fy_ (y as
  /// krawczyk takes it), in midpoint-radius arithmetic (no rounding-mode switch; encloseSystem);
  /// `excluded`: some F_i - c_i provably has no zero in X. False when a run fails.
  bool enclose(const Box<S>& box, bool stopWhenExcluded, bool& excluded);
  /// m = 1 (hypersurfaces, k = n - 1): the face is a grid edge, and the parity of its roots is
  /// the sign change of F between its ends (sign 0 counts as +), exactly as in 3-D dual
  /// contouring. The grid vertices are shared by all their edges, so the result is closed
  /// whatever the roots inside do. An odd edge gets one crossing, found by safeguarded Newton.
  void edge(const Box<S>& box, std::vector<std::vector<S>>& roots);
  /// The sign rule on an edge is a proof when the signs of F at both ends are (the end
  /// coefficients clear the rounding margin, or interval values exclude 0 or are exactly 0,
  /// which counts as +) and the edge holds at most one root of F: the coefficients, or the
  /// differences of consecutive ones (the derivative), have one strict sign.
  bool edgeProven(const Bernstein<S>& patch) const;
  /// The number of roots of F on the edge patch, proven by halving into pieces that are root
  /// free (coefficients clear 0) or monotone (derivative hull clears 0; then the end signs
  /// count the root); -1 when a piece stays undecided at 2^-kMaxEdgeDepth of the edge or
  /// after `pieces` pieces.
  int provenRoots(const Bernstein<S>& patch, int depth, int& pieces) const;
  std::vector<S> fullPoint(const std::vector<S>& y) const;
  bool insideClosed(const Box<S>& box, const std::vector<S>& y) const;
  /// Half-open `[lo, hi)` inside the grid, closed and widened by the slack at domain ends.
  bool inside(const Box<S>& box, const FaceEnds& ends, const std::vector<S>& y) const;
  /// Square Newton on the face from its centre, damped (the step is halved until the residual
  /// drops, and the iterate stays within two face widths), so that it also converges near a
  /// fold of M where the face Jacobian is nearly singular; true if it converged.
  bool newton(const Box<S>& box, std::vector<S>& y);
  /// newton's start: y at the face's centre, its working storage sized; returns the face's
  /// largest width.
  S newtonStart(const Box<S>& box, std::vector<S>& y);
  /// max_i |F_i - c_i| at the free coordinates `at`, with F - c into newtonRhs_ and the
  /// Jacobian into jacobian_.
  S newtonResidual(const std::vector<S>& at);
  /// The Newton step J^-1 (F - c) at y into newtonStep_ (J from the last newtonResidual), its
  /// largest entry `size` and the scale max(1, |y|); false when J is singular.
  bool newtonStep(const std::vector<S>& y, S& size, S& scale);
  /// Damping: the step newtonStep_ halved until it stays within two widths of the face `box`
  /// and lowers the residual `r` (or, near the root, taken whole); y and r move there. Returns
  /// the step's factor, 0 when none lowers the residual.
  S dampedStep(const Box<S>& box, const S& width, const S& size, std::vector<S>& y, S& r);
  /// Whether F - c on the free coordinates y, widened by rounding, encloses 0 in outward-rounded
  /// interval arithmetic.
  bool residualWithinRounding(const std::vector<S>& y) const;
  /// Krawczyk operator on the face box X with y = mid X, Y = J(y)^-1:
  /// K = y - Y F(y) + (I - Y J(X)) (X - y). K inside int X proves one root in X;
  /// K disjoint from X proves none. J(X) comes from the Bernstein derivative hulls.
  Krawczyk krawczyk(const std::vector<Bernstein<S>>& patches);
  /// J(X) on a box (free coordinates) into jx_, by interval evaluation of the gradients
  /// (outward rounded; for boxes that are not a face patch's).
  void intervalJacobian(const Box<S>& box);
  /// Whether F_i - c_i, evaluated in interval arithmetic over the face box, excludes 0.
  bool intervalExcludes(const Box<S>& box, int i) const;
  /// The box `root +- width` (the face's width per free axis) around a Newton root.
  Box<S> aroundRoot(const std::vector<S>& root, const Box<S>& face) const;
  /// Krawczyk on the box `root +- width` around a Newton root, with J(X) from the interval
  /// gradient; it contains the whole current face when `width` is the face's width, so
  /// kUnique proves the root is the face's only one even when it lies near the face boundary.
  Krawczyk krawczykAround(const std::vector<S>& root, const Box<S>& face);
  /// Krawczyk operator on the box X with y = mid X, Y = J(y)^-1 and J(X) enclosed by jx_:
  /// K = y - Y F(y) + (I - Y J(X)) (X - y). K inside int X proves one root in X;
  /// K disjoint from X proves none.
  Krawczyk krawczyk(const Box<S>& box, const std::vector<Interval<S>>* given = nullptr);
  /// K(X) = y - Y F(y) + (I - Y J(X)) (X - y), row i into kLower_[i], kUpper_[i]; in double one
  /// kernel with one rounding-mode switch (ndc::krawczykOperator), the same operations.
  void krawczykOperator(const Box<S>& box, const std::vector<S>& y, const std::vector<S>& inverse,
                        const std::vector<Interval<S>>& fy);
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
  /// solveByEvaluation's limits by default: beyond them the face goes to the Bernstein solve,
  /// which handles what evaluation alone cannot decide (tangencies, roots within rounding).
  static constexpr int kEvaluationDepth = 3;
  static constexpr long kEvaluationBoxes = 64;
  /// The limits where the Bernstein solve is dear (setBernsteinCost).
  static constexpr int kLargeEvaluationDepth = 6;
  static constexpr long kMaxEvaluationBoxes = 4096;
  static constexpr long kUnaidedEvaluationBoxes = 256;
  int evaluationDepth_ = kEvaluationDepth;
  long evaluationBoxes_ = kEvaluationBoxes;
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

extern template class FaceSolver<double>;
extern template class FaceSolver<Mpfr>;

}  // namespace ndc::crossing_detail
