#include "strategies/connection/crossing/dual_complex.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numeric>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "framework/numeric/iteration.hpp"
#include "framework/numeric/parallel.hpp"
#include "strategies/connection/crossing/domain_boundary.hpp"
#include "strategies/connection/crossing/jacobian_work.hpp"

namespace ndc::crossing_detail {
namespace {

/// The axes a region beyond the domain lies beyond (outside bits: 2 per axis, 1 below, 2
/// above), as a mask of axes.
inline std::uint64_t beyondAxes(std::uint64_t key) {
  std::uint64_t axes = 0;
  for (int j = 0; key != 0; ++j, key >>= 2) {
    if (key & 3) axes |= std::uint64_t{1} << j;
  }
  return axes;
}

/// A polygon's cycle of mesh vertices, the regions beyond the domain replaced by vertices on
/// its faces (at most 4: a quad).
struct Cycle {
  std::array<std::int32_t, 4> v{};
  int size = 0;
};

/// The builder of buildDualComplex.
template <class S>
class DualComplex {
 public:
  explicit DualComplex(const DualInput<S>& d)
      : d_(d),
        polygons_(d.polygons),
        n_(d.tree.n()),
        k_(d.in.k),
        m_(n_ - k_),
        incident_(d.polygons, d.tree.size()) {}

  void build(ConnectionOutput<S>& out) {
    const std::size_t count = d_.tree.size();
    // Step 4: the pieces of M in each leaf; each leaf writes its own slots of piece_ (its
    // position in each incident polygon).
    piece_.assign(polygons_.size() * 4, 0);
    std::vector<std::int32_t> pieceCount(count, 0);
    std::vector<std::uint8_t> ambiguous(count, 0);
    parallelFor(count, [&](std::size_t c) { pieceCount[c] = pieces(c, ambiguous[c]); });
    for (std::uint8_t a : ambiguous) out.ambiguousCells += a;
    // Dual vertices: the Newton projection of the mean of each piece's crossings, written
    // into the complex in leaf and piece order.
    const std::size_t base = out.complex.vertexCount();
    const std::vector<DualVertex> vertices = dualVertices(pieceCount, out.complex);
    first_.assign(count, -1);
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const DualVertex& d = vertices[i];
      if (!d.converged) ++out.offManifoldVertices;  // reported, never written silently off M
      if (d.piece == 0) first_[d.leaf] = static_cast<std::int32_t>(base + i);
      if (d.piece == 0 && (d_.singular[d.leaf] || d.singular)) ++out.singularCells;
    }
    // The domain's boundary: every polygon is a cell of the mesh, its regions beyond the
    // domain replaced by vertices on the domain's faces, which come after the leaves'.
    boundaryBase_ = static_cast<std::int32_t>(out.complex.vertexCount());
    std::vector<Cycle> cycles(polygons_.size());
    for (std::size_t p = 0; p < polygons_.size(); ++p) cycles[p] = cycleOf(p);
    out.offManifoldVertices += placeBoundaryVertices(out.complex);
    addSimplices(cycles, out.complex);
  }

 private:
  /// A dual vertex: piece `piece` of M in leaf `leaf` (its point is in the complex).
  struct DualVertex {
    std::int32_t leaf = 0;
    std::int32_t piece = 0;
    bool converged = false;  ///< whether the projection converged
    bool singular = false;   ///< the Jacobian at the point is (nearly) rank-deficient
  };

  /// A vertex on the domain's boundary: on the face of the domain given by `key` (outside
  /// bits), next to leaf `leaf`; its point the projection onto M ∩ that face of the mean of
  /// its crossings (`sum` / `count`).
  struct BoundaryVertex {
    std::int32_t leaf = 0;
    std::uint64_t key = 0;
    std::int32_t count = 0;
  };

  /// The slot of leaf c in polygon p.
  int slotOf(std::int32_t p, std::size_t c) const {
    int at = 0;
    while (polygons_[p].node[at] != static_cast<std::int64_t>(c)) ++at;
    return at;
  }

