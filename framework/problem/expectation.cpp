#include "framework/problem/expectation.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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
  if (key == "boundary_facets") return m.boundaryFacets;
  if (key == "nonmanifold_facets") return m.nonmanifoldFacets;
  return std::nullopt;
}

/// A list as `[1, 2, 1]`.
std::string listText(const std::vector<long>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i)
    out += (i ? ", " : "") + std::to_string(values[i]);
  return out + "]";
}

/// A list key (`betti`, `betti_z2`) compared with the mesh's list of k + 1 numbers.
ExpectCheck checkList(const std::string& key, const std::vector<long>& wanted, const MeshStats& m,
                      int k) {
  ExpectCheck c;
  c.key = key;
  c.isList = true;
  c.wantedList = wanted;
  const std::vector<std::int64_t>& got = key == "betti" ? m.betti : m.bettiZ2;
  if (got.empty())
    c.notComparable = "the mesh has no Betti numbers (a summary written before them)";
  else if (wanted.size() != got.size())
    c.notComparable = key + " needs k + 1 = " + std::to_string(k + 1) + " numbers, it has " +
                      std::to_string(wanted.size());
  if (!c.notComparable.empty()) return c;
  c.gotList.assign(got.begin(), got.end());
  c.ok = c.gotList == c.wantedList;
  return c;
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
  for (const auto& [key, wanted] : expect.lists) checks.push_back(checkList(key, wanted, mesh, k));
  return checks;
}

bool expectationMismatch(const std::vector<ExpectCheck>& checks) {
  for (const ExpectCheck& c : checks)
    if (c.notComparable.empty() && !c.ok) return true;
  return false;
}

std::string expectedText(const ExpectCheck& c) {
  return c.isList ? listText(c.wantedList) : std::to_string(c.wanted);
}

std::string gotText(const ExpectCheck& c) {
  return c.isList ? listText(c.gotList) : std::to_string(c.got);
}

std::string bettiText(const std::vector<std::int64_t>& betti) {
  return listText(std::vector<long>(betti.begin(), betti.end()));
}

std::string describeCheck(const ExpectCheck& c) {
  const std::string head = "expect " + c.key + " = " + expectedText(c);
  if (!c.notComparable.empty()) return head + ": not comparable (" + c.notComparable + ")";
  return head + ", got " + gotText(c);
}

}  // namespace ndc
