/// \file crossing.cpp
/// The crossing connection, phase 5 and entry point: the per-leaf state, the pieces of M in each
/// leaf, the dual vertices and simplices, and CrossingConnection::connect.
#include "strategies/connection/crossing.hpp"

#include <algorithm>
#include <numeric>

#include "strategies/connection/crossing_detail.hpp"

namespace ndc {
namespace crossing_detail {

template <class S>
AdaptiveCrossing<S>::AdaptiveCrossing(const ConnectionInput<S>& in, int maxFaceDepth)
    : in_(in),
      grid_(in.cells.grid),
      n_(grid_.n),
      k_(in.k),
      m_(n_ - k_),
      maxFaceDepth_(maxFaceDepth),
      position_(in, grid_),
      graphTest_(grid_.n, grid_.n - in.k),
      tree_(grid_, std::max(grid_.depth, in.refine ? in.maxLevel : grid_.depth)) {
  domain_ = toScalar<S>(grid_.domain);
  for (int a = 0; a < n_; ++a) {
    if (k_ == 1) fixedAxes_.push_back({a, -1});
    for (int b = a + 1; k_ == 2 && b < n_; ++b) fixedAxes_.push_back({a, b});
  }
  // Refinement stops before this many leaves: thin features need a few times the base
  // cells (genus2 at depth 5: 8x, the thin torus at depth 3: 50x, so at least 65536 in
  // R^3); where refinement cannot succeed (tangency along a curve, graph tests that fail on
  // every cell) it bounds the cost. A leaf costs more and a refinement makes 2^n of them as
  // n grows, so the floor shrinks by 16 per dimension, to 4096 from R^4 on.
  maxLeaves_ = std::max<std::size_t>(16 * in.cells.size(),
                                     std::size_t{1} << std::max(12, 16 - 4 * (grid_.n - 3)));
  // A chord error the user asks for (--tolerance) may need many more: up to 2^22 leaves
  // (a few hundred MB); the CLI warns when the tolerance is not reached.
  if (in.tolerance > 0) maxLeaves_ = std::max<std::size_t>(maxLeaves_, std::size_t{1} << 22);
}

template <class S>
void AdaptiveCrossing<S>::grow() {
  const std::size_t size = tree_.size();
  if (empty_.size() >= size) return;
  trouble_.resize(size * n_, S(0));
  hasTrouble_.resize(size, 0);
  empty_.resize(size, -1);
  bandEmpty_.resize(size, 0);
  unproven_.resize(size, 0);
  stuck_.resize(size, 0);
  singular_.resize(size, 0);
  graph_.resize(size, -1);
  faceGraph_.resize(size, -1);
  failure_.resize(size, Failure::kNone);
}

template <class S>
void AdaptiveCrossing<S>::buildComplex(ConnectionOutput<S>& out) {
  collapseBlocks(out.topology.certified);
  const std::size_t count = tree_.size();
  std::vector<std::int32_t> mesh;
  for (std::size_t p = 0; p < polygons_.size(); ++p) {
    if (!polygons_[p].outside) mesh.push_back(static_cast<std::int32_t>(p));
  }
  std::vector<std::vector<std::int32_t>> incident(count);
  for (std::int32_t p : mesh) {
    for (int i = 0; i < polygons_[p].size; ++i) incident[polygons_[p].node[i]].push_back(p);
  }
  const auto slotOf = [&](std::int32_t p, std::size_t c) {
    int at = 0;
    while (polygons_[p].node[at] != static_cast<std::int64_t>(c)) ++at;
    return at;
  };
  // piece[p * 4 + i]: the piece of M in leaf node[i] that polygon p belongs to.
  std::vector<std::int32_t> piece(polygons_.size() * 4, 0), pieceCount(count, 0);
  for (std::size_t c = 0; c < count; ++c)
    pieceCount[c] = pieces(c, incident[c], piece, slotOf, out);
  // Dual vertices: the Newton projection of the mean of each piece's crossings.
  std::vector<std::int32_t> firstVertex(count, -1);
  std::vector<S> sums, x(n_);
  std::vector<std::int32_t> counts;
  for (std::size_t c = 0; c < count; ++c) {
    if (pieceCount[c] == 0) continue;
    const S width = S(tree_.grid(tree_.level(c)).cellWidth(0));
    sums.assign(std::size_t(pieceCount[c]) * n_, S(0));
    counts.assign(pieceCount[c], 0);
    for (std::int32_t p : incident[c]) {
      const std::int32_t q = piece[p * 4 + slotOf(p, c)];
      for (int j = 0; j < n_; ++j)
        sums[std::size_t(q) * n_ + j] += rootPoints_[std::size_t(polygons_[p].root) * n_ + j];
      ++counts[q];
    }
    for (int q = 0; q < pieceCount[c]; ++q) {
      for (int j = 0; j < n_; ++j) x[j] = sums[std::size_t(q) * n_ + j] / counts[q];
      const std::vector<S> mean = x;
      if (!in_.project(x).converged) {
        // Reported, never written silently off M (the analysis measures its residual too).
        x = mean;
        ++out.offManifoldVertices;
      }
      const std::int32_t v = out.complex.addVertex(x, tree_.baseCell(std::int32_t(c)));
      if (q == 0) firstVertex[c] = v;
      // Singular cells: the Jacobian at the vertex is (nearly) rank-deficient relative to
      // the cell size, as at self-intersections and cone points.
      const Vector<S> sigma = singularValuesAt<S>(in_.system, x);
      if (q == 0 && (singular_[c] || sigma(0) == 0 || sigma(m_ - 1) <= sigma(0) * width * 1e-3))
        ++out.singularCells;
    }
  }
  for (std::int32_t p : mesh) addSimplices(polygons_[p], p, firstVertex, piece, out);
}

template <class S>
template <class SlotOf>
std::int32_t AdaptiveCrossing<S>::pieces(std::size_t c, const std::vector<std::int32_t>& ps,
                                         std::vector<std::int32_t>& piece, const SlotOf& slotOf,
                                         ConnectionOutput<S>& out) const {
  if (ps.empty()) return 0;
  const bool boundary = onDomainBoundary(static_cast<std::int32_t>(c));
  if (k_ == 1) {
    for (std::int32_t p : ps) piece[p * 4 + slotOf(p, c)] = 0;
    if (ps.size() != 2 && !(boundary && ps.size() == 1)) ++out.ambiguousCells;
    return 1;
  }
  std::vector<std::int64_t> nodes;
  const std::vector<std::array<int, 2>> edges =
      linkEdges(static_cast<std::int64_t>(c), polygons_, ps, nodes);
  UnionFind uf{std::vector<int>(nodes.size())};
  std::iota(uf.parent.begin(), uf.parent.end(), 0);
  for (const auto& e : edges) uf.unite(e[0], e[1]);
  std::vector<int> componentOf(nodes.size(), -1), degree(nodes.size(), 0);
  int components = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const int r = uf.find(static_cast<int>(i));
    if (componentOf[r] < 0) componentOf[r] = components++;
  }
  for (const auto& e : edges) ++degree[e[0]], ++degree[e[1]];
  for (std::size_t q = 0; q < ps.size(); ++q)
    piece[ps[q] * 4 + slotOf(ps[q], c)] = componentOf[uf.find(edges[q][0])];
  // One simple piece: one component that is a cycle (or a path on the domain boundary).
  int ends = 0;
  bool simple = components == 1;
  for (int d : degree) {
    if (d == 1) ++ends;
    simple = simple && d <= 2;
  }
  simple = simple && (ends == 0 || (boundary && ends == 2));
  if (!simple) ++out.ambiguousCells;
  return components;
}

template <class S>
bool AdaptiveCrossing<S>::onDomainBoundary(std::int32_t c) const {
  const auto touches = [&](std::int32_t leaf) {
    const auto ci = tree_.index(leaf);
    const std::int64_t top = tree_.grid(tree_.level(leaf)).cellsPerAxis();
    return std::any_of(ci.begin(), ci.end(),
                       [&](std::int32_t i) { return i == 0 || i + 1 == top; });
  };
  if (c < static_cast<std::int32_t>(block_.size()) && block_[c] >= 0) {
    const auto& members = blocks_[block_[c]];
    return std::any_of(members.begin(), members.end(), touches);
  }
  return touches(c);
}

template <class S>
void AdaptiveCrossing<S>::addSimplices(const Polygon& poly, std::int32_t p,
                                       const std::vector<std::int32_t>& first,
                                       const std::vector<std::int32_t>& piece,
                                       ConnectionOutput<S>& out) const {
  std::array<std::int32_t, 4> v{};
  for (int i = 0; i < poly.size; ++i) v[i] = first[poly.node[i]] + piece[p * 4 + i];
  if (k_ == 1) {
    out.complex.addSimplex(std::array<std::int32_t, 2>{v[0], v[1]});
    return;
  }
  if (poly.size == 3) {
    out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[1], v[2]});
    return;
  }
  const auto distance = [&](int a, int b) {
    S sum = 0;
    for (int j = 0; j < n_; ++j) {
      const S diff = out.complex.vertices[std::size_t(v[a]) * n_ + j] -
                     out.complex.vertices[std::size_t(v[b]) * n_ + j];
      sum += diff * diff;
    }
    return sum;
  };
  if (distance(0, 2) <= distance(1, 3)) {
    out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[1], v[2]});
    out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[2], v[3]});
  } else {
    out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[1], v[3]});
    out.complex.addSimplex(std::array<std::int32_t, 3>{v[1], v[2], v[3]});
  }
}

