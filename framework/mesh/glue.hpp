/// \file glue.hpp
/// Gluing the meshes of a split solve (docs/split.md): the domain cut into boxes, each solved on
/// its own, and the pieces joined along the faces they share. A piece's mesh ends on its box's
/// faces (docs/crossing.md, "The domain's boundary"): for a curve in isolated points of M on the
/// face, for a surface in a polyline whose vertices lie on the curve M ∩ face. Two pieces that
/// share a face therefore end in the same points, or in two polylines along one curve that differ
/// only where one side was refined further; gluing identifies the points and merges the two
/// polylines into one before it identifies them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "framework/numeric/box.hpp"

namespace ndc {

/// One piece of a split solve: its box and its mesh.
struct MeshPiece {
  Box<double> box;                      ///< the piece's closed box (a sub-box of the domain)
  std::vector<double> vertices;         ///< n coordinates per vertex
  std::vector<std::int32_t> simplices;  ///< k + 1 vertex numbers per simplex
};

/// The glued mesh and how the shared faces matched.
struct GlueResult {
  std::vector<double> vertices;         ///< n coordinates per vertex
  std::vector<std::int32_t> simplices;  ///< k + 1 vertex numbers per simplex
  std::int64_t matched = 0;   ///< vertices identified with a vertex of a neighbouring piece
  std::int64_t inserted = 0;  ///< vertices inserted into a neighbour's boundary edge (k = 2)
  /// Boundary elements on a shared face left without a partner: open ends (k = 1) or edges in
  /// other than two triangles (k = 2). 0 when the pieces meet everywhere.
  std::int64_t unmatched = 0;
  std::string reason;  ///< why the pieces do not meet (empty when unmatched == 0)
};

/// Glues the meshes of pieces whose boxes tile a box (neighbours share whole faces). A vertex
/// lies on a shared face when its coordinate there is within `tolerance` of the face's plane;
/// two such vertices of neighbouring pieces are one when they agree within `tolerance` in every
/// coordinate. For k = 2 a boundary vertex of one side's polyline that the other side lacks is
/// inserted into the nearest boundary edge of the other side (its triangle is split in two,
/// orientation kept), so that both polylines have the same vertices; then every edge on a shared
/// face must lie in exactly two triangles and every vertex of a curve on one in exactly two
/// segments, or the result counts it in `unmatched`. Vertices that no simplex uses are dropped.
GlueResult gluePieces(int n, int k, const std::vector<MeshPiece>& pieces, double tolerance);

}  // namespace ndc
