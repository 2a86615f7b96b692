/// \file dual_complex.hpp
/// The mesh of the crossing connection: the dual complex of the final tree's crossed minimal
/// m-faces (docs/crossing.md, steps 3 and 4), with the domain's boundary as part of it
/// (docs/crossing.md, "The domain's boundary"): a region beyond the domain around a crossed
/// face becomes a vertex on the domain's face, so the mesh's boundary lies on the boundary of
/// the domain and a piece of M that crosses no interior face of the grid is still meshed.
/// Internal to the crossing connection.
#pragma once

#include <cstdint>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/connection/crossing/cell_tree.hpp"
#include "strategies/connection/crossing/dual_polygon.hpp"

namespace ndc::crossing_detail {

/// What the dual complex is made of: the final tree, its polygons (blocks already merged) and
/// their crossings.
template <class S>
struct DualInput {
  const ConnectionInput<S>& in;
  const CellTree& tree;
  const Box<S>& domain;
  const std::vector<Polygon>& polygons;
  const std::vector<S>& roots;                ///< n coordinates per crossing (Polygon::root)
  const std::vector<std::uint8_t>& singular;  ///< per leaf: next to a singular face
  S slack;  ///< how far beyond the domain crossings are kept (docs/crossing.md, "Domain boundary")
};

/// Appends the dual complex to `out.complex` and counts its ambiguous and singular cells and
/// its vertices off M into `out`. (A vertex whose simplices all collapsed is dropped when the
/// mesh is welded, ndc::dropUnusedVertices.)
template <class S>
void buildDualComplex(const DualInput<S>& input, ConnectionOutput<S>& out);

extern template void buildDualComplex(const DualInput<double>&, ConnectionOutput<double>&);
extern template void buildDualComplex(const DualInput<Mpfr>&, ConnectionOutput<Mpfr>&);

}  // namespace ndc::crossing_detail
