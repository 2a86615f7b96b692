/// \file orientation.hpp
/// Consistent orientation of the output mesh (`mesh.orientable` in summary.json).
#pragma once

#include <cstdint>
#include <vector>

namespace ndc {

/// Orients the simplices of a welded k-complex (k = 1: segments, k = 2: triangles; k + 1 vertex
/// numbers each) consistently within each connected component: two simplices that share a facet
/// (an edge of two triangles, a vertex of two segments) and no other simplex induce opposite
/// orientations on it. Each component keeps the orientation of its lowest-numbered simplex; the
/// others are flipped where needed (the last two vertices swapped), in a deterministic
/// breadth-first order. Facets shared by three or more simplices (non-manifold) do not propagate.
/// Returns false when some component cannot be oriented (a Möbius band or Klein bottle): its
/// simplices are then left as the search oriented them, consistent along a spanning tree.
/// The vertex numbers are those of a mesh (0 to its vertex count - 1): the facets are sorted by
/// counting over them.
bool orientSimplices(int k, std::vector<std::int32_t>& simplices);

}  // namespace ndc
