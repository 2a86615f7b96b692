// PaperConnection: the connection stage of the paper (Sec. 4.1, 4.2, Algorithm 1).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <unordered_map>
#include <utility>
#include <vector>

#include "strategies/connection/connection.hpp"
#include "strategies/connection/connection_detail.hpp"

namespace ndc {
namespace {

using connection_detail::distance2;
using connection_detail::dot;
using connection_detail::edgeKey;

/// The state of one run of the paper's connection.
template <class S>
class PaperBuilder {
 public:
  PaperBuilder(const ConnectionInput<S>& input, const PaperConnection::Options& options)
      : in_(input),
        cells_(input.cells),
        n_(input.cells.grid.n),
        k_(input.k),
        options_(options),
        vertexOf_(input.cells.size(), -1),
        consumed_(input.cells.size(), 0),
        mark_(input.cells.size(), -1) {
    out_.complex.n = n_;
    out_.complex.k = k_;
  }

  ConnectionOutput<S> run() {
    //! [paper-alg1]
    // Sec. 4.1: the vertices are the projected points of the normal cells only.
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (!normal(c)) continue;
      vertexOf_[c] = newVertex(in_.projections.at(c), static_cast<std::int32_t>(c));
    }
    if (k_ == 1)
      connectNormalCurve();
    else
      connectNormalSurface();

    // Alg. 1 (2): collect dangling normal cells that have a face-adjacent abnormal cell.
    std::vector<std::int32_t> dangling;
    inD_.assign(cells_.size(), 0);
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (!normal(c) || !open(vertexOf_[c]) || !hasNonNormalNeighbour(c)) continue;
      dangling.push_back(static_cast<std::int32_t>(c));
      inD_[c] = 1;
    }

    // Alg. 1: for each dangling normal cube d in D, bridge through its abnormal cluster.
    for (std::int32_t d : dangling) {
      if (consumed_[d] || !open(vertexOf_[d])) continue;
      bridge(d);
    }
    // Second pass (beyond the paper, k = 1): a cell of D still open (deleted from D by a
    // cluster that could not close it, or whose partner lies more than n - 1 abnormal layers
    // away) gets a cluster of its own, n layers deeper.
    if (k_ == 1)
      for (std::int32_t d : dangling)
        if (open(vertexOf_[d])) bridge(d, n_);
    compact();
    //! [paper-alg1]
    return std::move(out_);
  }

 private:
  bool normal(std::size_t c) const { return in_.classes[c] == CellClass::kNormal; }

  bool hasNonNormalNeighbour(std::size_t c) const {
    for (int a = 0; a < n_; ++a)
      for (int s : {-1, +1}) {
        const std::int32_t d = cells_.neighbour(c, a, s);
        if (d >= 0 && !normal(d)) return true;
      }
    return false;
  }

  std::int32_t newVertex(std::span<const S> x, std::int32_t cell) {
    adjacent_.emplace_back();
    triangles_.push_back(0);
    return out_.complex.addVertex(x, cell);
  }

  int edgeCount(std::int32_t a, std::int32_t b) const {
    auto it = edgeCount_.find(edgeKey(a, b));
    return it == edgeCount_.end() ? 0 : it->second;
  }

  /// Records one more simplex on the edge {a, b}.
  void touchEdge(std::int32_t a, std::int32_t b) {
    if (edgeCount_[edgeKey(a, b)]++ == 0) {
      adjacent_[a].push_back(b);
      adjacent_[b].push_back(a);
    }
  }

  void addEdge(std::int32_t a, std::int32_t b) {
    const std::array<std::int32_t, 2> e{a, b};
    out_.complex.addSimplex(e);
    touchEdge(a, b);
  }

  void addTriangle(std::int32_t a, std::int32_t b, std::int32_t c) {
    const std::array<std::int32_t, 3> t{a, b, c};
    out_.complex.addSimplex(t);
    touchEdge(a, b);
    touchEdge(b, c);
    touchEdge(c, a);
    ++triangles_[a];
    ++triangles_[b];
    ++triangles_[c];
  }

  /// Whether a vertex still dangles: k = 1 fewer than two edges; k = 2 no triangle or a
  /// boundary edge (an edge of exactly one triangle).
  bool open(std::int32_t v) const {
    if (k_ == 1) return adjacent_[v].size() < 2;
    if (triangles_[v] == 0) return true;
    for (std::int32_t w : adjacent_[v])
      if (edgeCount(v, w) == 1) return true;
    return false;
  }

