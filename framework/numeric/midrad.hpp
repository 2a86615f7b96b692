/// \file midrad.hpp
/// Evaluation of a Tape in midpoint-radius arithmetic, with or without the gradient.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "framework/numeric/scalar.hpp"
#include "framework/numeric/tape.hpp"

namespace ndc {

/// Whether the constant Hessian H of a quadratic program is semidefinite, for one-sided Taylor
/// remainders: F(c + d) - F(c) - grad F(c) . d = d^T H d / 2, which for a sum of squares (a
/// sphere, an ellipsoid, a cylinder) is never negative.
struct Curvature {
  /// +1: d^T H d / 2 >= -slack max_j d_j^2 for every d; -1: d^T H d / 2 <= slack max_j d_j^2;
  /// 0: neither is proven (H indefinite, or the program is not a quadratic without leaves).
  int sign = 0;
  double slack = 0;  ///< rounded up; covers the rounding of H's enclosure and factorisation
};

/// The curvature of `tape`, proven in double: H enclosed column by column from gradients
/// (grad F(e_k) - grad F(0), midpoint-radius), then an approximate pivoted factorisation
/// +-H ~ L D L^T with D > 0 (stopped where the remaining pivots are below 1e-12 of the largest
/// diagonal), so that d^T (+-H) d >= -sum_jk B_jk |d_j| |d_k| with B bounding H - L D L^T
/// (the enclosure's radius, the symmetrisation and every rounding). Accepted when the slack is
/// below 1e-8 of sum |H_jk|; otherwise sign 0.
Curvature quadraticCurvature(const std::shared_ptr<const Tape>& tape);

/// The Taylor remainder d^T H d / 2 over |d_j| <= h_j as a centre and radius, from `bound` >=
/// |d^T H d| / 2 (rounded up) and hMax = max_j h_j: [-bound, bound] for sign 0, and for a
/// semidefinite H the one-sided [-e, bound] (sign +1) or [-bound, e] (sign -1) with
/// e = slack hMax^2 (rounded up by `up`). The centre and radius are rounded to nearest: the
/// caller rounds the radius up with the sums it joins.
template <class S>
void taylorRemainder(const Curvature& curvature, const S& bound, const S& hMax, const S& up,
                     S& centre, S& radius) {
  if (curvature.sign == 0) {
    centre = 0;
    radius = bound;
    return;
  }
  const S e = S(curvature.slack) * hMax * hMax * up;
  centre = S(curvature.sign) * (bound - e) / 2;
  radius = (bound + e) / 2;
}

/// Runs a Tape on a box given as centre +- radius in midpoint-radius arithmetic: every
/// operation rounds to nearest and adds a bound on its rounding error (and the radii's) to the
/// radius, so the result encloses the range as rigorously as outward-rounded intervals, without
/// switching the rounding mode per operation. Underflow is ignored.
///
/// A program of total degree at most 2 without leaves (gradientAffine) is run in its quadratic
/// form about an origin o (the domain's centre): F(c + d) = F(c) + G(c) . d + d^T H d / 2 with
/// G(c) = g_o + H (c - o) and F(c) = f_o + (c - o) . (g_o + G(c)) / 2, whose coefficients
/// f_o = F(o), g_o = grad F(o) and H are enclosed once, by passes over the program at o, at 0
/// and at the unit vectors. A run then costs O(n + nonzeros of H) operations instead of a pass
/// with n + 1 components per slot, and its enclosures are never wider than the pass's up to
/// rounding (the range over the box is F(c) +- sum_j (|G_j| + (|H| h)_j / 2) h_j, the
/// gradient's G +- |H| h); the origin keeps the rounding of the expanded terms at the scale of
/// F's variation over the domain, wherever the domain lies.
///
/// The scratch is sized once: run() does not allocate, and an instance must not be shared
/// between threads.
template <class S>
class MidRadEvaluator {
 public:
  /// Prepares the constants of `tape` as midpoint and radius, and a quadratic program's form
  /// about `origin` (n values; empty: 0).
  explicit MidRadEvaluator(std::shared_ptr<const Tape> tape, std::span<const S> origin = {});

  /// Runs the program with variable j = centre[j] +- radius[j]. With `gradient` the result
  /// holds the value and the n partial derivatives, else the value only. False when a divisor
  /// encloses 0 or the value is not finite.
  bool run(std::span<const S> centre, std::span<const S> radius, bool gradient) const;

  /// run() over the box with the gradient, and also the value at the centre alone (what
  /// run(centre, 0, false) gives) into centreMid() and centreRad(): one run in a quadratic
  /// form, two passes over a program. False when either fails.
  bool runWithCentre(std::span<const S> centre, std::span<const S> radius) const;
  /// The value at the centre from the last runWithCentre().
  const S& centreMid() const { return centreMid_; }
  const S& centreRad() const { return centreRad_; }

