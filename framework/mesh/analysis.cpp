// The analysis stage (docs/contracts.md 4.3): welding, topology and accuracy of a complex.
//
// Welding: vertices closer than `tolerance` (Euclidean, in the coordinates) merge into the
// first of them (its coordinates are kept, not averaged, so a welded vertex is still a
// projected point of M). Candidates are found in a hashed grid of buckets of edge
// 16 * tolerance: a vertex looks in its own bucket and, along each axis where it lies within
// 2 * tolerance of a bucket face, in the neighbour bucket across that face (so pairs that
// straddle a face merge too, at an expected ~1.25^n buckets per vertex instead of 3^n).
// Merging is greedy in vertex order: a chain a~b~c with |a - c| > tolerance still maps every
// vertex to the first representative within tolerance.
//
// Chord error: a midpoint / centroid whose projection does not converge is left out of
// max_chord_error and counted in MeshStats::chordFailures.
#include "framework/mesh/analysis.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numeric>
#include <span>
#include <vector>

#include "framework/mesh/homology.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/util/disjoint_sets.hpp"
#include "framework/util/flat_map.hpp"

namespace ndc {

namespace {

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  // splitmix64 finaliser of the running hash and the next value.
  h ^= v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

/// Clears keep[s] of every record s (`width` integers each in `keys`) whose key equals that
/// of an earlier record that is kept: a sort of record numbers instead of a hash set of
/// vectors (one allocation per record), with the same result.
void markDuplicates(const std::vector<std::int32_t>& keys, std::size_t width,
                    std::vector<std::uint8_t>& keep) {
  std::vector<std::uint32_t> order;
  order.reserve(keep.size());
  for (std::size_t s = 0; s < keep.size(); ++s) {
    if (keep[s]) order.push_back(static_cast<std::uint32_t>(s));
  }
  const auto key = [&](std::uint32_t s) { return keys.begin() + std::ptrdiff_t(s * width); };
  const auto less = [&](std::uint32_t a, std::uint32_t b) {
    const auto x = key(a), y = key(b);
    for (std::size_t i = 0; i < width; ++i) {
      if (x[i] != y[i]) return x[i] < y[i];
    }
    return a < b;
  };
  parallelSort(order.begin(), order.end(), less);  // ties broken by the record number
  for (std::size_t i = 1; i < order.size(); ++i) {
    if (std::equal(key(order[i]), key(order[i]) + std::ptrdiff_t(width), key(order[i - 1])))
      keep[order[i]] = 0;
  }
}

/// The buckets of weld's hashed grid: a vertex's own bucket and the neighbours across the
/// bucket faces it lies within 2 tolerance of, as hashes of their integer coordinates.
template <class S>
class WeldBuckets {
 public:
  WeldBuckets(const Complex<S>& complex, double tolerance)
      : complex_(complex),
        fuzzy_(tolerance > 0),
        bucket_(fuzzy_ ? 16 * tolerance : 1.0),
        margin_(2 * tolerance) {}

  /// Per-caller scratch of probes().
  struct Scratch {
    std::vector<std::int64_t> home, probe;
    std::vector<std::array<int, 2>> reach;  // per axis: lowest and highest bucket offset
    std::vector<int> offset;
  };

  /// The hash of vertex v's own bucket.
  std::uint64_t home(std::size_t v, Scratch& w) const {
    locate(v, w);
    return hashOf(w.home);
  }

  /// Calls `f(hash)` for every bucket vertex v looks in (its own among them).
  template <class F>
  void probes(std::size_t v, Scratch& w, const F& f) const {
    locate(v, w);
    const int n = complex_.n;
    for (int j = 0; j < n; ++j) w.offset[j] = w.reach[j][0];
    while (true) {
      for (int j = 0; j < n; ++j) w.probe[j] = w.home[j] + w.offset[j];
      f(hashOf(w.probe));
      int j = 0;
      while (j < n && w.offset[j] == w.reach[j][1]) w.offset[j] = w.reach[j][0], ++j;
      if (j == n) return;
      ++w.offset[j];
    }
  }

