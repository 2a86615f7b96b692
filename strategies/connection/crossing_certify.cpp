/// \file crossing_certify.cpp
/// The crossing connection, phase 2: the certificate of each leaf (docs/certificate.md): the
/// graph tests of its box and faces and its link.
#include "strategies/connection/crossing_detail.hpp"

#include <algorithm>
#include <numeric>
#include <utility>

namespace ndc::crossing_detail {

template <class S>
void AdaptiveCrossing<S>::setTrouble(std::int32_t leaf, std::span<const S> point) {
  grow();
  if (hasTrouble_[leaf]) return;
  hasTrouble_[leaf] = 1;
  std::copy(point.begin(), point.end(), trouble_.begin() + std::ptrdiff_t(leaf) * n_);
}

template <class S>
void AdaptiveCrossing<S>::faceTrouble(std::int32_t leaf, int a, bool upper) {
  const Box<S> box = leafBox(leaf);
  std::vector<S> centre(n_);
  for (int j = 0; j < n_; ++j) centre[j] = (box.lo[j] + box.hi[j]) / 2;
  centre[a] = upper ? box.hi[a] : box.lo[a];
  setTrouble(leaf, centre);
}

template <class S>
bool AdaptiveCrossing<S>::cellGraph(std::int32_t leaf) {
  if (graph_[leaf] < 0) {
    restrictTo(leaf);
    graph_[leaf] = patchesGraph();
  }
  return graph_[leaf] == 1;
}

template <class S>
bool AdaptiveCrossing<S>::patchesGraph() {
  jacobian_.assign(std::size_t(m_) * n_, Interval<S>());
  for (int i = 0; i < m_; ++i) {
    for (int j = 0; j < n_; ++j)
      jacobian_[std::size_t(i) * n_ + j] = derivativeHull(patches_[i], j, margins_[i]);
  }
  std::vector<int> axes(n_);
  std::iota(axes.begin(), axes.end(), 0);
  return graphTest_.graph(jacobian_, axes);
}

template <class S>
bool AdaptiveCrossing<S>::intervalEmpty(const Box<S>& box, bool band) {
  using I = Interval<S>;
  std::vector<I> x;
  for (int j = 0; j < n_; ++j) x.emplace_back(box.lo[j], box.hi[j]);
  for (int i = 0; i < m_; ++i) {
    const I f = in_.system.equations()[i].template evaluate<S>(std::span<const I>(x));
    if (m_ == 1 && (f.lower() >= 0 || f.upper() < 0)) return true;
    const S c = level_[i];
    const S lo = band ? std::min<S>(S(0), c) : c, hi = band ? std::max<S>(S(0), c) : c;
    if (m_ > 1 && (f.lower() > hi || f.upper() < lo)) return true;
  }
  return false;
}

template <class S>
bool AdaptiveCrossing<S>::facesGraph(std::int32_t leaf) {
  if (faceGraph_[leaf] < 0) {
    restrictTo(leaf);
    const int failed = failingFace();
    faceGraph_[leaf] = failed < 0;
    if (failed >= 0) faceTrouble(leaf, failed / 2, failed % 2 == 1);
  }
  return faceGraph_[leaf] == 1;
}

template <class S>
std::vector<int> AdaptiveCrossing<S>::freeAxes(int a) const {
  std::vector<int> axes;
  for (int j = 0; j < n_; ++j) {
    if (j != a) axes.push_back(j);
  }
  return axes;
}

template <class S>
std::vector<std::pair<int, bool>> AdaptiveCrossing<S>::failingFaces(bool all) {
  std::vector<std::pair<int, bool>> failing;
  for (int a = 0; a < n_; ++a) {
    const std::vector<int> axes = freeAxes(a);
    for (int side = 0; side < 2; ++side) {
      if (faceGraph(a, side == 1, axes)) continue;
      failing.emplace_back(a, side == 1);
      if (!all) return failing;
    }
  }
  return failing;
}

template <class S>
int AdaptiveCrossing<S>::failingFace() {
  const auto failing = failingFaces(false);
  return failing.empty() ? -1 : 2 * failing.front().first + int(failing.front().second);
}

template <class S>
bool AdaptiveCrossing<S>::faceGraph(int a, bool upper, const std::vector<int>& axes) {
  jacobian_.assign(std::size_t(m_) * n_, Interval<S>());
  for (int i = 0; i < m_; ++i) {
    const Bernstein<S> face = patches_[i].faceSlice(a, upper);
    if (clearsRange(face, level_[i], level_[i], margins_[i])) return true;
    for (int j : axes)
      jacobian_[std::size_t(i) * n_ + j] = derivativeHull(face, j < a ? j : j - 1, margins_[i]);
  }
  if (graphTest_.graph(jacobian_, axes)) return true;
  Box<S> face = patches_.front().domain();
  face.lo[a] = face.hi[a] = upper ? face.hi[a] : face.lo[a];
  // Near a point where M is tangent to the face's hyperplane no block is regular, and M
  // usually misses the face although each equation alone meets it.
  return combinationExcludes(in_.system, std::span<const S>(level_), face,
                             std::span<const Interval<S>>(jacobian_), axes) ||
         intervalEmpty(face, false);
}

template <class S>
void AdaptiveCrossing<S>::certify() {
  std::vector<std::vector<std::int32_t>> incident(tree_.size());
  for (std::size_t p = 0; p < polygons_.size(); ++p) {
    for (int i = 0; i < polygons_[p].size; ++i) {
      if (polygons_[p].node[i] >= 0)
        incident[polygons_[p].node[i]].push_back(static_cast<std::int32_t>(p));
    }
  }
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
    failure_[c] = Failure::kNone;
    if (!tree_.active(c)) continue;
    if (empty_[c] == 1) {
      // M_c misses the leaf; M may not (it lies 1e-8 h away): where it meets the leaf, the
      // isotopy from M to M_c needs the Jacobian's rank there.
      if (!bandEmpty_[c] && !cellGraph(c) && !intervalEmpty(leafBox(c), true))
        failure_[c] = Failure::kGraph;
      continue;
    }
    if (unproven_[c]) {
      failure_[c] = Failure::kCrossing;
    } else if (!cellGraph(c) && !intervalEmpty(leafBox(c), true)) {
      failure_[c] = Failure::kGraph;
    } else if (k_ == 2 && !facesGraph(c)) {
      failure_[c] = Failure::kFaceGraph;
    } else if (!simpleLink(c, polygons_, incident[c])) {
      failure_[c] = Failure::kLink;
    }
  }
  mergeBlocks(incident);
}

