/// \file dual_polygon.hpp
/// The polygons of the crossing connection's dual complex (docs/crossing.md, step 3): one per
/// crossed minimal m-face, its nodes the regions around the face in cyclic order, and the
/// link of a leaf that they form. Internal to the crossing connection (the certificate, the
/// blocks and the mesh all read them).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

namespace ndc::crossing_detail {

/// Union-find over small integer sets (the link of one vertex).
struct UnionFind {
  std::vector<int> parent;
  int find(int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

/// A crossed minimal m-face of the tree (docs/certificate.md): the leaves around it in cyclic
/// order (k = 2; a coarser leaf that fills two of the four quadrants appears once, so the
/// polygon is a triangle), or the two leaves across it (k = 1). A node is a leaf number, or
/// -1 - key for a region beyond the domain, key its outside bits (CellTree's Occupant: 2 bits
/// per axis, 1 below, 2 above). The mesh replaces such a node by a vertex on the domain's
/// boundary (docs/crossing.md, "The domain's boundary").
struct Polygon {
  std::array<std::int64_t, 4> node{-1, -1, -1, -1};
  int size = 0;
  std::int32_t root = -1;  ///< its crossing, in the root list
  bool outside = false;    ///< a node lies beyond the domain
};

/// The outside bits of a node beyond the domain (-1 - key), or 0 for a leaf.
inline std::uint64_t outsideKey(std::int64_t node) {
  return node >= 0 ? 0 : static_cast<std::uint64_t>(-1 - node);
}

/// The polygons at each node (leaf) of a polygon list, in polygon order, as one array: the
/// polygons of leaf c are polygons_[first_[c], first_[c + 1]). Built by counting, so it costs
/// two passes and no vector per leaf.
class Incidence {
 public:
  /// Over `leaves` leaves.
  Incidence(const std::vector<Polygon>& polygons, std::size_t leaves) {
    first_.assign(leaves + 1, 0);
    for (const Polygon& poly : polygons) {
      for (int i = 0; i < poly.size; ++i)
        if (poly.node[i] >= 0) ++first_[std::size_t(poly.node[i]) + 1];
    }
    for (std::size_t c = 0; c < leaves; ++c) first_[c + 1] += first_[c];
    polygons_.resize(first_.back());
    std::vector<std::size_t> at(first_.begin(), first_.end() - 1);
    for (std::size_t p = 0; p < polygons.size(); ++p) {
      for (int i = 0; i < polygons[p].size; ++i)
        if (polygons[p].node[i] >= 0)
          polygons_[at[std::size_t(polygons[p].node[i])]++] = static_cast<std::int32_t>(p);
    }
  }

  /// The polygons at leaf c.
  std::span<const std::int32_t> operator[](std::size_t c) const {
    return std::span<const std::int32_t>(polygons_).subspan(first_[c], first_[c + 1] - first_[c]);
  }

 private:
  std::vector<std::size_t> first_;
  std::vector<std::int32_t> polygons_;
};

/// The link of leaf c (k = 2): one edge per polygon, between the polygon's two nodes next to
/// c; `nodes` receives the distinct neighbour nodes the edges number.
inline std::vector<std::array<int, 2>> linkEdges(std::int64_t c,
                                                 const std::vector<Polygon>& polygons,
                                                 std::span<const std::int32_t> ps,
                                                 std::vector<std::int64_t>& nodes) {
  std::vector<std::array<int, 2>> edges;
  for (std::int32_t p : ps) {
    const Polygon& poly = polygons[p];
    int at = 0;
    while (poly.node[at] != c) ++at;
    std::array<int, 2> e{};
    for (int s = 0; s < 2; ++s) {
      const std::int64_t node = poly.node[(at + (s ? poly.size - 1 : 1)) % poly.size];
      auto it = std::find(nodes.begin(), nodes.end(), node);
      e[s] = static_cast<int>(it - nodes.begin());
      if (it == nodes.end()) nodes.push_back(node);
    }
    edges.push_back(e);
  }
  return edges;
}

/// Whether the crossings on the boundary of leaf c form one simple piece: none, or two
/// (k = 1), or one cycle through every neighbour region exactly twice (k = 2; the regions
/// beyond the domain are nodes too, so a surface with boundary closes its loop there).
inline bool simpleLink(int k, std::int64_t c, const std::vector<Polygon>& polygons,
                       std::span<const std::int32_t> ps) {
  if (ps.empty()) return true;
  if (k == 1) return ps.size() == 2;
  std::vector<std::int64_t> nodes;
  const std::vector<std::array<int, 2>> edges = linkEdges(c, polygons, ps, nodes);
  UnionFind uf{std::vector<int>(nodes.size())};
  std::iota(uf.parent.begin(), uf.parent.end(), 0);
  std::vector<int> degree(nodes.size(), 0);
  for (const auto& e : edges) {
    uf.unite(e[0], e[1]);
    ++degree[e[0]];
    ++degree[e[1]];
  }
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (degree[i] != 2 || uf.find(int(i)) != uf.find(0)) return false;
  }
  return true;
}

}  // namespace ndc::crossing_detail