  /// The pieces of M in leaf c: for k = 2 the components of the link of its vertex (one edge
  /// per incident polygon, between the polygon's two nodes next to c), one per sheet of M in
  /// the leaf; for k = 1 one. `ambiguous`: set when the piece is not simple.
  std::int32_t pieces(std::size_t c, std::uint8_t& ambiguous) {
    const std::span<const std::int32_t> ps = incident_[c];
    if (ps.empty()) return 0;
    if (k_ == 1) {
      for (std::int32_t p : ps) piece_[p * 4 + slotOf(p, c)] = 0;
      if (ps.size() != 2) ambiguous = 1;
      return 1;
    }
    std::vector<std::int64_t> nodes;
    std::vector<std::array<int, 2>> edges =
        linkEdges(static_cast<std::int64_t>(c), polygons_, ps, nodes);
    std::vector<int> degree(nodes.size(), 0);
    for (const auto& e : edges) ++degree[e[0]], ++degree[e[1]];
    // A region beyond the domain met more than twice is a facet that several sheets of M
    // reach: each meeting gets a node of its own, so that the sheets stay apart.
    for (auto& e : edges) {
      for (int& s : e) {
        if (nodes[s] >= 0 || degree[s] <= 2) continue;
        const std::int64_t node = nodes[s];
        s = static_cast<int>(nodes.size());
        nodes.push_back(node);
      }
    }
    UnionFind uf{std::vector<int>(nodes.size())};
    std::iota(uf.parent.begin(), uf.parent.end(), 0);
    for (const auto& e : edges) uf.unite(e[0], e[1]);
    std::vector<int> componentOf(nodes.size(), -1);
    int components = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const int r = uf.find(static_cast<int>(i));
      if (componentOf[r] < 0) componentOf[r] = components++;
    }
    for (std::size_t q = 0; q < ps.size(); ++q)
      piece_[ps[q] * 4 + slotOf(ps[q], c)] = componentOf[uf.find(edges[q][0])];
    // One simple piece: one component that is a cycle through every neighbour once.
    const bool simple =
        components == 1 && std::all_of(degree.begin(), degree.end(), [](int d) { return d == 2; });
    if (!simple) ambiguous = 1;
    return components;
  }

  /// The dual vertices in leaf and piece order, appended to `complex`: the mean of each piece's
  /// crossings (summed in the order of the leaf's polygons) projected onto M, or that mean
  /// where Newton fails; each leaf's in parallel into its own slots.
  std::vector<DualVertex> dualVertices(const std::vector<std::int32_t>& pieceCount,
                                       Complex<S>& complex) const {
    std::vector<std::size_t> first(pieceCount.size() + 1, complex.vertexCount());
    for (std::size_t c = 0; c < pieceCount.size(); ++c)
      first[c + 1] = first[c] + std::size_t(pieceCount[c]);
    complex.vertices.resize(first.back() * n_);
    complex.vertexCell.resize(first.back(), -1);
    std::vector<DualVertex> out(first.back() - first.front());
    parallelFor(pieceCount.size(), [&](std::size_t c) {
      if (pieceCount[c] == 0) return;
      std::vector<S> sums(std::size_t(pieceCount[c]) * n_, S(0));
      std::vector<std::int32_t> counts(pieceCount[c], 0);
      for (std::int32_t p : incident_[c]) {
        const std::int32_t q = piece_[p * 4 + slotOf(p, c)];
        for (int j = 0; j < n_; ++j)
          sums[std::size_t(q) * n_ + j] += d_.roots[std::size_t(polygons_[p].root) * n_ + j];
        ++counts[q];
      }
      const auto cell = d_.tree.baseCell(static_cast<std::int32_t>(c));
      for (int q = 0; q < pieceCount[c]; ++q) {
        const std::size_t v = first[c] + std::size_t(q);
        DualVertex& d = out[v - first.front()];
        d.leaf = static_cast<std::int32_t>(c);
        d.piece = q;
        const std::span<S> x(complex.vertices.data() + v * n_, std::size_t(n_));
        for (int j = 0; j < n_; ++j) x[j] = sums[std::size_t(q) * n_ + j] / counts[q];
        complex.vertexCell[v] = cell;
        projectVertex(d, x);
      }
    });
    return out;
  }

