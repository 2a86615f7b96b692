/// \file bernstein.hpp
/// The core type of ndcontour: a tensor-product multivariate Bernstein polynomial on a box.
#pragma once

#include <span>
#include <utility>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/numeric/scalar.hpp"

namespace ndc {

/// A tensor-product Bernstein polynomial in n variables on a box D (paper, Sec. 4:
/// the constraints `F_i` are "represented as B-spline functions" and subdivided).
///
/// With degrees `d_0..d_{n-1}` it is
/// `sum_I b_I prod_j B^{d_j}_{i_j}(t_j)`, `t_j = (x_j - lo_j) / (hi_j - lo_j)`,
/// where `B^d_i(t) = C(d,i) t^i (1-t)^{d-i}`. Coefficients are stored with variable 0
/// fastest: the linear index of `I` is `sum_j i_j * stride(j)`, `stride(0) = 1`,
/// `stride(j+1) = stride(j) * (d_j + 1)`. A polynomial in zero variables is a constant.
///
/// Operations that combine two polynomials require the same box (and the same number of
/// variables); they elevate degrees as needed. All operations are exact up to the rounding
/// of `S`; none changes the polynomial except where stated.
template <class S>
class Bernstein {
 public:
  /// The zero polynomial in zero variables.
  Bernstein() : coefficients_(1, S(0)) {}
  /// The polynomial with given degrees on `domain`, all coefficients zero.
  Bernstein(Box<S> domain, std::vector<int> degrees);

  /// The constant `value` on `domain` (all degrees 0).
  static Bernstein constant(const Box<S>& domain, const S& value);
  /// The coordinate function `x_axis` on `domain` (degree 1 in `axis`, 0 elsewhere).
  static Bernstein variable(const Box<S>& domain, int axis);

  /// Number of variables n.
  int dim() const { return static_cast<int>(degrees_.size()); }
  /// Degree in variable j.
  int degree(int j) const { return degrees_[j]; }
  const std::vector<int>& degrees() const { return degrees_; }
  const Box<S>& domain() const { return domain_; }
  /// Linear-index stride of variable j.
  std::size_t stride(int j) const;
  /// Number of coefficients `prod_j (d_j + 1)`.
  std::size_t size() const { return coefficients_.size(); }
  std::span<const S> coefficients() const { return coefficients_; }
  std::span<S> coefficients() { return coefficients_; }
  /// Coefficient at a multi-index.
  const S& coefficient(std::span<const int> index) const;
  S& coefficient(std::span<const int> index);

  /// Value at a point `x` of the domain (in domain coordinates), by de Casteljau per axis.
  /// Points outside the domain are evaluated by extrapolation. Works in a per-thread scratch
  /// buffer, so it is thread-safe and does not allocate once warm (except the returned value).
  S evaluate(std::span<const S> x) const;

  /// Partial derivative with respect to `x_axis` (degree drops by one; a degree-0 variable
  /// gives the zero polynomial of degree 0 in that variable).
  Bernstein derivative(int axis) const;

  /// de Casteljau split along `axis` at the local parameter `t` in (0, 1): `left` gets the
  /// part on `[lo, lo + t (hi - lo)]`, `right` the rest. `left` and `right` are overwritten
  /// and keep their storage when it is large enough (no allocation in the subdivision loop).
  /// `left` and `right` must be distinct; either may be `*this` (then a copy is split).
  /// Throws std::invalid_argument for a bad axis or t outside (0, 1).
  void split(int axis, const S& t, Bernstein& left, Bernstein& right) const;

  /// Halves along `axis` into `left` and `right` (split at t = 1/2); allocation-free when
  /// the outputs already have the right size.
  void halve(int axis, Bernstein& left, Bernstein& right) const;

  /// The same polynomial represented on a sub-box of the domain (by blossoming: two splits
  /// per axis). The sub-box may also extend outside the domain (extrapolation).
  Bernstein restrict(const Box<S>& sub) const;
  /// restrict into `out`: allocation-free when `out` already has this form's size.
  void restrictInto(const Box<S>& sub, Bernstein& out) const;

  /// Face slice: the polynomial in the n - 1 remaining variables obtained by fixing `axis`
  /// at its lower (`upper == false`) or upper end. Its coefficients are the boundary
  /// coefficients of this one.
  Bernstein faceSlice(int axis, bool upper) const;
  /// faceSlice into `out` (not `*this`): allocation-free when `out` already has the slice's
  /// size.
  void faceSliceInto(int axis, bool upper, Bernstein& out) const;

  /// Degree elevation to `degrees` (each at least the current degree).
  Bernstein elevate(std::span<const int> degrees) const;

  /// Embedding into more variables: variable j of this polynomial becomes variable
  /// `positions[j]` of the result, whose domain is `domain` (it must agree with this domain on
  /// the mapped axes). The polynomial is constant in the new variables.
  Bernstein embed(const Box<S>& domain, std::span<const int> positions) const;

  Bernstein& operator+=(const Bernstein& other);
  Bernstein& operator-=(const Bernstein& other);
  Bernstein& operator*=(const S& scale);
  Bernstein operator-() const;

  /// Smallest and largest coefficient: an enclosure of the range on the domain (convex hull
  /// property).
  std::pair<S, S> coefficientRange() const;
  /// Whether every coefficient is > 0 or every coefficient is < 0 (then no zero in the box).
  bool excludesZero() const;

 private:
  Box<S> domain_;
  std::vector<int> degrees_;
  std::vector<S> coefficients_;
};

template <class S>
Bernstein<S> operator+(Bernstein<S> a, const Bernstein<S>& b) {
  return a += b;
}
template <class S>
Bernstein<S> operator-(Bernstein<S> a, const Bernstein<S>& b) {
  return a -= b;
}
template <class S>
Bernstein<S> operator*(Bernstein<S> a, const S& s) {
  return a *= s;
}
template <class S>
Bernstein<S> operator*(const S& s, Bernstein<S> a) {
  return a *= s;
}
/// Product: degrees add.
template <class S>
Bernstein<S> operator*(const Bernstein<S>& a, const Bernstein<S>& b);
/// Integer power by repeated multiplication.
template <class S>
Bernstein<S> pow(const Bernstein<S>& a, int exponent);

extern template class Bernstein<double>;
extern template class Bernstein<Mpfr>;
extern template Bernstein<double> operator*(const Bernstein<double>&, const Bernstein<double>&);
extern template Bernstein<Mpfr> operator*(const Bernstein<Mpfr>&, const Bernstein<Mpfr>&);
extern template Bernstein<double> pow(const Bernstein<double>&, int);
extern template Bernstein<Mpfr> pow(const Bernstein<Mpfr>&, int);

}  // namespace ndc
