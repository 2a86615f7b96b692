/// \file application.hpp
/// What an application problem (paper Sec. 3) adds to a plain problem: the map of a point of
/// M to R^3, the input geometry, and the parameter map of B-spline variables.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "framework/problem/expression.hpp"

namespace ndc {

/// Triangles of the input surfaces (and of a moving body's instances), for `input.ply`.
struct TriangleSoup {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> part;  ///< per triangle: which input surface (or instance) it belongs to
};

/// A rational map R^n -> R^3, `x -> numerator(x) / denominator(x)`, built in Bernstein
/// arithmetic from the input surfaces and motion.
struct RationalMap {
  std::array<Expression, 3> numerator;
  Expression denominator;  ///< the constant 1 for a polynomial map
  /// The image of x in double, and whether the denominator is too close to 0 to trust it
  /// (|den| <= 1e-12 max(1, |num|)); then the point is NaN.
  std::array<double, 3> operator()(std::span<const double> x, bool* singular = nullptr) const;
};

/// The application part of a problem.
struct ApplicationData {
  std::string name;   ///< convex-hull, sweep-silhouette, bisector, sweep-envelope, blending
  RationalMap image;  ///< mesh.ply x y z (docs/contracts.md 4.4: "the application's map to R^3")
  /// convex-hull: the other end of each bitangent segment (S(s, t)), written as x2 y2 z2 and
  /// used for ruled.ply.
  std::optional<RationalMap> secondImage;
  /// What a vanishing image denominator means, for the summary (e.g. "bisector determinant").
  std::string singularName;
  TriangleSoup input;  ///< input.ply
  /// Per variable: the distinct knots of a B-spline direction solved in span coordinates (span
  /// i is the interval [i, i + 1]); empty when the variable is the parameter itself.
  std::vector<std::vector<double>> knots;
  /// The parameter value of variable j at span coordinate x (identity without knots).
  double parameter(int j, double x) const;
};

}  // namespace ndc
