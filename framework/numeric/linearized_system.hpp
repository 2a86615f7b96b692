/// \file linearized_system.hpp
/// A system of m equations linearized over a box, J_c d = -g with g in mu +- rho and
/// |d_j| <= h_j, and the tests that prove it has no solution (docs/subdivision.md, "Linearized
/// bounding"): the subdivision's linearized bounding and the crossing connection's leaf model
/// both produce such a system and ask it the same questions.
#pragma once

#include <cstdint>
#include <vector>

#include "framework/numeric/multipliers.hpp"
#include "framework/numeric/scalar.hpp"

namespace ndc {

/// The linearized system of m equations in n unknowns over a box: every zero x = c + d of the
/// equations in the box (centre c, half-widths h_j >= |x_j - c_j|) satisfies
///
///     J_c d = -g,   g in G := mu + [-rho, rho],
///
/// for the point matrix J_c and the enclosures mu, rho that the caller fills in (`jac`, `mu`,
/// `rho`, `h`). The tests below are the steps 3 to 8 of LinearizedBounding's derivation (QR of
/// J_c^T, the row, ball, null-space, planar and multiplier tests); every one is conservative:
/// the identities hold for the matrices actually computed, and every floating-point sum is
/// bounded by the relative margin `tolerance()` (at least 2 gamma_p for the longest p-term sum),
/// so rounding never proves a solvable system empty. A rank-deficient J_c (a pivot below 1e-10
/// of the largest row) proves nothing. The working storage is sized once by resize(): the tests
/// do not allocate in double; use one instance per thread.
template <class S>
class LinearizedSystem {
 public:
  /// Sizes the system for m equations in n unknowns (m <= n) and sets the margin
  /// 8 (n + m + 8) eps.
  void resize(int n, int m);

  int n() const { return n_; }
  int m() const { return m_; }
  /// The relative rounding margin of every bound here.
  const S& tolerance() const { return tol_; }

  std::vector<S> jac;  ///< J_c, m x n, row-major (filled by the caller)
  std::vector<S> mu;   ///< the centres of G (m)
  std::vector<S> rho;  ///< the radii of G (m), rounded up
  std::vector<S> h;    ///< the box's half-widths (n), rounded up

  /// True when the tests prove that no d in the box solves the system; `hh` is |h|_2^2 rounded
  /// up, `multiplierSteps` caps the multiplier test's least-squares steps.
  bool excludes(const S& hh, int multiplierSteps);

  /// After excludes() returned false: a step d inside the box (by a relative 1e-6 on every
  /// axis) that solves J_c d = -mid G up to rounding, if step 8's shortcut found one
  /// (solvesInside), else null. c + d is a point of the linearized zero set inside the box.
  const S* insideStep() const { return insideFound_ ? inside_.data() : nullptr; }

  /// After excludes() returned false having run steps 7b and 7c (else 0; and 0 for n > 32):
  /// the halves of the box that step 7's bounds show to hold no solution, bit 2 j for d_j <= 0
  /// and bit 2 j + 1 for d_j >= 0 (the children of a halving along j; docs/subdivision.md,
  /// "Empty halves").
  std::uint64_t emptyHalves() const;

  /// After excludes() returned false having run steps 7b and 7c: bounds lo_j <= d_j <= hi_j
  /// (within -h_j..h_j) of every solution d, from step 7's bounds (what emptyHalves reads);
  /// false (nothing written) otherwise.
  bool solutionBox(std::vector<S>& lo, std::vector<S>& hi) const;

  /// For k = n - m = 2: which facets of the box (fixed axis j at its lower end, entry 2 j, or
  /// its upper end, entry 2 j + 1) may hold a solution, into `met` (2 n entries, 1: may). A
  /// facet d_j = +-h_j is ruled out when no point of the planar test's polygon in the kernel
  /// coordinates t reaches the band where (N t)_j - a_j is within the system's slack of +-h_j
  /// (docs/crossing.md, "Facets first"). Returns true when the whole box holds no solution
  /// (every entry 0); every entry stays 1 when J_c is rank-deficient or k != 2.
  bool facetsMet(std::vector<char>& met);