  /// Projects a dual vertex onto M (keeping the mean where Newton fails) and tests whether
  /// its cell is singular: the Jacobian at the vertex (nearly) rank-deficient relative to the
  /// cell size, as at self-intersections and cone points.
  void projectVertex(DualVertex& d, std::span<S> x) const {
    const std::vector<S> mean(x.begin(), x.end());
    d.converged = d_.in.project(x).converged;
    if (!d.converged) std::copy(mean.begin(), mean.end(), x.begin());
    if (d.converged && nearDomainBoundary(x)) {
      std::vector<int> all(n_);
      std::iota(all.begin(), all.end(), 0);
      snapToFaces(x, all);
    }
    if (d.piece != 0) return;
    const S width = S(d_.tree.grid(d_.tree.level(d.leaf)).cellWidth(0));
    std::optional<JacobianWork<S>> fresh;
    JacobianWork<S>& w = threadScratch<S, JacobianWork<S>>(fresh);
    w.jacobianAt(d_.in.system, std::span<const S>(x));
    // Most vertices are far from singular: a Cholesky test settles those.
    const S ratio = width * 1e-3;
    if (w.clearlyRegular(ratio)) {
      d.singular = false;
      return;
    }
    const auto& sigma = w.singularValues();
    d.singular = sigma(0) == 0 || sigma(m_ - 1) <= sigma(0) * ratio;
  }

  /// Polygon p's cycle of mesh vertices. A leaf is its piece's vertex; a region beyond the
  /// domain across k fixed axes (a domain face of dimension m, where M meets the face in the
  /// polygon's crossing) is the crossing's vertex; a region beyond one axis (k = 2) is the
  /// domain facet of each leaf next to it in the cycle, one vertex per (leaf, piece, facet).
  Cycle cycleOf(std::size_t p) {
    const Polygon& poly = polygons_[p];
    Cycle cycle;
    const auto push = [&cycle](std::int32_t v) {
      if (cycle.size > 0 && cycle.v[cycle.size - 1] == v) return;
      if (cycle.size < 4) cycle.v[cycle.size++] = v;
    };
    for (int i = 0; i < poly.size; ++i) {
      const std::int64_t node = poly.node[i];
      if (node >= 0) {
        push(first_[node] + piece_[p * 4 + i]);
        continue;
      }
      const std::uint64_t key = outsideKey(node);
      if (std::popcount(beyondAxes(key)) >= k_) {
        push(crossingVertex(poly, key));
        continue;
      }
      for (const int slot : {(i + poly.size - 1) % poly.size, (i + 1) % poly.size}) {
        const std::int64_t leaf = poly.node[slot];
        if (leaf >= 0) push(facetVertex(poly, leaf, piece_[p * 4 + slot], key));
      }
    }
    if (cycle.size > 1 && cycle.v[cycle.size - 1] == cycle.v[0]) --cycle.size;
    return cycle;
  }

  /// The vertex of the crossing of `poly`, a point of M on the domain face `key`.
  std::int32_t crossingVertex(const Polygon& poly, std::uint64_t key) {
    const auto [it, fresh] = crossingVertex_.try_emplace(poly.root, 0);
    if (fresh) {
      std::int64_t leaf = 0;
      for (int i = 0; i < poly.size; ++i) leaf = poly.node[i] >= 0 ? poly.node[i] : leaf;
      it->second = addBoundaryVertex(static_cast<std::int32_t>(leaf), key, poly.root);
    }
    return it->second;
  }

  /// The vertex of piece `piece` of leaf `leaf` on its domain facet `key` (k = 2), which
  /// gathers the crossings of the polygons that reach it.
  std::int32_t facetVertex(const Polygon& poly, std::int64_t leaf, std::int32_t piece,
                           std::uint64_t key) {
    const std::uint64_t axes = beyondAxes(key);
    const int axis = std::countr_zero(axes);
    const std::uint64_t id =
        (static_cast<std::uint64_t>(leaf) << 24) ^ (static_cast<std::uint64_t>(piece) << 8) ^
        static_cast<std::uint64_t>(2 * axis + ((key >> (2 * axis)) & 2 ? 1 : 0));
    const auto [it, fresh] = facetVertex_.try_emplace(id, 0);
    if (fresh) {
      it->second = addBoundaryVertex(static_cast<std::int32_t>(leaf), key, poly.root);
    } else {
      addCrossing(it->second, poly.root);
    }
    return it->second;
  }