  /// Sec. 4.1: "When a normal cubic cell has a face-adjacent normal cube, we connect them by
  /// an edge", with thick normal sets thinned along the tangent line (see docs/connection.md).
  void connectNormalCurve() {
    std::vector<std::vector<std::int32_t>> normalNeighbours(cells_.size());
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (!normal(c)) continue;
      for (int a = 0; a < n_; ++a)
        for (int s : {-1, +1}) {
          const std::int32_t d = cells_.neighbour(c, a, s);
          if (d >= 0 && normal(d)) normalNeighbours[c].push_back(d);
        }
    }
    // Thick normal set: keep the nearest neighbour on each side of the tangent line.
    std::vector<std::vector<std::int32_t>> kept(cells_.size());
    std::vector<std::uint8_t> thinned(cells_.size(), 0);
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      const auto& nb = normalNeighbours[c];
      if (nb.size() < 2 || !options_.thinThickNormal) continue;
      const auto p = in_.projections.at(c);
      const auto ts = connection_detail::tangentSpace<S>(in_.system, p, 1);
      if (ts.basis.empty()) continue;
      std::int32_t before = -1, after = -1;
      double tBefore = 0, tAfter = 0;
      for (std::int32_t d : nb) {
        const auto q = in_.projections.at(d);
        S t = 0;
        for (int j = 0; j < n_; ++j) t += (q[j] - p[j]) * ts.basis[j];
        const double td = toDouble(t);
        if (td >= 0 && (after < 0 || td < tAfter)) after = d, tAfter = td;
        if (td < 0 && (before < 0 || td > tBefore)) before = d, tBefore = td;
      }
      if (before >= 0) kept[c].push_back(before);
      if (after >= 0) kept[c].push_back(after);
      thinned[c] = kept[c].size() < nb.size();
    }
    for (std::size_t c = 0; c < cells_.size(); ++c)
      if (normalNeighbours[c].size() > 2 || thinned[c]) ++out_.ambiguousCells;
    auto keeps = [&](std::size_t c, std::int32_t d) {
      if (!thinned[c]) return true;
      return std::find(kept[c].begin(), kept[c].end(), d) != kept[c].end();
    };
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (!normal(c)) continue;
      for (int a = 0; a < n_; ++a) {
        const std::int32_t d = cells_.neighbour(c, a, +1);
        if (d < 0 || !normal(d) || !keeps(c, d) || !keeps(d, c)) continue;
        addEdge(vertexOf_[c], vertexOf_[d]);
      }
    }
  }

  /// Sec. 4.2: four mutually face-adjacent normal cells (a plaquette) give a quad, split into
  /// two triangles along its shorter diagonal.
  void connectNormalSurface() {
    connection_detail::forEachPlaquette(
        cells_, [&](std::int32_t c) { return normal(c); },
        [&](std::int32_t c0, std::int32_t c1, std::int32_t c2, std::int32_t c3) {
          connection_detail::splitQuad(
              out_.complex, vertexOf_[c0], vertexOf_[c1], vertexOf_[c2], vertexOf_[c3],
              [&](std::int32_t a, std::int32_t b, std::int32_t c) { addTriangle(a, b, c); });
        });
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (!normal(c)) continue;
      const std::int32_t v = vertexOf_[c];
      for (std::int32_t w : adjacent_[v])
        if (edgeCount(v, w) >= 3) {
          ++out_.ambiguousCells;
          break;
        }
    }
  }

  /// Alg. 1: the cluster N of d, its projected centroid, the tangent space there, and the
  /// polyline (k = 1) or fan (k = 2) through the cluster's dangling points and the centroid.
  void bridge(std::int32_t d, int deeper = 0) {
    const int id = clusters_++;
    //! [paper-cluster]
    // Alg. 1: N <- face-adjacent normal and abnormal cubes at d, then recursively through
    // abnormal cubes, up to n - 1 layers. Failed cells are traversed like abnormal ones but
    // have no point.
    const int layers = n_ - 1 + options_.extraLayers + deeper;
    std::vector<std::pair<std::int32_t, int>> queue{{d, 0}};
    mark_[d] = id;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const auto [u, depth] = queue[head];
      if (u != d && (normal(u) || depth > layers)) continue;
      for (int a = 0; a < n_; ++a)
        for (int s : {-1, +1}) {
          const std::int32_t w = cells_.neighbour(static_cast<std::size_t>(u), a, s);
          if (w < 0 || mark_[w] == id) continue;
          mark_[w] = id;
          queue.emplace_back(w, depth + 1);
        }
    }

    std::vector<std::int32_t> abnormal, points;  // cells
    for (const auto& [u, depth] : queue) {
      if (in_.classes[u] == CellClass::kAbnormal) abnormal.push_back(u);
      // k = 1: the dangling cells of D (a non-dangling normal cell would become a branch);
      // k = 2: every normal cell of N whose ring is still open ("all the normal cubes").
      if (normal(u) && (inD_[u] || k_ == 2) && open(vertexOf_[u])) points.push_back(u);
    }
    // Alg. 1: delete the cluster's normal cubes from D.
    for (const auto& [u, depth] : queue)
      if (normal(u)) consumed_[u] = 1;
    //! [paper-cluster]
    if (points.size() < 2) return;  // nothing to bridge: a lone end stays open

    // Alg. 1: the centroid of N (of its abnormal points; of all its points if none).
    const auto& centreCells = abnormal.empty() ? points : abnormal;
    std::vector<S> centroid(n_, S(0));
    for (std::int32_t u : centreCells) {
      const auto p = in_.projections.at(u);
      for (int j = 0; j < n_; ++j) centroid[j] += p[j];
    }
    for (int j = 0; j < n_; ++j) centroid[j] /= S(static_cast<double>(centreCells.size()));
    std::vector<S> onM = centroid;
    const ProjectedPoint<S> projected = in_.project(std::span<S>(onM));
    if (!projected.converged || !(distance2<S>(onM, centroid) <= S(4.0 * cellDiagonal2()))) {
      // Projection failed or jumped away: use the cluster point nearest to the centroid.
      std::int32_t best = -1;
      S bestD = 0;
      for (const auto* list : {&abnormal, &points})
        for (std::int32_t u : *list) {
          const S dd = distance2<S>(in_.projections.at(u), centroid);
          if (best < 0 || dd < bestD) best = u, bestD = dd;
        }
      const auto p = in_.projections.at(best);
      onM.assign(p.begin(), p.end());
    }

    // Sec. 4.1: V <- the basis of the tangent space at the centroid.
    const auto ts = connection_detail::tangentSpace<S>(in_.system, onM, k_);
    if (ts.singular) ++out_.singularCells;
    if (static_cast<int>(ts.basis.size()) != k_ * n_) return;

    // Parameterise the dangling points over the tangent space: (p - c) . v_i.
    auto coordinate = [&](std::span<const S> p, int i) {
      S t = 0;
      for (int j = 0; j < n_; ++j) t += (p[j] - onM[j]) * ts.basis[std::size_t(i) * n_ + j];
      return toDouble(t);
    };
    if (k_ == 1)
      bridgeCurve(points, onM, coordinate);
    else
      bridgeSurface(points, onM, coordinate);
  }

  /// k = 1: parameterise the dangling points (and the centroid, t = 0) along the tangent
  /// line and join them in that order. An end of a polyline is open only away from its one
  /// neighbour (towards larger t if its neighbour has a smaller t, and vice versa); a cell
  /// with no edge is open both ways. Open ends facing each other are matched, nearest pairs
  /// first; the pair that straddles the centroid goes through it.
  template <class Coordinate>
  void bridgeCurve(const std::vector<std::int32_t>& points, const std::vector<S>& onM,
                   Coordinate&& coordinate) {
    struct End {
      std::int32_t vertex;
      double t;
      bool up, down;  // open towards larger / smaller t
    };
    std::vector<End> ends;
    for (std::int32_t u : points) {
      const std::int32_t v = vertexOf_[u];
      const double t = coordinate(out_.complex.vertex(v), 0);
      End e{v, t, true, true};
      if (adjacent_[v].size() == 1) {
        const double tq = coordinate(out_.complex.vertex(adjacent_[v][0]), 0);
        e.up = tq <= t;
        e.down = tq >= t;
      }
      ends.push_back(e);
    }
    // Candidate pairs (a below b, a open up, b open down), shortest first.
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t a = 0; a < ends.size(); ++a)
      for (std::size_t b = 0; b < ends.size(); ++b)
        if (a != b && ends[a].t <= ends[b].t && ends[a].up && ends[b].down)
          pairs.emplace_back(a, b);
    std::stable_sort(pairs.begin(), pairs.end(), [&](const auto& x, const auto& y) {
      return ends[x.second].t - ends[x.first].t < ends[y.second].t - ends[y.first].t;
    });
    std::int32_t centroid = -1;
    for (const auto& [a, b] : pairs) {
      End& lo = ends[a];
      End& hi = ends[b];
      if (!lo.up || !hi.down || edgeCount(lo.vertex, hi.vertex) > 0) continue;
      if (adjacent_[lo.vertex].size() >= 2 || adjacent_[hi.vertex].size() >= 2) continue;
      if (centroid < 0 && lo.t < 0 && 0 < hi.t) {
        // Alg. 1: the centroid becomes the intermediate solution point of the bridge.
        centroid = newVertex(onM, -1);
        addEdge(lo.vertex, centroid);
        addEdge(centroid, hi.vertex);
      } else {
        addEdge(lo.vertex, hi.vertex);
      }
      lo.up = false;
      hi.down = false;
    }
  }

  /// k = 2: order the dangling points by angle around the centroid in the tangent plane and
  /// fan-triangulate consecutive pairs to the centroid; a pair is skipped when its angular gap
  /// is at least pi (the fan would not be a disk there) or its edge already has two triangles.
  template <class Coordinate>
  void bridgeSurface(const std::vector<std::int32_t>& points, const std::vector<S>& onM,
                     Coordinate&& coordinate) {
    std::vector<std::pair<double, std::int32_t>> ring;  // (angle, cell)
    const double tiny = 1e-9 * std::sqrt(cellDiagonal2());
    for (std::int32_t u : points) {
      const auto p = in_.projections.at(u);
      const double x = coordinate(p, 0), y = coordinate(p, 1);
      if (std::hypot(x, y) <= tiny) continue;  // on the centroid: no direction
      ring.emplace_back(std::atan2(y, x), u);
    }
    if (ring.size() < 2) return;
    std::sort(ring.begin(), ring.end());
    std::int32_t vc = -1;
    const std::size_t r = ring.size();
    for (std::size_t i = 0; i < (r == 2 ? 1 : r); ++i) {
      const std::size_t j = (i + 1) % r;
      double gap = ring[j].first - ring[i].first;
      if (j == 0) gap += 2 * std::numbers::pi;
      if (gap >= std::numbers::pi) continue;
      const std::int32_t va = vertexOf_[ring[i].second], vb = vertexOf_[ring[j].second];
      if (edgeCount(va, vb) >= 2) continue;
      if (vc < 0) vc = newVertex(onM, -1);
      addTriangle(vc, va, vb);
    }
  }

  double cellDiagonal2() const {
    double sum = 0;
    for (int j = 0; j < n_; ++j) sum += cells_.grid.cellWidth(j) * cells_.grid.cellWidth(j);
    return sum;
  }

  /// Drops vertices no simplex uses (normal cells left without a simplex, e.g. by thinning)
  /// and renumbers the simplices.
  void compact() {
    Complex<S>& cx = out_.complex;
    std::vector<std::int32_t> used(cx.vertexCount(), 0);
    for (std::int32_t v : cx.simplices) used[v] = 1;
    Complex<S> result;
    result.n = cx.n;
    result.k = cx.k;
    std::vector<std::int32_t> renumber(cx.vertexCount(), -1);
    for (std::size_t v = 0; v < cx.vertexCount(); ++v)
      if (used[v]) renumber[v] = result.addVertex(cx.vertex(v), cx.vertexCell[v]);
    result.simplices.reserve(cx.simplices.size());
    for (std::int32_t v : cx.simplices) result.simplices.push_back(renumber[v]);
    cx = std::move(result);
  }

  const ConnectionInput<S>& in_;
  const SolutionCells& cells_;
  int n_, k_;
  PaperConnection::Options options_;
  ConnectionOutput<S> out_;
  std::vector<std::int32_t> vertexOf_;  ///< cell -> vertex (normal cells) or -1
  std::vector<std::uint8_t> consumed_;  ///< removed from D by a cluster
  std::vector<std::uint8_t> inD_;       ///< in D (Alg. 1 step (2))
  std::vector<std::int32_t> mark_;      ///< cluster stamp of a cell
  int clusters_ = 0;
  std::unordered_map<std::uint64_t, std::int32_t> edgeCount_;  ///< simplices per edge
  std::vector<std::vector<std::int32_t>> adjacent_;            ///< vertex -> edge neighbours
  std::vector<std::int32_t> triangles_;                        ///< vertex -> triangle count
};

}  // namespace

