/// \file analysis.hpp
/// The analysis stage: welding, topology and accuracy of a complex (summary.json `mesh` and
/// `accuracy`).
#pragma once

#include "framework/mesh/complex.hpp"
#include "framework/problem/summary.hpp"
#include "framework/problem/system.hpp"

namespace ndc {

/// Merges vertices that coincide (to a tolerance relative to the domain size, so two cells
/// that project to the same point of M give one vertex), drops degenerate simplices (repeated
/// vertices) and duplicate simplices. Returns the welded complex.
template <class S>
Complex<S> weld(const Complex<S>& complex, double tolerance);

/// Every `mesh` and `accuracy` field of docs/contracts.md 4.3 for a welded complex: vertices,
/// edges, triangles, components, boundary and non-manifold edges, Euler characteristic, open ends,
/// branch vertices, max residual over vertices, max chord error (midpoints or centroids
/// projected with `project`), Betti numbers over Q and Z/2 and the facets of one and of three or
/// more k-simplices (framework/mesh/homology.hpp; docs/contracts.md 4.5).
template <class S>
MeshStats analyse(const Complex<S>& welded, const System<S>& system, const Projector<S>& project);

/// Removes the vertices that no simplex uses, renumbering the rest in order: a mesh is written
/// with no isolated vertex, which would count as a component (a simplex that welding made
/// degenerate, as where M passes through a corner of the domain, leaves its vertex behind).
template <class S>
void dropUnusedVertices(Complex<S>& complex);

extern template Complex<double> weld(const Complex<double>&, double);
extern template Complex<Mpfr> weld(const Complex<Mpfr>&, double);
extern template void dropUnusedVertices(Complex<double>&);
extern template void dropUnusedVertices(Complex<Mpfr>&);
extern template MeshStats analyse(const Complex<double>&, const System<double>&,
                                  const Projector<double>&);
extern template MeshStats analyse(const Complex<Mpfr>&, const System<Mpfr>&,
                                  const Projector<Mpfr>&);

}  // namespace ndc
