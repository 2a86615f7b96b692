/// \file expectation.hpp
/// The comparison of a problem's `[expect]` table with the mesh statistics of a run (`expect` in
/// summary.json, docs/contracts.md 4.5; `solve --check`; the `expect_ok` column of experiments).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"

namespace ndc {

/// The `[expect]` keys that are compared with the mesh: the integer `mesh` fields of
/// summary.json (docs/contracts.md 4.3, 4.5) by the same names, `genus`, and the lists of
/// Betti numbers (kExpectListKeys).
inline constexpr std::array<std::string_view, 15> kExpectKeys = {"components",
                                                                 "euler_characteristic",
                                                                 "vertices",
                                                                 "edges",
                                                                 "triangles",
                                                                 "boundary_edges",
                                                                 "boundary_components",
                                                                 "nonmanifold_edges",
                                                                 "open_ends",
                                                                 "branch_vertices",
                                                                 "boundary_facets",
                                                                 "nonmanifold_facets",
                                                                 "genus",
                                                                 "betti",
                                                                 "betti_z2"};

/// The `[expect]` keys whose value is a list of integers: `mesh.betti` and `mesh.betti_z2`, b_0 ..
/// b_k over Q and over Z/2.
inline constexpr std::array<std::string_view, 2> kExpectListKeys = {"betti", "betti_z2"};

/// Compares every key of `expect` with `mesh` (a run of a k-manifold), in the order
/// components, euler_characteristic, the other integer keys by name, then the list keys by
/// name. Each key gives one
/// ExpectCheck; none is skipped:
/// - a `mesh` field (kExpectKeys) is compared as an integer;
/// - `genus` is compared as (2 - euler_characteristic) / 2 only where that formula holds for
///   the mesh: k = 2, one component, no boundary or non-manifold edges, and an even Euler
///   characteristic (a closed connected orientable surface); otherwise it is not comparable;
/// - a list key (kExpectListKeys) is compared element by element with the mesh's list, which has
///   k + 1 numbers; a list of another length is not comparable, nor is a mesh without Betti
///   numbers (a summary written before they were);
/// - any other key (problem files refuse them when read) is not comparable.
/// A key that is not comparable has ExpectCheck::notComparable set and `ok` false.
std::vector<ExpectCheck> checkExpectation(const Expectation& expect, const MeshStats& mesh, int k);

/// Whether some compared key differs (keys that were not comparable do not count).
bool expectationMismatch(const std::vector<ExpectCheck>& checks);

/// The value a check wanted and the one it got, as text: `2`, or `[1, 2, 1]` for a list key.
std::string expectedText(const ExpectCheck& check);
std::string gotText(const ExpectCheck& check);

/// Betti numbers as text: `[1, 2, 1]`.
std::string bettiText(const std::vector<std::int64_t>& betti);

/// One line describing a check that is not ok: `expect components = 1, got 4`,
/// `expect betti = [1, 2, 1], got [1, 0, 1]`, or `expect genus = 2: not comparable (...)`.
std::string describeCheck(const ExpectCheck& check);

}  // namespace ndc
