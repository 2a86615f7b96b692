/// \file newton.hpp
/// The `newton` projection model (docs/projection.md): the paper's Newton-Raphson projection of a
/// cell's point onto the solution manifold M (Sec. 4, Algorithm 1: "apply the Newton-Raphson method
/// to project the solution point in c into the solution manifold").
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/magnitude.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/system.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc {

/// Minimum-norm Newton-Raphson onto M = {F = 0}:
/// `x <- x - J^+ F(x)`, where `J^+ = J^T (J J^T)^{-1}` is the pseudo-inverse of the m x n
/// Jacobian (full row rank). The step is computed from a Householder QR of J^T with pivoting
/// (ndc::MinimumNormSolver: rank revealing, and it never forms J J^T, so the conditioning is
/// not squared). A rank-deficient J at an iterate whose residual has not yet converged ends the
/// iteration as not converged.
///
/// **Convergence criterion** (backward error at the working precision). For each equation
/// `F_i`, let `|F_i|(|x|)` be its program evaluated with every constant and variable
/// replaced by its absolute value and every subtraction by an addition: it bounds the sum of
/// the magnitudes of all the terms the evaluation of `F_i(x)` combines. A standard
/// running-error argument gives `|fl(F_i(x)) - F_i(x)| <= ops_i * eps * |F_i|(|x|)` to first
/// order, and rounding x itself to the working precision moves `F_i` by at most
/// `deg_i * eps * |F_i|(|x|)` (Euler's identity for polynomials with non-negative
/// coefficients), where `ops_i` is the operation count of the program and `deg_i` its total
/// degree. So no iterate can be told apart from a zero once
///
///     |F_i(x)| <= tol_i(x) + 2 eps |x|_inf |grad F_i(x)|_1,
///     tol_i(x) = 2 (ops_i + deg_i) eps |F_i|(|x|)   for every i,
///
/// with `eps = ScalarTraits<S>::epsilon()`. The second term is the normwise backward error
/// (x moved by eps |x|_inf in every coordinate): without it a coordinate that is 0 at the
/// root (M in a coordinate plane, e.g. a constraint `x3`) has no rounding of its own and the
/// iterate, stuck at 1e-30 instead of 0, would never converge. That is the test, applied before
/// each step (so a point already on M stays put with 0 iterations). For O(1) coefficients and |x| =
/// O(1) this is ~1e-14 in double and ~1e-36 in MPFR at 128 bits. Newton also stops when a step is
/// below `16 eps (1 + |x|_inf)` (stagnation at the rounding floor); it then counts as converged iff
/// every `|F_i| <= 64 tol_i` (a tolerance for the first-order bound above being optimistic).
///
/// **Divergence**: a non-finite F or iterate, or `|x|_inf > 1e4 (1 + |x_0|_inf)`, stops the
/// iteration at once as not converged. After `maxIterations` steps without convergence the
/// point is reported as not converged (e.g. a Newton cycle, or no real zero nearby).
template <class S>
class NewtonProjection final {
 public:
  /// The system must outlive the projection (it is held by pointer so the object is cheap to
  /// copy into a Projector).
  explicit NewtonProjection(const System<S>& system, int maxIterations = 40);

  /// The model's name, sentence and parameters (its registry entry, strategies/projection/
  /// projection.cpp).
  static ModelSpec spec();

  /// Projects `x` onto M in place (Alg. 1, projection step). `converged` says whether the
  /// final x satisfies the criterion above; `iterations` is the number of Newton steps taken.
  ProjectedPoint<S> project(std::span<S> x) const;

  /// `tol_i(x)` of the convergence criterion for every equation (m values into `tol`).
  void residualTolerance(std::span<const S> x, std::span<S> tol) const;

  const System<S>& system() const { return *system_; }
  int maxIterations() const { return maxIterations_; }

 private:
  /// tol_i(x) of equation i; `fresh`: x differs from the last call's in this thread.
  S toleranceOf(int i, std::span<const S> x, bool fresh) const;

  const System<S>* system_;
  int maxIterations_;
  std::vector<MagnitudeBound<S>> magnitudes_;  ///< |F_i|(|x|) per equation
};

extern template class NewtonProjection<double>;
extern template class NewtonProjection<Mpfr>;
static_assert(ProjectionStrategy<NewtonProjection<double>, double>);
static_assert(ProjectionStrategy<NewtonProjection<Mpfr>, Mpfr>);

}  // namespace ndc
