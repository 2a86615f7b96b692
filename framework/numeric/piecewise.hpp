/// \file piecewise.hpp
/// Piecewise tensor-product Bernstein polynomials: the leaves of application expressions (a
/// coordinate of a Bézier or B-spline surface after Bézier extraction, or of a motion).
#pragma once
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/scalar.hpp"

namespace ndc {

/// A piecewise polynomial in `p` of a problem's variables: local axis `a` is problem variable
/// `axes[a]`, cut by the increasing `breaks[a]` into pieces; each piece is a Bernstein
/// polynomial (double coefficients, the input data) on its box of breaks. A B-spline after Bézier
/// extraction has one piece per knot span; a Bézier patch has one piece.
///
/// Outside the outermost breaks the first or last piece is extrapolated.
struct PiecewiseBernstein {
  std::string name;                         ///< for messages and expression text
  std::vector<int> axes;                    ///< problem variable of each local axis
  std::vector<std::vector<double>> breaks;  ///< per local axis, at least two increasing values
  std::vector<Bernstein<double>> pieces;    ///< one per piece box, local axis 0 fastest

  /// Number of local axes p.
  int dim() const { return static_cast<int>(axes.size()); }
  /// Number of pieces along local axis a.
  int pieceCount(int a) const { return static_cast<int>(breaks[a].size()) - 1; }
  /// Largest degree of any piece along local axis a.
  int degree(int a) const;
  /// Largest absolute coefficient of any piece (the value's magnitude is at most this on the
  /// breaks' box, by the convex hull property).
  double maxAbsCoefficient() const;
  /// Checks the invariants (sizes, increasing breaks, each piece on its box); throws
  /// std::invalid_argument.
  void validate() const;

  /// Value at a local point (`local[a]` is the value of variable `axes[a]`).
  template <class S>
  S evaluate(std::span<const S> local) const;
  /// Enclosure of the range over a box of local intervals (outward rounded: the hull of interval
  /// de Casteljau evaluations on every piece the box meets).
  template <class S>
  Interval<S> enclose(std::span<const Interval<S>> local) const;
  /// The exact Bernstein form on a local box lying in one piece (up to a relative 1e-9 of the
  /// piece width); throws std::domain_error when the box straddles a break.
  template <class S>
  Bernstein<S> onBox(const Box<S>& local) const;

  /// The partial derivative along local axis a (each piece differentiated; the coefficients
  /// are rounded to double once).
  PiecewiseBernstein derivative(int a) const;
};

extern template double PiecewiseBernstein::evaluate<double>(std::span<const double>) const;
extern template Mpfr PiecewiseBernstein::evaluate<Mpfr>(std::span<const Mpfr>) const;
extern template Interval<double> PiecewiseBernstein::enclose<double>(
    std::span<const Interval<double>>) const;
extern template Interval<Mpfr> PiecewiseBernstein::enclose<Mpfr>(
    std::span<const Interval<Mpfr>>) const;
extern template Bernstein<double> PiecewiseBernstein::onBox<double>(const Box<double>&) const;
extern template Bernstein<Mpfr> PiecewiseBernstein::onBox<Mpfr>(const Box<Mpfr>&) const;

}  // namespace ndc
