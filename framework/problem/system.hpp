/// \file system.hpp
/// The constraint system F = (F_1..F_m) of a problem, evaluated with its Jacobian.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "framework/numeric/scalar.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/problem.hpp"

namespace ndc {

/// The m constraints in n variables of a problem, in scalar S, evaluated directly from their
/// compiled programs (Tape) (not from the Bernstein form, so Newton sees the exact polynomials).
/// A program of total degree at most 2 without leaves is evaluated in its quadratic form about
/// the domain's centre o, F(x) = f + g . d + d^T H d / 2 with d = x - o (f, g and H taken from
/// the program at o and o + e_l once): O(n + nonzeros of H) per value and gradient instead of a
/// pass over the program with n + 1 components per operation; the same values up to rounding.
template <class S>
class System {
 public:
  explicit System(const Problem& problem);
  int n() const { return n_; }
  int m() const { return static_cast<int>(equations_.size()); }
  /// F(x) into `f` (m values).
  void evaluate(std::span<const S> x, std::span<S> f) const;
  /// F(x) into `f` and the Jacobian into `jacobian` (m x n, row-major).
  void evaluate(std::span<const S> x, std::span<S> f, std::span<S> jacobian) const;
  /// max_i |F_i(x)|.
  S maxResidual(std::span<const S> x) const;
  /// Whether equation i is evaluated in its quadratic form.
  bool quadraticForm(int i) const { return !forms_[std::size_t(i)].g.empty(); }
  /// For an equation in its quadratic form: (|H| h)_j into `spread` (n values), which bounds how
  /// far dF_i/dx_j moves over a box of half-widths h; false (and nothing written) otherwise.
  bool hessianSpread(int i, std::span<const S> h, std::span<S> spread) const;
  /// For an equation in its quadratic form: the Frobenius norm of its Hessian H, a Lipschitz
  /// constant of its gradient everywhere (0 for an affine equation); -1 otherwise.
  S hessianNorm(int i) const;
  const std::vector<Expression>& equations() const { return equations_; }
  /// The centre of the problem's domain: the origin of the quadratic forms of its
  /// midpoint-radius evaluators (MidRadEvaluator).
  const std::vector<S>& origin() const { return origin_; }

 private:
  /// A quadratic form (no g: the equation is not a quadratic).
  struct Form {
    S f;
    std::vector<S> g;                        ///< n
    std::vector<std::uint32_t> row, column;  ///< H's nonzeros in row order
    std::vector<S> h;
  };
  /// F_i(x), and its gradient into `gradient` (n values) unless empty, in the quadratic form.
  S evaluateForm(const Form& form, std::span<const S> x, std::span<S> gradient) const;

  int n_ = 0;
  std::vector<Expression> equations_;
  std::vector<S> origin_;
  std::vector<Form> forms_;  ///< per equation
};

extern template class System<double>;
extern template class System<Mpfr>;

}  // namespace ndc
