/// \file system.hpp
/// The constraint system F = (F_1..F_m) of a problem, evaluated with its Jacobian.
#pragma once

#include <span>
#include <vector>

#include "framework/core/expression.hpp"
#include "framework/core/problem.hpp"
#include "framework/core/scalar.hpp"

namespace ndc {

/// The m constraints in n variables of a problem, in scalar S, evaluated directly from their
/// compiled programs (Tape) (not from the Bernstein form, so Newton sees the exact polynomials).
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
  const std::vector<Expression>& equations() const { return equations_; }
  /// The centre of the problem's domain: the origin of the quadratic forms of its
  /// midpoint-radius evaluators (MidRadEvaluator).
  const std::vector<S>& origin() const { return origin_; }

 private:
  int n_ = 0;
  std::vector<Expression> equations_;
  std::vector<S> origin_;
};

extern template class System<double>;
extern template class System<Mpfr>;

}  // namespace ndc