 private:
  /// Vertex v's bucket coordinates and reach into w.
  void locate(std::size_t v, Scratch& w) const {
    const int n = complex_.n;
    w.home.resize(n), w.probe.resize(n), w.reach.resize(n), w.offset.resize(n);
    const auto x = complex_.vertex(v);
    for (int j = 0; j < n; ++j) {
      const double xd = toDouble(x[j]);
      double q = std::floor(xd / bucket_);
      if (!std::isfinite(q)) q = 0;  // NaN / inf coordinates share bucket 0; distance decides
      q = std::clamp(q, -4.0e18, 4.0e18);
      w.home[j] = static_cast<std::int64_t>(q);
      w.reach[j] = {0, 0};
      if (fuzzy_ && std::isfinite(xd)) {
        // Why: a partner within tolerance may sit across the nearest bucket face.
        if (xd - q * bucket_ <= margin_) w.reach[j][0] = -1;
        if ((q + 1) * bucket_ - xd <= margin_) w.reach[j][1] = 1;
      }
    }
  }

  static std::uint64_t hashOf(std::span<const std::int64_t> b) {
    std::uint64_t h = 0x12345678;
    for (std::int64_t c : b) h = mix(h, static_cast<std::uint64_t>(c));
    return h;
  }

  const Complex<S>& complex_;
  bool fuzzy_;
  double bucket_, margin_;
};

/// Which vertices can merge at all: those that look in a bucket (by hash) where another vertex
/// lives, and those others. The rest are alone within their reach and stay as they are.
/// In parallel: each vertex marks itself and the vertices it finds.
template <class S>
std::vector<std::uint8_t> mergeCandidates(const Complex<S>& complex,
                                          const WeldBuckets<S>& buckets) {
  using Scratch = typename WeldBuckets<S>::Scratch;
  const std::size_t count = complex.vertexCount();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> homes(count);
  parallelForBlocks(count, [&](std::size_t begin, std::size_t end) {
    Scratch w;
    for (std::size_t v = begin; v < end; ++v)
      homes[v] = {buckets.home(v, w), static_cast<std::uint32_t>(v)};
  });
  parallelSort(homes.begin(), homes.end(), std::less<>());
  // Where each vertex's own bucket is in `homes`: its run of equal hashes is next to it.
  std::vector<std::uint32_t> rank(count);
  parallelFor(
      count, [&](std::size_t i) { rank[homes[i].second] = static_cast<std::uint32_t>(i); }, 4096);
  std::vector<std::uint8_t> candidate(count, 0);
  parallelForBlocks(count, [&](std::size_t begin, std::size_t end) {
    Scratch w;
    for (std::size_t v = begin; v < end; ++v) {
      const std::size_t at = rank[v];
      const std::uint64_t own = homes[at].first;
      // Its own bucket: the vertices there mark themselves too.
      if ((at > 0 && homes[at - 1].first == own) || (at + 1 < count && homes[at + 1].first == own))
        std::atomic_ref<std::uint8_t>(candidate[v]).store(1, std::memory_order_relaxed);
      // The neighbour buckets (a vertex near a bucket face): a search, and the vertices found
      // are marked, since they need not look back.
      buckets.probes(v, w, [&](std::uint64_t hash) {
        if (hash == own) return;
        auto it = std::lower_bound(homes.begin(), homes.end(), std::pair{hash, std::uint32_t{0}});
        for (; it != homes.end() && it->first == hash; ++it) {
          std::atomic_ref<std::uint8_t>(candidate[v]).store(1, std::memory_order_relaxed);
          std::atomic_ref<std::uint8_t>(candidate[it->second]).store(1, std::memory_order_relaxed);
        }
      });
    }
  });
  return candidate;
}

}  // namespace

template <class S>
void dropUnusedVertices(Complex<S>& c) {
  const std::size_t count = c.vertexCount(), n = std::size_t(c.n);
  std::vector<std::int32_t> map(count, -1);
  for (std::int32_t v : c.simplices) map[v] = 0;
  if (std::none_of(map.begin(), map.end(), [](std::int32_t u) { return u < 0; })) return;
  std::size_t kept = 0;
  for (std::size_t v = 0; v < count; ++v) {
    if (map[v] < 0) continue;
    map[v] = static_cast<std::int32_t>(kept);
    std::copy_n(c.vertices.begin() + std::ptrdiff_t(v * n), n,
                c.vertices.begin() + std::ptrdiff_t(kept * n));
    if (!c.vertexCell.empty()) c.vertexCell[kept] = c.vertexCell[v];
    ++kept;
  }
  c.vertices.resize(kept * n);
  if (!c.vertexCell.empty()) c.vertexCell.resize(kept);
  for (std::int32_t& v : c.simplices) v = map[v];
}

namespace {

/// weld, step 1: greedy merge through the hashed bucket grid, among the vertices that can merge
/// at all (the others stay, and are found by no one): in vertex order, each merges into the
/// first earlier vertex that stayed and lies within tolerance (first: the one that stayed
/// earliest, so the one with the lowest output number). Returns, per vertex, the vertex it
/// merges into (itself: it stays).
template <class S>
std::vector<std::int32_t> mergeTargets(const Complex<S>& complex, double tolerance) {
  const int n = complex.n;
  const S tol2 = tolerance > 0 ? S(tolerance) * S(tolerance) : S(0);
  const std::size_t vertices = complex.vertexCount();
  const WeldBuckets<S> buckets(complex, tolerance);
  const std::vector<std::uint8_t> candidate = mergeCandidates(complex, buckets);
  std::vector<std::int32_t> into(vertices);
  std::iota(into.begin(), into.end(), std::int32_t{0});
  // bucket hash -> its latest staying vertex; next[v]: the one added to the bucket before v.
  FlatMap<std::uint64_t, std::int32_t> latest;
  std::vector<std::int32_t> next(vertices, -1);
  typename WeldBuckets<S>::Scratch w;
  for (std::size_t v = 0; v < vertices; ++v) {
    if (!candidate[v]) continue;
    const auto x = complex.vertex(v);
    std::int32_t found = -1;
    buckets.probes(v, w, [&](std::uint64_t hash) {
      const std::int32_t* last = latest.find(hash);
      for (std::int32_t r = last ? *last : -1; r >= 0; r = next[r]) {
        const auto y = complex.vertex(static_cast<std::size_t>(r));
        S d2 = 0;
        for (int j = 0; j < n; ++j) d2 += (x[j] - y[j]) * (x[j] - y[j]);
        if (d2 <= tol2 && (found < 0 || r < found)) found = r;
      }
    });
    if (found >= 0) {
      into[v] = found;
      continue;
    }
    const auto [slot, added] = latest.insert(buckets.home(v, w), static_cast<std::int32_t>(v));
    if (!added) next[v] = *slot;
    *slot = static_cast<std::int32_t>(v);
  }
  return into;
}

/// weld, the staying vertices numbered in order and copied into `out` in parallel. Returns each
/// input vertex's output number.
template <class S>
std::vector<std::int32_t> copyStaying(const Complex<S>& complex,
                                      const std::vector<std::int32_t>& into, Complex<S>& out) {
  const int n = complex.n;
  const std::size_t vertices = complex.vertexCount();
  std::vector<std::int32_t> remap(vertices);
  std::int32_t stayed = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    if (into[v] == static_cast<std::int32_t>(v)) remap[v] = stayed++;
  }
  for (std::size_t v = 0; v < vertices; ++v) remap[v] = remap[into[v]];
  out.vertices.resize(std::size_t(stayed) * n);
  out.vertexCell.resize(std::size_t(stayed), -1);
  parallelFor(
      vertices,
      [&](std::size_t v) {
        if (into[v] != static_cast<std::int32_t>(v)) return;
        const auto x = complex.vertex(v);
        std::copy(x.begin(), x.end(), out.vertices.begin() + std::ptrdiff_t(remap[v]) * n);
        if (!complex.vertexCell.empty()) out.vertexCell[remap[v]] = complex.vertexCell[v];
      },
      4096);
  return remap;
}

/// weld, step 2: remap the simplices into `out`, dropping degenerate ones and duplicates (same
/// vertex set): the first of each vertex set stays, in the input's order.
template <class S>
void remapSimplices(const Complex<S>& complex, const std::vector<std::int32_t>& remap,
                    Complex<S>& out) {
  const auto width = static_cast<std::size_t>(complex.k + 1);
  const std::size_t count = complex.simplexCount();
  std::vector<std::int32_t> sorted(count * width);
  std::vector<std::uint8_t> keep(count, 1);
  parallelFor(
      count,
      [&](std::size_t s) {
        const auto key = sorted.begin() + std::ptrdiff_t(s * width);
        for (std::size_t i = 0; i < width; ++i) key[i] = remap[complex.simplices[s * width + i]];
        std::sort(key, key + std::ptrdiff_t(width));
        if (std::adjacent_find(key, key + std::ptrdiff_t(width)) != key + std::ptrdiff_t(width))
          keep[s] = 0;
      },
      4096);
  markDuplicates(sorted, width, keep);
  // The kept simplices in order, remapped in parallel.
  std::vector<std::size_t> at(count + 1, 0);
  for (std::size_t s = 0; s < count; ++s) at[s + 1] = at[s] + keep[s];
  out.simplices.resize(at.back() * width);
  parallelFor(
      count,
      [&](std::size_t s) {
        if (!keep[s]) return;
        for (std::size_t i = 0; i < width; ++i)
          out.simplices[at[s] * width + i] = remap[complex.simplices[s * width + i]];
      },
      4096);
}

}  // namespace

