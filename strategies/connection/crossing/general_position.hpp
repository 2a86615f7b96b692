/// \file general_position.hpp
/// The level offset c of the crossing connection (docs/crossing.md, "General position"): the
/// crossings that make the mesh are those of M_c = {F = c}, not of M. Internal to the crossing
/// connection.
#pragma once

#include <cstdint>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/connection/crossing/face_solver.hpp"

namespace ndc::crossing_detail {

/// The level c of the perturbed system F = c whose crossings with the grid faces decide the
/// dual cells (docs/crossing.md, "General position"). M itself may pass through vertices,
/// edges and faces of the grid; by Sard's theorem almost every nearby level set meets every
/// face of the grid transversally and misses its lower-dimensional faces. c_i is a fixed
/// irrational fraction of `kRelative` times the cell width times the gradient scale of F_i,
/// so F = c lies about 1e-8 cell widths from M: far above rounding, far below any feature
/// the grid resolves. The grid, the domain and the B-spline knot planes stay where they are.
template <class S>
struct GeneralPosition {
  static constexpr int kAttempts = 4;
  static constexpr double kRelative = 1.0 / (1 << 26);

  /// The scales of the levels for `in` on `grid`.
  GeneralPosition(const ConnectionInput<S>& in, const Grid& grid);

  /// The level of attempt a: c_i = theta_{a,i} * scale_i with theta in [0.5, 1) from the
  /// golden-ratio sequence (no two attempts or equations share a ratio).
  std::vector<S> level(int attempt) const;

  /// How many of a face's roots lie within the tolerance of one of its grid (not domain)
  /// boundaries: there the face and its neighbour could disagree about the root.
  std::int64_t nearBoundary(const std::vector<std::vector<S>>& roots, const Box<S>& box,
                            const std::vector<int>& freeAxes, const FaceEnds& ends) const;

  std::vector<S> scale;  ///< kRelative * cell width * gradient scale, per equation
  S slack;               ///< crossings kept this far outside the domain
  S tolerance;           ///< a root this close to a face boundary is degenerate
};

extern template struct GeneralPosition<double>;
extern template struct GeneralPosition<Mpfr>;

}  // namespace ndc::crossing_detail
