/// \file interval.hpp
/// Outward-rounded interval arithmetic: Boost.Interval on double, MPFI on Mpfr.
#pragma once

#include <span>
#include <string_view>

#include "framework/numeric/scalar.hpp"

namespace ndc {

/// A closed interval `[lower, upper]` of scalars `S`, with outward rounding, so every result
/// encloses the exact result of the operation on any points of the operands.
///
/// Models: `Interval<double>` (Boost.Interval with rounded arithmetic) and `Interval<Mpfr>`
/// (MPFI at the current Mpfr precision). Both are defined in interval.cpp; this header does not
/// pull in either library.
template <class S>
class Interval {
 public:
  Interval();                                ///< [0, 0]
  explicit Interval(const S& point);         ///< [p, p]
  Interval(const S& lower, const S& upper);  ///< requires lower <= upper
  /// The tightest enclosure of a decimal literal (e.g. "0.1" is not a double).
  static Interval fromString(std::string_view text);
  Interval(const Interval&);
  Interval(Interval&&) noexcept;
  Interval& operator=(const Interval&);
  Interval& operator=(Interval&&) noexcept;
  ~Interval();

  S lower() const;
  S upper() const;
  /// Rounded midpoint (inside the interval).
  S midpoint() const;
  /// Width rounded up.
  S width() const;
  bool contains(const S& v) const;
  /// Whether 0 may lie in the interval: true also when an end is NaN (an overflow such as
  /// inf - inf gives no information), so that no exclusion or regularity test concludes from it.
  bool containsZero() const;

  Interval& operator+=(const Interval& o);
  Interval& operator-=(const Interval& o);
  Interval& operator*=(const Interval& o);
  Interval operator-() const;
  /// Integer power `x^n`, n >= 0, with the even-power rule (`[-1,2]^2 = [0,4]`).
  Interval pow(int exponent) const;
  /// Division by a point scalar != 0.
  Interval dividedBy(const S& divisor) const;
  /// Smallest interval holding both.
  Interval hull(const Interval& o) const;

 private:
  struct Impl;
  alignas(16) unsigned char storage_[64];  // holds the backend value without a heap object
  Impl& impl();
  const Impl& impl() const;
};

template <class S>
Interval<S> operator+(Interval<S> a, const Interval<S>& b) {
  return a += b;
}
template <class S>
Interval<S> operator-(Interval<S> a, const Interval<S>& b) {
  return a -= b;
}
template <class S>
Interval<S> operator*(Interval<S> a, const Interval<S>& b) {
  return a *= b;
}

extern template class Interval<double>;
extern template class Interval<Mpfr>;

/// de Casteljau along every axis of a tensor-product Bernstein polynomial (double coefficients,
/// variable 0 fastest, `degrees` per axis) at the parameter intervals `t[0..p-1]`, in interval
/// arithmetic: the same operations, in the same order and with the same result bit for bit, as
/// with Interval<double>, but the rounding mode is switched once per call instead of three
/// times per operation (the switches were most of the time of a leaf's enclosure). Where an
/// overflow leaves a NaN end (inf - inf), the result is the whole line [-inf, inf].
Interval<double> tensorDeCasteljauEnclosure(std::span<const double> coefficients,
                                            std::span<const int> degrees,
                                            const Interval<double>* t);

/// `(a * [factor]).dividedBy(divisor)` with one rounding-mode switch: the same bounds bit for
/// bit (the whole line where they would be NaN). Throws std::domain_error when divisor is 0.
Interval<double> scaledQuotient(const Interval<double>& a, double factor, double divisor);

/// An upper bound on ||I - Y A||_inf in outward-rounded interval arithmetic (NaN when an entry
/// overflowed), for a point matrix Y (m x m, column-major as Eigen stores it, any m) and the
/// interval matrix A whose entry (l, j) is `matrix[l * stride + columns[j]]` (m columns of a
/// row-major matrix). Row i is sum_j |[delta_ij - sum_l Y_il A_lj]|: the same operations in the
/// same order, bit for bit, as Interval<double> arithmetic, with one rounding-mode switch per call.
/// A bound below 1 proves every real matrix in A regular (the graph certificate,
/// strategies/connection/crossing/certificate.hpp).
double identityResidualNorm(int m, std::span<const double> y,
                            std::span<const Interval<double>> matrix, std::size_t stride,
                            std::span<const int> columns);

/// The Krawczyk operator K(X) = y - Y F(y) + (I - Y J(X)) (X - y) of an m x m system, in
/// outward-rounded interval arithmetic with one rounding-mode switch per call (any m): `y` the
/// point (m), `inverse` Y (m x m, column-major as Eigen stores it), `fy` an enclosure of F(y) (m),
/// `jx` J(X) (m x m, row-major), X = [lo, hi]. Writes K's rows to kLower and kUpper (NaN ends where
/// an entry overflowed). The same operations in the same order as Interval<double> arithmetic, with
/// X - y enclosed outward as [lo - y, hi - y].
void krawczykOperator(int m, std::span<const double> y, std::span<const double> inverse,
                      std::span<const Interval<double>> fy, std::span<const Interval<double>> jx,
                      std::span<const double> lo, std::span<const double> hi,
                      std::span<double> kLower, std::span<double> kUpper);

}  // namespace ndc