  /// A new boundary vertex with its first crossing; its number in the complex.
  std::int32_t addBoundaryVertex(std::int32_t leaf, std::uint64_t key, std::int32_t root) {
    boundary_.push_back(BoundaryVertex{leaf, key, 0});
    sums_.resize(boundary_.size() * n_, S(0));
    const auto v = boundaryBase_ + static_cast<std::int32_t>(boundary_.size() - 1);
    addCrossing(v, root);
    return v;
  }

  void addCrossing(std::int32_t v, std::int32_t root) {
    const auto b = static_cast<std::size_t>(v - boundaryBase_);
    for (int j = 0; j < n_; ++j) sums_[b * n_ + j] += d_.roots[std::size_t(root) * n_ + j];
    ++boundary_[b].count;
  }

  /// The boundary vertices' points, appended to `complex`: the mean of each one's crossings
  /// on its domain face, projected onto M ∩ that face (its fixed coordinates stay; a free one
  /// may end beyond the domain by as much as the crossings, 64 * 2^-26 cell widths, where M
  /// meets a lower-dimensional face of it). Returns how many projections failed (those keep
  /// the mean).
  std::int64_t placeBoundaryVertices(Complex<S>& complex) const {
    const std::size_t first = complex.vertexCount();
    complex.vertices.resize((first + boundary_.size()) * n_);
    complex.vertexCell.resize(first + boundary_.size(), -1);
    std::vector<std::uint8_t> failed(boundary_.size(), 0);
    parallelFor(boundary_.size(), [&](std::size_t b) {
      const BoundaryVertex& v = boundary_[b];
      const std::span<S> x(complex.vertices.data() + (first + b) * n_, std::size_t(n_));
      std::vector<int> freeAxes;
      for (int j = 0; j < n_; ++j) {
        const std::uint64_t side = (v.key >> (2 * j)) & 3;
        x[j] = side == 1 ? d_.domain.lo[j]
                         : (side == 2 ? d_.domain.hi[j] : sums_[b * n_ + j] / v.count);
        if (side == 0) freeAxes.push_back(j);
      }
      const std::vector<S> mean(x.begin(), x.end());
      if (!projectOnFace(x, freeAxes)) {
        std::copy(mean.begin(), mean.end(), x.begin());
        failed[b] = 1;
      } else {
        snapToFaces(x, freeAxes);
      }
      complex.vertexCell[first + b] = d_.tree.baseCell(v.leaf);
    });
    return std::count(failed.begin(), failed.end(), std::uint8_t{1});
  }

  /// Whether x lies within the crossings' slack of a face of the domain.
  bool nearDomainBoundary(std::span<const S> x) const {
    using std::abs;
    for (int j = 0; j < n_; ++j) {
      if (abs(x[j] - d_.domain.lo[j]) <= d_.slack || abs(d_.domain.hi[j] - x[j]) <= d_.slack)
        return true;
    }
    return false;
  }

  /// A vertex within the crossings' slack of a face of the domain (of lower dimension than its
  /// own: M passes through that face, and M_c misses it by about c): moved onto M ∩ that face while
  /// the face keeps m free axes, so that the vertices of the facets meeting there become one
  /// point (they would stay 1e-9 apart, too far to weld, and leave a sliver triangle).
  void snapToFaces(std::span<S> x, std::vector<int>& freeAxes) const {
    using std::abs;
    while (static_cast<int>(freeAxes.size()) > m_) {
      int best = -1;
      S gap = d_.slack;
      for (std::size_t t = 0; t < freeAxes.size(); ++t) {
        const int j = freeAxes[t];
        const S g = std::min<S>(abs(x[j] - d_.domain.lo[j]), abs(d_.domain.hi[j] - x[j]));
        if (g <= gap) gap = g, best = static_cast<int>(t);
      }
      if (best < 0) return;
      const int j = freeAxes[best];
      std::vector<S> y(x.begin(), x.end());
      std::vector<int> fewer = freeAxes;
      fewer.erase(fewer.begin() + best);
      y[j] = abs(x[j] - d_.domain.lo[j]) < abs(d_.domain.hi[j] - x[j]) ? d_.domain.lo[j]
                                                                       : d_.domain.hi[j];
      if (!projectOnFace(std::span<S>(y), fewer)) return;
      std::copy(y.begin(), y.end(), x.begin());
      freeAxes = std::move(fewer);
    }
  }

