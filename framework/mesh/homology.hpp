/// \file homology.hpp
/// Betti numbers and facet counts of a pure simplicial complex (summary.json `mesh.betti`,
/// `mesh.betti_z2`, `mesh.boundary_facets`, `mesh.nonmanifold_facets`; docs/contracts.md 4.5).
///
/// The complex is given by its vertices and its k-simplices (a welded ndc::Complex); every
/// lower face is generated from the k-simplices, and a vertex that no simplex uses is a
/// component of its own, as in `mesh.components`.
///
/// Coefficients: `bettiZ2` is over Z/2. `betti` is over Q, computed with ranks modulo the prime
/// p = 2^31 - 1 (kHomologyPrime): the rank of an integer matrix modulo p equals its rank over Q
/// unless p divides one of its elementary divisors, so `betti` is the rational Betti vector
/// unless the integral homology has p-torsion (a complex of fewer than about 2^31 simplices
/// per dimension with such torsion is not met in practice, but it is not excluded).
///
/// Method: the complex is first shrunk by elementary reductions (a free face with its only
/// coface) and coreductions (a cell with a single face, with that face), both of which keep the
/// homology over any coefficients (Mrozek and Batko, "Coreduction homology algorithm", 2009);
/// the cells left are reduced as sparse boundary matrices by column reduction with a pivot
/// table and clearing (the twist of persistent homology codes). Near-linear on meshes of
/// manifolds: a million tetrahedra in a few seconds.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "framework/mesh/complex.hpp"

namespace ndc {

/// The prime p = 2^31 - 1 of the rational Betti numbers (ranks over Z/p stand for ranks over Q).
inline constexpr std::uint32_t kHomologyPrime = 2147483647u;

/// The homology and facet counts of a pure k-complex.
struct Homology {
  /// b_0 .. b_k over Q (ranks modulo kHomologyPrime; see the file comment).
  std::vector<std::int64_t> betti;
  /// b_0 .. b_k over Z/2.
  std::vector<std::int64_t> bettiZ2;
  /// The number of d-faces, d = 0 .. k (faces[0]: every vertex, used or not).
  std::vector<std::int64_t> faces;
  /// (k-1)-faces of exactly one k-simplex (k = 1: vertices of degree 1).
  std::int64_t boundaryFacets = 0;
  /// (k-1)-faces of three or more k-simplices (k = 1: vertices of degree 3 or more).
  std::int64_t nonmanifoldFacets = 0;

  /// The alternating sum of `faces`, which equals that of `betti` and of `bettiZ2`.
  std::int64_t eulerCharacteristic() const;
};

/// The homology of the complex of `vertexCount` vertices and the k-simplices `simplices`
/// (k + 1 vertex numbers each, in any order and orientation). Repeated simplices count once;
/// a simplex with a repeated vertex is ignored (welding leaves none).
Homology homology(std::size_t vertexCount, int k, std::span<const std::int32_t> simplices);

/// The homology of a complex (its coordinates are not read).
template <class S>
Homology homology(const Complex<S>& complex) {
  return homology(complex.vertexCount(), complex.k, complex.simplices);
}

}  // namespace ndc
