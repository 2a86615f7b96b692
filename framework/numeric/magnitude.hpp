/// \file magnitude.hpp
/// The magnitude bound |F|(|x|) of a Tape, for running-error bounds on its evaluation.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "framework/numeric/scalar.hpp"
#include "framework/numeric/tape.hpp"

namespace ndc {

/// `|F|(|x|)`: the program with every constant and variable replaced by its absolute value,
/// every subtraction by an addition, negation dropped, each leaf by its largest absolute
/// coefficient and each division by the absolute value of its constant divisor. It bounds the
/// magnitude of every term the evaluation of `F(x)` combines (NewtonProjection's convergence
/// criterion), with `count()` = the operation count plus the total degree of the program.
template <class S>
class MagnitudeBound {
 public:
  /// Rounds the constants, leaf bounds and divisors to S once.
  explicit MagnitudeBound(std::shared_ptr<const Tape> tape);

  /// Operations that round (a leaf's de Casteljau steps included) plus the total degree.
  int count() const { return count_; }
  /// `|F|(|x|)` where `absX[j] = |x_j|`; `stack` is scratch.
  S operator()(std::span<const S> absX, std::vector<S>& stack) const;

 private:
  std::shared_ptr<const Tape> tape_;
  std::vector<S> operand_;  ///< per instruction: |constant|, leaf bound or |divisor|
  int count_ = 0;
  std::size_t depth_ = 0;  ///< the largest stack the program needs
};

extern template class MagnitudeBound<double>;
extern template class MagnitudeBound<Mpfr>;

}  // namespace ndc