 private:
  /// 3: Householder QR of J_c^T into w_, beta_, diag_ and Q (q_); false when J_c is (nearly)
  /// rank-deficient.
  bool factorTranspose();
  /// Applies reflector i (column i of w_) to the column `x` (n entries).
  void reflect(int i, S* x) const;
  /// 4: P = L^{-1} (p_) with L = R^T.
  void invertLowerFactor();
  /// 5: P J_c and the row test; adds each row's mig^2 to `migSq`; true when a row excludes.
  bool rowTestExcludes(S& migSq);
  /// 6: the ball test; true when it excludes.
  bool ballTestExcludes(const S& migSq, const S& hh) const;
  /// 7a: J^+ (pinv_) and the centre a_ and bound b_ of (N t)_j per axis.
  void kernelBounds();
  /// 7b: constraint propagation on the kernel coordinates t; true when no t is left.
  bool kernelPropagationExcludes();
  /// Narrows the box of t_p by the constraint of axis j; true when it becomes empty.
  bool narrowKernelBox(int j, int p);
  /// 7c (k = 2): the exact test on the plane of t: the propagated box clipped by the 2 n
  /// half-planes of the axes' strips (its vertices left in polygon_); true when nothing is
  /// left.
  bool kernelPolygonExcludes();
  /// The largest |t_p| that kernelRange's products take: over the polygon's vertices for
  /// k = 2, else over the t box.
  S kernelReach() const;
  /// The range [lo, hi] of (N t)_j over what steps 7b and 7c left of t (the polygon for
  /// k = 2, the t box otherwise, which hold N^T d for every solution d); returns the slack
  /// that covers the rounding of the range and of comparing it with h_j and b_j.
  S kernelRange(int j, const S& reach, S& lo, S& hi) const;
  /// The range [lo, hi] of d_j over the solutions, from kernelRange and step 7's bound, its
  /// rounding included.
  void solutionRange(int j, const S& reach, S& lo, S& hi) const;
  /// Keeps the part of `polygon` (vertices (t_0, t_1) interleaved) where u . t <= bound
  /// (Sutherland-Hodgman); false when nothing is left.
  bool clip(std::vector<S>& polygon, const S& u0, const S& u1, const S& bound);
  /// clip() by u . t <= upper and then by -u . t <= lower (a strip); false when nothing is
  /// left.
  bool clipStrip(std::vector<S>& polygon, const S& u0, const S& u1, const S& upper, const S& lower);
  /// 8: the multiplier test (reweighted least squares for y); true when some y excludes.
  bool multiplierExcludes(int steps);
  /// True when some d = N t - J^+ mid G lies inside the box by a relative 1e-6 on every axis:
  /// t = 0 (d = -J^+ mid G), else a point of the region of t where every |d_j| is below
  /// h_j (1 - 1e-6) (an interval for k = 1, a polygon clipped from step 7c's for k = 2; the
  /// centre of the t box for k > 2). Such a d solves J_c d = -mid G up to rounding, so the
  /// linearized system is solvable, no multipliers exist, and step 8 is skipped (a heuristic
  /// only in that skipping never discards a box).
  bool solvesInside();
  /// Q1 (row space of J_c) and N = Q2 (its kernel) as n x m and n x k matrices.
  const S& q1(int row, int col) const {
    return q_[static_cast<std::size_t>(col) * static_cast<std::size_t>(n_) +
              static_cast<std::size_t>(row)];
  }
  const S& nul(int row, int col) const { return q1(row, m_ + col); }

  int n_ = 0, m_ = 0;
  S tol_;
  bool kernelReady_ = false;  // steps 7b and 7c ran on this system and kept it
  // Scratch (matrices row-major unless noted).
  std::vector<S> w_, beta_, diag_;           // w_: J_c^T (n x m, column-major), reflectors
  std::vector<S> q_;                         // n x n orthogonal factor, column-major
  std::vector<S> p_, pj_, pjAbs_, mig_;      // P (m x m), P J_c and |P| |J_c| (m x n)
  std::vector<S> pinv_, a_, b_, tlo_, thi_;  // J^+ (n x m), centre/bound per axis, t box
  std::vector<S> polygon_, clipped_;         // 7c: vertices (t_0, t_1) interleaved
  std::vector<S> witness_, tight_;           // solvesInside's t (k) and polygon
  std::vector<S> inside_;                    // solvesInside's d (n)
  bool insideFound_ = false;                 // inside_ holds it
  MultiplierTest<S> multipliers_;            // 8
};

extern template class LinearizedSystem<double>;
extern template class LinearizedSystem<Mpfr>;

}  // namespace ndc