template <class S>
Complex<S> weld(const Complex<S>& complex, double tolerance) {
  Complex<S> out;
  out.n = complex.n;
  out.k = complex.k;
  const std::vector<std::int32_t> into = mergeTargets(complex, tolerance);
  const std::vector<std::int32_t> remap = copyStaying(complex, into, out);
  remapSimplices(complex, remap, out);
  return out;
}

namespace {

/// The distinct edges of the simplices (by key, ascending), each with the number of simplices
/// on it.
using EdgeCounts = std::vector<std::pair<std::uint64_t, std::int32_t>>;

/// Simplex s of `welded` as its k + 1 vertex numbers.
template <class S>
std::span<const std::int32_t> simplexAt(const Complex<S>& welded, std::size_t s) {
  const auto size = static_cast<std::size_t>(welded.k + 1);
  return std::span<const std::int32_t>(welded.simplices.data() + s * size, size);
}

/// Distinct edges with their simplex counts, and the connected components of the edge graph
/// (isolated vertices are components too).
template <class S>
EdgeCounts countEdges(const Complex<S>& welded, MeshStats& stats) {
  const int k = welded.k;
  const std::size_t vertexCount = welded.vertexCount();
  DisjointSets sets(vertexCount);
  std::vector<std::uint64_t> keys;
  keys.reserve(welded.simplexCount() * std::size_t(k * (k + 1) / 2));
  for (std::size_t s = 0; s < welded.simplexCount(); ++s) {
    const auto v = simplexAt(welded, s);
    for (int a = 0; a <= k; ++a) {
      for (int b = a + 1; b <= k; ++b) {
        keys.push_back(edgeKey(v[a], v[b]));
        sets.unite(v[a], v[b]);
      }
    }
  }
  // Sorted keys, then runs of equal ones (no hash node per edge).
  parallelSort(keys.begin(), keys.end(), std::less<>());
  EdgeCounts edges;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (i == 0 || keys[i] != keys[i - 1])
      edges.emplace_back(keys[i], 1);
    else
      ++edges.back().second;
  }
  stats.edges = static_cast<std::int64_t>(edges.size());
  for (std::size_t v = 0; v < vertexCount; ++v)
    if (sets.find(static_cast<std::int32_t>(v)) == static_cast<std::int32_t>(v)) ++stats.components;
  return edges;
}