template <class S>
std::vector<std::array<int, 2>> AdaptiveCrossing<S>::linkEdges(std::int64_t c,
                                                               const std::vector<Polygon>& polygons,
                                                               const std::vector<std::int32_t>& ps,
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

template <class S>
bool AdaptiveCrossing<S>::simpleLink(std::int64_t c, const std::vector<Polygon>& polygons,
                                     const std::vector<std::int32_t>& ps) const {
  if (ps.empty()) return true;
  if (k_ == 1) return ps.size() == 2;
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

// The members of AdaptiveCrossing defined in this file, for double and ndc::Mpfr.
#define NDC_CROSSING_INSTANTIATE(S)                                                              \
  template void AdaptiveCrossing<S>::setTrouble(std::int32_t leaf, std::span<const S> point);    \
  template void AdaptiveCrossing<S>::faceTrouble(std::int32_t leaf, int a, bool upper);          \
  template bool AdaptiveCrossing<S>::cellGraph(std::int32_t leaf);                               \
  template bool AdaptiveCrossing<S>::patchesGraph();                                             \
  template bool AdaptiveCrossing<S>::intervalEmpty(const Box<S>& box, bool band);                \
  template bool AdaptiveCrossing<S>::facesGraph(std::int32_t leaf);                              \
  template std::vector<int> AdaptiveCrossing<S>::freeAxes(int a) const;                          \
  template std::vector<std::pair<int, bool>> AdaptiveCrossing<S>::failingFaces(bool all);        \
  template int AdaptiveCrossing<S>::failingFace();                                               \
  template bool AdaptiveCrossing<S>::faceGraph(int a, bool upper, const std::vector<int>& axes); \
  template void AdaptiveCrossing<S>::certify();                                                  \
  template std::vector<std::array<int, 2>> AdaptiveCrossing<S>::linkEdges(                       \
      std::int64_t c, const std::vector<Polygon>& polygons, const std::vector<std::int32_t>& ps, \
      std::vector<std::int64_t>& nodes);                                                         \
  template bool AdaptiveCrossing<S>::simpleLink(                                                 \
      std::int64_t c, const std::vector<Polygon>& polygons, const std::vector<std::int32_t>& ps) \
      const;
NDC_CROSSING_INSTANTIATE(double)
NDC_CROSSING_INSTANTIATE(Mpfr)
#undef NDC_CROSSING_INSTANTIATE

}  // namespace ndc::crossing_detail