  /// run() as a pass over the program even where it has a quadratic form (which is built by
  /// such passes); for tests and comparisons.
  bool runProgram(std::span<const S> centre, std::span<const S> radius, bool gradient) const;
  /// Whether run() uses the quadratic form.
  bool quadraticForm() const { return form_.has_value(); }

  /// Midpoint and radius of the value (q = 0) or of the partial derivative along q - 1 (after
  /// a run with the gradient).
  const S& mid(int q) const { return stackMid_[static_cast<std::size_t>(q)]; }
  const S& rad(int q) const { return stackRad_[static_cast<std::size_t>(q)]; }

  /// True when the program is a polynomial of total degree at most 2 without piecewise leaves,
  /// so that its gradient is affine: F(c + d) = F(c) + grad F(c) . d + d^T H d / 2 exactly, and
  /// a gradient enclosed over c +- h has radius at least sum_l |H_jl| h_l along each axis j.
  bool gradientAffine() const { return gradientAffine_; }
  /// For a program whose gradient is affine, spread_j >= sum_l |H_jl| radius_l (rounded up):
  /// what the gradient's range over centre +- radius adds to the gradient at the centre, in
  /// O(nonzeros of H) instead of a run over the box. False (spread untouched) for other programs.
  bool gradientSpread(std::span<const S> radius, std::span<S> spread) const;
  /// quadraticCurvature of the program, computed on first use (then cached).
  const Curvature& curvature() const {
    if (!curvature_) curvature_ = quadraticCurvature(tape_);
    return *curvature_;
  }

 private:
  /// F = f_o + g_o . (x - o) + (x - o)^T H (x - o) / 2, each coefficient as midpoint and
  /// radius; H as its nonzero entries (j, l) in row order.
  struct QuadraticForm {
    std::vector<S> origin;                   // o (n)
    S f0m, f0r;                              // F(o)
    std::vector<S> g0m, g0r;                 // grad F(o) (n)
    std::vector<std::uint32_t> row, column;  // row <= column: each symmetric pair once
    std::vector<S> hm, hr, habs;             // per nonzero of H; habs >= |H_jl| (rounded up)
  };
  /// run() in the quadratic form.
  bool runForm(std::span<const S> centre, std::span<const S> radius, bool gradient) const;
  /// Widens the value's radius `fr` at the centre to the box of half-widths w, with (|H| w)_j
  /// rounded up left in `spread` (n); false, and nothing changed, when every w_j is 0. Needs
  /// G(c) from runForm.
  bool widen(S& fr, std::span<const S> w, S* spread, const S& up) const;
  /// spread += |H| w (habs; both rows of an entry off the diagonal).
  void addAbsH(const S* w, S* spread) const;
  /// The quadratic form about `origin` from passes over the program; false when one fails
  /// (then run() stays the pass).
  bool buildForm(std::span<const S> origin);
  /// Pushes a constant, variable or leaf into slot (m, r).
  void pushOperand(const TapeOp& op, S* m, S* r) const;
  /// The enclosures of leaf i and its partials, once per run.
  void leafEnclosure(std::size_t i, S* m, S* r) const;
  /// Applies a unary or binary instruction to the top slots x (and y above it); false when a
  /// divisor encloses 0.
  bool apply(const TapeOp& op, S* xm, S* xr, const S* ym, const S* yr) const;
  /// x^p and p x^(p-1) x' by binary powering.
  void power(int p, S* xm, S* xr) const;

  std::shared_ptr<const Tape> tape_;
  std::vector<S> constMid_, constRad_;  // per constant
  S u_, up_;  // unit of the arithmetic (>= 2 x unit round-off) and 1 + 8 u
  bool gradientAffine_ = false;
  std::optional<QuadraticForm> form_;  // gradientAffine_ programs
  // runForm's scratch: G(c)'s radii, |terms| per row, c - o and the radii widened by its rounding
  mutable std::vector<S> formG_, formMagnitude_, formD_, formR_;
  // runWithCentre's: the half-widths of d's rounding and their spread, the centre's value,
  // whether runForm records it, and the zero radii of a program's pass at the centre
  mutable std::vector<S> formP_, formSpread_, zero_;
  mutable S centreMid_, centreRad_;
  mutable bool recordCentre_ = false;
  mutable std::optional<Curvature> curvature_;
  // Per run: the stride (n + 1 or 1), the centre and radii, the stack ((n + 1) per slot) and
  // the enclosures of each distinct leaf ((n + 1) per leaf).
  mutable std::size_t stride_ = 1;
  mutable std::span<const S> centre_, radius_;
  mutable std::vector<S> stackMid_, stackRad_, leafMid_, leafRad_;
  mutable std::vector<unsigned char> leafDone_;
  mutable S tm_, tr_, sm_, sr_, fm_, fr_;  // temporaries of the products (no allocation per run)
};

extern template class MidRadEvaluator<double>;
extern template class MidRadEvaluator<Mpfr>;

}  // namespace ndc