/// Polylines (k = 1): open ends (degree 1), branch vertices (degree >= 3), chi = V - E.
void curveTopology(const EdgeCounts& edges, std::size_t vertexCount, MeshStats& stats) {
  std::vector<std::int32_t> degree(vertexCount, 0);
  for (const auto& [key, count] : edges) {
    ++degree[key >> 32];
    ++degree[key & 0xffffffffULL];
  }
  for (std::int32_t d : degree) {
    if (d == 1) ++stats.openEnds;
    if (d >= 3) ++stats.branchVertices;
  }
  stats.eulerCharacteristic = stats.vertices - stats.edges;
}

/// Triangle meshes (k = 2): an edge of one triangle is boundary, of three or more
/// non-manifold; the boundary's loops; chi = V - E + T.
void surfaceTopology(const EdgeCounts& edges, std::size_t vertexCount, std::size_t triangles,
                     MeshStats& stats) {
  stats.triangles = static_cast<std::int64_t>(triangles);
  DisjointSets boundary(vertexCount);
  std::vector<std::uint8_t> onBoundary(vertexCount, 0);
  for (const auto& [key, count] : edges) {
    if (count == 1) {
      ++stats.boundaryEdges;
      const auto a = static_cast<std::int32_t>(key >> 32);
      const auto b = static_cast<std::int32_t>(key & 0xffffffffULL);
      boundary.unite(a, b);
      onBoundary[a] = onBoundary[b] = 1;
    }
    if (count >= 3) ++stats.nonmanifoldEdges;
  }
  for (std::size_t v = 0; v < vertexCount; ++v) {
    const auto i = static_cast<std::int32_t>(v);
    if (onBoundary[v] && boundary.find(i) == i) ++stats.boundaryComponents;
  }
  stats.eulerCharacteristic = stats.vertices - stats.edges + stats.triangles;
}

