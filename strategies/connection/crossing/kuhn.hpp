/// \file kuhn.hpp
/// The combinatorics of the crossing connection for manifolds of any dimension k
/// (docs/crossing.md, "Any k"): the k-subsets of axes that a minimal m-face fixes, the Kuhn
/// (Freudenthal) split of a dual k-cube into k! simplices, and the test that the crossings on a
/// face of a cell form a sphere. Internal to the crossing connection; header only, so that the
/// tests drive it directly.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <numeric>
#include <set>
#include <vector>

namespace ndc::crossing_detail {

/// The k-subsets of {0, .., n-1} as sorted axis lists, in lexicographic order.
inline std::vector<std::vector<int>> axisSubsets(int n, int k) {
  std::vector<std::vector<int>> out;
  std::vector<int> pick(static_cast<std::size_t>(k));
  std::iota(pick.begin(), pick.end(), 0);
  if (k > n || k < 0) return out;
  for (;;) {
    out.push_back(pick);
    // Next combination: the last position that can still move right.
    int t = k - 1;
    while (t >= 0 && pick[std::size_t(t)] == n - k + t) --t;
    if (t < 0) return out;
    ++pick[std::size_t(t)];
    for (int u = t + 1; u < k; ++u) pick[std::size_t(u)] = pick[std::size_t(u - 1)] + 1;
  }
}

/// One simplex of the Kuhn split of the unit k-cube: the order in which the chain from the
/// corner 0 to the corner 1..1 raises the k coordinates (`order[t]` is a position in 0..k-1),
/// and the sign of that permutation.
struct KuhnChain {
  std::vector<int> order;
  int sign = 1;
};

/// The k! chains of the Kuhn split of the k-cube. The split of every cube of a grid by all
/// monotone chains is the Freudenthal triangulation: the chains of a facet x_t = 0 or 1 are
/// the facet's own Kuhn split, whichever cube it is seen from, so neighbouring dual cubes
/// agree on the faces they share (docs/crossing.md, "Any k").
inline std::vector<KuhnChain> kuhnChains(int k) {
  std::vector<KuhnChain> out;
  std::vector<int> order(static_cast<std::size_t>(k));
  std::iota(order.begin(), order.end(), 0);
  do {
    // The sign of the permutation by its inversions.
    int inversions = 0;
    for (int a = 0; a < k; ++a)
      for (int b = a + 1; b < k; ++b) inversions += order[std::size_t(a)] > order[std::size_t(b)];
    out.push_back(KuhnChain{order, inversions % 2 ? -1 : 1});
  } while (std::next_permutation(order.begin(), order.end()));
  return out;
}

/// What sphereTest finds of a pure complex of j-simplices.
enum class SphereCheck { kEmpty, kSphere, kNotSphere, kUndecided };

/// Whether a pure complex of j-simplices (each a sorted list of j + 1 vertex labels) is a
/// j-sphere, given that the links of its vertices are (j-1)-spheres (the caller checked the
/// smaller faces first): for j = 0 exactly two points; for j >= 1 strongly connected with
/// Euler characteristic 1 + (-1)^j, which with the links decides j = 1 (one cycle) and j = 2
/// (a closed connected surface with chi = 2 is S^2). For j >= 3 a homology count cannot tell a
/// sphere from other manifolds: such a complex that passes is kUndecided, never kSphere.
inline SphereCheck sphereTest(int j, const std::vector<std::vector<int>>& simplices) {
  if (simplices.empty()) return SphereCheck::kEmpty;
  if (j == 0) return simplices.size() == 2 ? SphereCheck::kSphere : SphereCheck::kNotSphere;
  // Every face of every dimension, counted once, for chi; the (j-1)-faces join simplices.
  std::set<std::vector<int>> faces;
  std::map<std::vector<int>, std::vector<int>> ridges;
  std::vector<int> part;
  for (std::size_t s = 0; s < simplices.size(); ++s) {
    const std::vector<int>& v = simplices[s];
    const auto size = static_cast<int>(v.size());
    for (int mask = 1; mask < (1 << size); ++mask) {
      part.clear();
      for (int b = 0; b < size; ++b)
        if (mask >> b & 1) part.push_back(v[std::size_t(b)]);
      faces.insert(part);
      if (static_cast<int>(part.size()) == size - 1) ridges[part].push_back(static_cast<int>(s));
    }
  }
  std::int64_t chi = 0;
  for (const auto& f : faces) chi += (f.size() % 2 == 1) ? 1 : -1;
  // Strong connectivity: simplices joined through shared ridges; every ridge on two.
  std::vector<int> parent(simplices.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&parent](int i) {
    while (parent[std::size_t(i)] != i)
      i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
    return i;
  };
  for (const auto& [ridge, on] : ridges) {
    if (on.size() != 2) return SphereCheck::kNotSphere;
    parent[std::size_t(find(on[0]))] = find(on[1]);
  }
  for (std::size_t s = 0; s < simplices.size(); ++s)
    if (find(static_cast<int>(s)) != find(0)) return SphereCheck::kNotSphere;
  if (chi != 1 + (j % 2 == 0 ? 1 : -1)) return SphereCheck::kNotSphere;
  return j <= 2 ? SphereCheck::kSphere : SphereCheck::kUndecided;
}

}  // namespace ndc::crossing_detail