// The members of AdaptiveCrossing defined in this file, for double and ndc::Mpfr.
#define NDC_CROSSING_INSTANTIATE(S)                                                               \
  template AdaptiveCrossing<S>::AdaptiveCrossing(const ConnectionInput<S>& in, int maxFaceDepth); \
  template void AdaptiveCrossing<S>::grow();                                                      \
  template void AdaptiveCrossing<S>::buildComplex(ConnectionOutput<S>& out);                      \
  template bool AdaptiveCrossing<S>::onDomainBoundary(std::int32_t c) const;                      \
  template void AdaptiveCrossing<S>::addSimplices(                                                \
      const Polygon& poly, std::int32_t p, const std::vector<std::int32_t>& first,                \
      const std::vector<std::int32_t>& piece, ConnectionOutput<S>& out) const;
NDC_CROSSING_INSTANTIATE(double)
NDC_CROSSING_INSTANTIATE(Mpfr)
#undef NDC_CROSSING_INSTANTIATE

}  // namespace crossing_detail

template <class S>
ConnectionOutput<S> CrossingConnection::connect(const ConnectionInput<S>& in) const {
  if (in.k != 1 && in.k != 2) {
    throw InputError("connection 'crossing' supports k = 1 and k = 2, not k = " +
                     std::to_string(in.k));
  }
  return crossing_detail::AdaptiveCrossing<S>(in, maxFaceDepth).run();
}

template ConnectionOutput<double> CrossingConnection::connect(const ConnectionInput<double>&) const;
template ConnectionOutput<Mpfr> CrossingConnection::connect(const ConnectionInput<Mpfr>&) const;

}  // namespace ndc