/// Accuracy: the largest residual at the vertices and the chord error, the distance of each
/// simplex's barycentre to its Newton projection onto M (in S).
template <class S>
void accuracy(const Complex<S>& welded, const System<S>& system, const Projector<S>& project,
              MeshStats& stats) {
  using std::sqrt;
  const int n = welded.n, k = welded.k;
  // Residuals and chord errors per vertex and simplex in parallel, each into its own slot;
  // the maxima are taken afterwards (framework/numeric/parallel.hpp).
  std::vector<S> residual(welded.vertexCount());
  parallelFor(welded.vertexCount(),
              [&](std::size_t v) { residual[v] = system.maxResidual(welded.vertex(v)); });
  S worstResidual = 0;
  for (const S& r : residual) worstResidual = std::max<S>(worstResidual, r);
  stats.maxResidual = toDouble(worstResidual);

  std::vector<S> chord(welded.simplexCount());
  std::vector<std::uint8_t> failed(welded.simplexCount(), 0);
  parallelForBlocks(welded.simplexCount(), [&](std::size_t begin, std::size_t end) {
    std::vector<S> centre(n), projected(n);
    for (std::size_t s = begin; s < end; ++s) {
      std::fill(centre.begin(), centre.end(), S(0));
      for (std::int32_t i : simplexAt(welded, s)) {
        const auto x = welded.vertex(i);
        for (int j = 0; j < n; ++j) centre[j] += x[j];
      }
      for (int j = 0; j < n; ++j) centre[j] /= S(k + 1);
      projected = centre;
      if (!project || !project(projected).converged) {
        failed[s] = 1;
        continue;
      }
      S d2 = 0;
      for (int j = 0; j < n; ++j) d2 += (projected[j] - centre[j]) * (projected[j] - centre[j]);
      chord[s] = sqrt(d2);
    }
  });
  S worstChord = 0;
  for (std::size_t s = 0; s < chord.size(); ++s) {
    if (failed[s])
      ++stats.chordFailures;
    else
      worstChord = std::max<S>(worstChord, chord[s]);
  }
  stats.maxChordError = toDouble(worstChord);
}

/// The Betti numbers and facet counts of `h` into `stats`. For k <= 2 the other topology fields
/// are counted independently, and the Euler characteristics must agree; for k >= 3, beyond
/// docs/contracts.md 4.3, they are taken from h: triangles are the distinct 2-faces, boundary /
/// non-manifold edges count the (k-1)-faces of one / three or more simplices, and chi is the full
/// alternating sum.
void addHomology(const Homology& h, int k, MeshStats& stats) {
  if (k >= 3) {
    stats.triangles = h.faces[2];
    stats.boundaryEdges = h.boundaryFacets;
    stats.nonmanifoldEdges = h.nonmanifoldFacets;
    stats.eulerCharacteristic = h.eulerCharacteristic();
  }
  stats.betti = h.betti;
  stats.bettiZ2 = h.bettiZ2;
  stats.boundaryFacets = h.boundaryFacets;
  stats.nonmanifoldFacets = h.nonmanifoldFacets;
  assert(h.eulerCharacteristic() == stats.eulerCharacteristic);
}

}  // namespace

template <class S>
MeshStats analyse(const Complex<S>& welded, const System<S>& system, const Projector<S>& project) {
  MeshStats stats;
  stats.vertices = static_cast<std::int64_t>(welded.vertexCount());
  // The topology's counting (mostly sequential) beside the accuracy's projections (parallel):
  // both only read the mesh, and they write different fields.
  MeshStats measured;
  TaskBeside topology;
  topology.start([&welded, &stats] {
    const EdgeCounts edges = countEdges(welded, stats);
    if (welded.k == 1) curveTopology(edges, welded.vertexCount(), stats);
    if (welded.k == 2) surfaceTopology(edges, welded.vertexCount(), welded.simplexCount(), stats);
  });
  // The homology in a task of its own, so that it runs beside both (it reads only the mesh).
  Homology h;
  TaskBeside homologyTask;
  homologyTask.start([&welded, &h] { h = homology(welded); });
  accuracy(welded, system, project, measured);
  topology.wait();
  homologyTask.wait();
  stats.maxResidual = measured.maxResidual;
  stats.maxChordError = measured.maxChordError;
  stats.chordFailures = measured.chordFailures;
  addHomology(h, welded.k, stats);
  return stats;
}

template Complex<double> weld(const Complex<double>&, double);
template Complex<Mpfr> weld(const Complex<Mpfr>&, double);
template void dropUnusedVertices(Complex<double>&);
template void dropUnusedVertices(Complex<Mpfr>&);
template MeshStats analyse(const Complex<double>&, const System<double>&, const Projector<double>&);
template MeshStats analyse(const Complex<Mpfr>&, const System<Mpfr>&, const Projector<Mpfr>&);

}  // namespace ndc
