/// \file expectation.hpp
/// The comparison of a problem's `[expect]` table with the mesh statistics of a run (`expect` in
/// summary.json, docs/contracts.md 4.5; `solve --check`; the `expect_ok` column of experiments).
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"

namespace ndc {

/// The `[expect]` keys that are compared with the mesh: the integer `mesh` fields of
/// summary.json (docs/contracts.md 4.3) by the same names, and `genus`.
inline constexpr std::array<std::string_view, 11> kExpectKeys = {
    "components",     "euler_characteristic", "vertices",          "edges",     "triangles",
    "boundary_edges", "boundary_components",  "nonmanifold_edges", "open_ends", "branch_vertices",
    "genus"};

/// Compares every key of `expect` with `mesh` (a run of a k-manifold), in the order
/// components, euler_characteristic, then the other keys by name. Each key gives one
/// ExpectCheck; none is skipped:
/// - a `mesh` field (kExpectKeys) is compared as an integer;
/// - `genus` is compared as (2 - euler_characteristic) / 2 only where that formula holds for
///   the mesh: k = 2, one component, no boundary or non-manifold edges, and an even Euler
///   characteristic (a closed connected orientable surface); otherwise it is not comparable;
/// - any other key (problem files refuse them when read) is not comparable.
/// A key that is not comparable has ExpectCheck::notComparable set and `ok` false.
std::vector<ExpectCheck> checkExpectation(const Expectation& expect, const MeshStats& mesh, int k);

/// Whether some compared key differs (keys that were not comparable do not count).
bool expectationMismatch(const std::vector<ExpectCheck>& checks);

/// One line describing a check that is not ok: `expect components = 1, got 4`, or
/// `expect genus = 2: not comparable (...)`.
std::string describeCheck(const ExpectCheck& check);

}  // namespace ndc