ModelSpec PaperConnection::spec() {
  const Options defaults;
  return {"paper",
          "The paper's connection (Sec. 4.1, 4.2): normal cells joined through shared faces, "
          "abnormal cells repaired in their tangent space.",
          {{"extra_layers", ParameterType::kInteger, static_cast<double>(defaults.extraLayers), 0,
            8, "expansions through abnormal cells beyond the paper's n - 1 layers"},
           {"thin_thick_normal", ParameterType::kBoolean, defaults.thinThickNormal ? 1.0 : 0.0, 0,
            1, "k = 1: thin thick normal sets along the tangent line (false: the literal rule)"}},
          {.certifies = false, .refines = false, .minK = 1, .maxK = 2}};
}

PaperConnection PaperConnection::create(const Parameters& parameters) {
  return PaperConnection({.thinThickNormal = parameters.boolean("thin_thick_normal"),
                          .extraLayers = parameters.integer("extra_layers")});
}

template <class S>
ConnectionOutput<S> PaperConnection::connect(const ConnectionInput<S>& input) const {
  requireBuildsK(spec(), input.k);
  PaperBuilder<S> builder(input, options_);
  return builder.run();
}

template ConnectionOutput<double> PaperConnection::connect(const ConnectionInput<double>&) const;
template ConnectionOutput<Mpfr> PaperConnection::connect(const ConnectionInput<Mpfr>&) const;

}  // namespace ndc
