/// \file certificate.hpp
/// The cell test of the topology certificate (docs/certificate.md): over a whole box, either M
/// does not meet the box, or M ∩ box is the graph of a function of the remaining coordinates.
/// Every enclosure here is rigorous: Bernstein coefficient hulls widened by the rounding margin
/// of the coefficients, and outward-rounded interval arithmetic.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/problem/system.hpp"

namespace ndc {

/// An enclosure of the partial derivative of `p` along variable `axis` over p's box: the hull of
/// the derivative's Bernstein coefficients `d / w (b_{i+1} - b_i)`, widened so that it holds for
/// the exact polynomial when every coefficient of `p` is within `margin` of the exact one.
template <class S>
Interval<S> derivativeHull(const Bernstein<S>& p, int axis, const S& margin);

/// Whether the coefficients of `p` prove that p has no value between `a` and `b` (a <= b) on
/// its box: all above b + margin, or all below a - margin.
template <class S>
bool clearsRange(const Bernstein<S>& p, const S& a, const S& b, const S& margin);

/// The graph test (Elber and Kim's normal-cone test in its interval form). Given an enclosure J
/// of the m x n Jacobian of F over a box, if the m columns B of J form an interval matrix whose
/// every member is regular, then F(x_B, x_K) = c has at most one solution x_B in the box for
/// every x_K (mean value theorem: F(y) - F(x) = A (y - x) with A in the hull), so M_c ∩ box is
/// the graph of a function of the other coordinates x_K, for every level c at once. Regularity
/// is proven by the preconditioned test ||I - Y A||_inf < 1 in interval arithmetic, Y the
/// inverse of the midpoint matrix.
template <class S>
class GraphTest {
 public:
  GraphTest(int n, int m) : n_(n), m_(m) {}

  /// Whether M_c ∩ box is proven a graph over the columns `axes` of `jacobian` (m x n,
  /// row-major): some m of them form a regular block, or [J; T^T] is regular over the
  /// midpoint tangent space T (tangentGraph). Tries the pivot columns of the midpoint matrix
  /// first, then the tangent space, then every other block (at most C(a, a - m) with
  /// a - m <= 2).
  bool graph(std::span<const Interval<S>> jacobian, std::span<const int> axes);

  /// The face graph test of every facet at once on one enclosure J of the Jacobian (m x n,
  /// row-major) over a whole leaf, which encloses J on each facet: bit a of the result is set
  /// when the columns other than a hold a block that is regular for every member of J (so
  /// M_c ∩ facet is a graph on both facets fixing axis a), for the axes in `wanted` (n <= 64).
  /// One block B of pivot columns of the midpoint, Y the inverse of its midpoint and Z = Y J
  /// (midpoint-radius, every rounding bounded) serve all axes: B, proven regular by
  /// ||I - Z_B||_inf < 1, for each axis outside B; for an axis a in B, B with a's column
  /// swapped for a column u outside B, proven regular by ||I - E Z_B'||_inf < 1 where E inverts
  /// the eta matrix that mid Z_B' nearly is (O(m^2) per axis instead of a factorization and an
  /// O(m^3) residual). Proves less than graph() can (its other blocks and the tangent space):
  /// the caller tests the axes left with graph().
  std::uint64_t facetGraphs(std::span<const Interval<S>> jacobian, std::uint64_t wanted);

 private:
  bool regular(std::span<const Interval<S>> jacobian, std::span<const int> columns) const;
  /// The graph test over a linear map instead of coordinates: with T (a x (a - m)) an
  /// orthonormal basis of the midpoint Jacobian's null space over `axes`, whether the square
  /// interval matrix [J; T^T] is regular. Then (F, T^T x) is injective on the box (mean value
  /// theorem, as for a block), so M_c ∩ box is the graph of a function of T^T x; a block of
  /// coordinates is the case T = the dropped unit vectors.
  bool tangentGraph(std::span<const Interval<S>> jacobian, std::span<const int> axes) const;
  /// Whether the m x m interval matrix with entry (i, t) at matrix[i * stride + columns[t]] is
  /// regular: ||I - Y A||_inf < 1 with Y the inverse of its midpoint.
  static bool regularSquare(int m, std::span<const Interval<S>> matrix, std::size_t stride,
                            std::span<const int> columns);

  int n_, m_;
};

/// Whether one combination g = lambda . (F - c) of the equations is proven nonzero on `box`, so
/// that the level set F = c does not meet it. Where M is nearly tangent to the box (a face
/// near a critical point of a coordinate on M), every single equation vanishes somewhere on
/// the box although their common zeros miss it; lambda, the left singular vector of the
/// smallest singular value of the midpoint Jacobian over `axes`, cancels the first-order change
/// of F along the box, and the mean value form g(box) in g(x0) + sum_j [dg/dx_j](box) (x_j - x0_j)
/// then decides with an error of second order. `jacobian` (m x n, row-major) encloses the
/// Jacobian of F over the box in the columns `axes` (the box's other axes are points). Every
/// step is outward rounded; lambda itself needs no accuracy.
template <class S>
bool combinationExcludes(const System<S>& system, std::span<const S> level, const Box<S>& box,
                         std::span<const Interval<S>> jacobian, std::span<const int> axes);

extern template Interval<double> derivativeHull(const Bernstein<double>&, int, const double&);
extern template Interval<Mpfr> derivativeHull(const Bernstein<Mpfr>&, int, const Mpfr&);
extern template bool clearsRange(const Bernstein<double>&, const double&, const double&,
                                 const double&);
extern template bool clearsRange(const Bernstein<Mpfr>&, const Mpfr&, const Mpfr&, const Mpfr&);
extern template bool combinationExcludes(const System<double>&, std::span<const double>,
                                         const Box<double>&, std::span<const Interval<double>>,
                                         std::span<const int>);
extern template bool combinationExcludes(const System<Mpfr>&, std::span<const Mpfr>,
                                         const Box<Mpfr>&, std::span<const Interval<Mpfr>>,
                                         std::span<const int>);
extern template class GraphTest<double>;
extern template class GraphTest<Mpfr>;

}  // namespace ndc
