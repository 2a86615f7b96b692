/// \file complex.hpp
/// Per-cell results of the projection and classification stages, and the simplicial complex
/// the connection stage builds.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace ndc {

/// The paper's classification of a solution cell (Sec. 4.1): normal if Newton converged to a
/// point inside the closed cell, abnormal if it converged outside, failed if it did not
/// converge.
enum class CellClass : std::uint8_t { kNormal = 0, kAbnormal = 1, kFailed = 2 };

/// Name of a class as written in cells.csv ("normal", "abnormal", "failed").
const char* className(CellClass c);

/// Result of projecting one point onto M.
template <class S>
struct ProjectedPoint {
  bool converged = false;
  int iterations = 0;
};

/// Projection of a point onto M (in place), as the later stages call it (a model of
/// ndc::ProjectionStrategy, framework/strategy/strategy.hpp, wrapped).
template <class S>
using Projector = std::function<ProjectedPoint<S>(std::span<S> x)>;

/// The projection stage's output: one point per solution cell (n scalars per cell).
template <class S>
struct Projections {
  int n = 0;
  std::vector<S> point;                 ///< n per cell
  std::vector<std::uint8_t> converged;  ///< 1 if Newton converged
  std::vector<std::int32_t> iterations;
  std::span<const S> at(std::size_t c) const {
    return {point.data() + c * n, static_cast<std::size_t>(n)};
  }
};

/// A simplicial complex in R^n: vertices and k-simplices (segments for k = 1, triangles for
/// k = 2), as produced by a connection strategy before welding.
template <class S>
struct Complex {
  int n = 0;                             ///< ambient dimension
  int k = 0;                             ///< simplex dimension
  std::vector<S> vertices;               ///< n scalars per vertex
  std::vector<std::int32_t> simplices;   ///< k + 1 vertex numbers per simplex
  std::vector<std::int32_t> vertexCell;  ///< the solution cell a vertex came from, or -1

  std::size_t vertexCount() const { return n ? vertices.size() / n : 0; }
  std::size_t simplexCount() const { return simplices.size() / (k + 1); }
  std::span<const S> vertex(std::size_t v) const {
    return {vertices.data() + v * n, static_cast<std::size_t>(n)};
  }
  /// Appends a vertex and returns its number.
  std::int32_t addVertex(std::span<const S> x, std::int32_t cell = -1);
  /// Appends a simplex given its k + 1 vertex numbers.
  void addSimplex(std::span<const std::int32_t> v);
};

}  // namespace ndc
