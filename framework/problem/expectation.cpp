#include "framework/problem/expectation.hpp"

#include <cstdint>
#include <optional>

namespace ndc {
namespace {

/// The mesh statistic named `key`, if it is one.
std::optional<std::int64_t> meshField(const std::string& key, const MeshStats& m) {
  if (key == "components") return m.components;
  if (key == "euler_characteristic") return m.eulerCharacteristic;
  if (key == "vertices") return m.vertices;
  if (key == "edges") return m.edges;
  if (key == "triangles") return m.triangles;
  if (key == "boundary_edges") return m.boundaryEdges;
  if (key == "boundary_components") return m.boundaryComponents;
  if (key == "nonmanifold_edges") return m.nonmanifoldEdges;
  if (key == "open_ends") return m.openEnds;
  if (key == "branch_vertices") return m.branchVertices;
  return std::nullopt;
}

ExpectCheck check(const std::string& key, long wanted, const MeshStats& m, int k) {
  ExpectCheck c;
  c.key = key;
  c.wanted = wanted;
  if (const auto got = meshField(key, m)) {
    c.got = static_cast<long>(*got);
    c.ok = c.got == c.wanted;
    return c;
  }
  if (key == "genus") {
    // chi = 2 - 2g holds for one closed orientable surface; anything else has no genus to
    // compare (the components and Euler characteristic keys say what is wrong).
    if (k != 2)
      c.notComparable = "genus needs a surface (k = 2), the problem has k = " + std::to_string(k);
    else if (m.components != 1)
      c.notComparable = "genus needs one component, the mesh has " + std::to_string(m.components);
    else if (m.boundaryEdges != 0 || m.nonmanifoldEdges != 0)
      c.notComparable = "genus needs a closed manifold mesh, it has " +
                        std::to_string(m.boundaryEdges) + " boundary and " +
                        std::to_string(m.nonmanifoldEdges) + " non-manifold edges";
    else if (m.eulerCharacteristic % 2 != 0)
      c.notComparable = "genus needs an even Euler characteristic, the mesh has " +
                        std::to_string(m.eulerCharacteristic);
    if (c.notComparable.empty()) {
      c.got = static_cast<long>((2 - m.eulerCharacteristic) / 2);
      c.ok = c.got == c.wanted;
    }
    return c;
  }
  std::string known;
  for (std::string_view name : kExpectKeys)
    known += (known.empty() ? "" : ", ") + std::string(name);
  c.notComparable = "not a mesh statistic (compared: " + known + ")";
  return c;
}

}  // namespace

std::vector<ExpectCheck> checkExpectation(const Expectation& expect, const MeshStats& mesh, int k) {
  std::vector<ExpectCheck> checks;
  if (expect.components) checks.push_back(check("components", *expect.components, mesh, k));
  if (expect.eulerCharacteristic)
    checks.push_back(check("euler_characteristic", *expect.eulerCharacteristic, mesh, k));
  for (const auto& [key, wanted] : expect.other) checks.push_back(check(key, wanted, mesh, k));
  return checks;
}

bool expectationMismatch(const std::vector<ExpectCheck>& checks) {
  for (const ExpectCheck& c : checks)
    if (c.notComparable.empty() && !c.ok) return true;
  return false;
}

std::string describeCheck(const ExpectCheck& c) {
  const std::string head = "expect " + c.key + " = " + std::to_string(c.wanted);
  if (!c.notComparable.empty()) return head + ": not comparable (" + c.notComparable + ")";
  return head + ", got " + std::to_string(c.got);
}

}  // namespace ndc