  /// Minimum-norm Newton onto M ∩ the face where every axis but `freeAxes` keeps its value
  /// (faceNewton), on M when the run's own projection then leaves the point where it is.
  bool projectOnFace(std::span<S> x, const std::vector<int>& freeAxes) const {
    using std::abs;
    if (!faceNewton(d_.in.system, x, freeAxes)) return false;
    std::vector<S> copy(x.begin(), x.end());
    if (!d_.in.project(std::span<S>(copy)).converged) return false;
    const S size = 1 + normInf<S>(std::span<const S>(x.data(), x.size()));
    for (int j = 0; j < n_; ++j) {
      if (abs(copy[j] - x[j]) > S(1024) * ScalarTraits<S>::epsilon() * size) return false;
    }
    return true;
  }

  /// The simplices of every cycle, appended to `complex` in polygon order, each polygon's in
  /// parallel into its own slots.
  void addSimplices(const std::vector<Cycle>& cycles, Complex<S>& complex) const {
    const auto width = static_cast<std::size_t>(k_ + 1);
    std::vector<std::size_t> at(cycles.size() + 1, complex.simplices.size());
    for (std::size_t i = 0; i < cycles.size(); ++i)
      at[i + 1] = at[i] + width * simplicesOf(cycles[i]);
    complex.simplices.resize(at.back());
    parallelFor(
        cycles.size(),
        [&](std::size_t i) {
          writeSimplices(cycles[i], complex, complex.simplices.data() + at[i]);
        },
        1024);
  }

  /// How many simplices a cycle gives: an edge (k = 1), a triangle, or a quad's two; none when
  /// it has collapsed (a polygon whose nodes became one vertex).
  std::size_t simplicesOf(const Cycle& cycle) const {
    if (k_ == 1) return cycle.size == 2 ? 1 : 0;
    return cycle.size == 3 ? 1 : (cycle.size == 4 ? 2 : 0);
  }

  /// The simplices of one cycle into `slot`: an edge (k = 1), a triangle, or a quad split along
  /// its shorter diagonal (between the complex's vertices).
  void writeSimplices(const Cycle& cycle, const Complex<S>& complex, std::int32_t* slot) const {
    const auto& v = cycle.v;
    const auto put = [&slot](std::initializer_list<std::int32_t> simplex) {
      for (std::int32_t u : simplex) *slot++ = u;
    };
    if (simplicesOf(cycle) == 0) return;
    if (k_ == 1) return put({v[0], v[1]});
    if (cycle.size == 3) return put({v[0], v[1], v[2]});
    const auto distance = [&](int a, int b) {
      S sum = 0;
      for (int j = 0; j < n_; ++j) {
        const S diff = complex.vertices[std::size_t(v[a]) * n_ + j] -
                       complex.vertices[std::size_t(v[b]) * n_ + j];
        sum += diff * diff;
      }
      return sum;
    };
    if (distance(0, 2) <= distance(1, 3)) {
      put({v[0], v[1], v[2]});
      put({v[0], v[2], v[3]});
    } else {
      put({v[0], v[1], v[3]});
      put({v[1], v[2], v[3]});
    }
  }

  const DualInput<S>& d_;
  const std::vector<Polygon>& polygons_;
  int n_, k_, m_;
  Incidence incident_;
  std::vector<std::int32_t> piece_;  ///< [p * 4 + i]: the piece of node i of polygon p
  std::vector<std::int32_t> first_;  ///< per leaf: its first vertex
  std::int32_t boundaryBase_ = 0;    ///< the first boundary vertex's number
  std::vector<BoundaryVertex> boundary_;
  std::vector<S> sums_;  ///< n per boundary vertex: the sum of its crossings
  std::unordered_map<std::int32_t, std::int32_t> crossingVertex_;  ///< by root
  std::unordered_map<std::uint64_t, std::int32_t> facetVertex_;    ///< by (leaf, piece, facet)
};

}  // namespace

template <class S>
void buildDualComplex(const DualInput<S>& input, ConnectionOutput<S>& out) {
  DualComplex<S>(input).build(out);
}

template void buildDualComplex(const DualInput<double>&, ConnectionOutput<double>&);
template void buildDualComplex(const DualInput<Mpfr>&, ConnectionOutput<Mpfr>&);

}  // namespace ndc::crossing_detail
