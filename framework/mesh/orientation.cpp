// Consistent orientation of a welded mesh by a breadth-first search over shared facets.
#include "framework/mesh/orientation.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "framework/numeric/parallel.hpp"

namespace ndc {

namespace {

/// A facet of a simplex: its vertices sorted (one for segments, two for triangles), with the
/// orientation the simplex induces on it (+1 or -1).
struct Facet {
  std::array<std::int32_t, 2> key;
  int sign;
};

/// The k + 1 facets of simplex s, with induced signs: a segment (a, b) gives -a and +b; a
/// triangle (a, b, c) gives its cyclic edges a->b, b->c, c->a, each +1 when it runs from the
/// smaller vertex number to the larger.
std::array<Facet, 3> facetsOf(int k, const std::int32_t* s) {
  std::array<Facet, 3> f{};
  if (k == 1) {
    f[0] = {{s[0], -1}, -1};
    f[1] = {{s[1], -1}, +1};
    return f;
  }
  for (int e = 0; e < 3; ++e) {
    const std::int32_t a = s[e], b = s[(e + 1) % 3];
    f[e] = {{std::min(a, b), std::max(a, b)}, a < b ? +1 : -1};
  }
  return f;
}

}  // namespace

/// A facet of a simplex as one sortable record: the facet's key packed into 64 bits, the
/// simplex, which of its facets it is, and the sign it induces.
struct FacetEntry {
  std::uint64_t key;
  std::uint32_t simplex;
  std::int32_t facet;
  int sign;
};

namespace {

/// `entries` (made in (simplex, facet) order) sorted by (key, simplex, facet), a total order
/// ((key, simplex) is unique once degenerate facets are welded away, and the facet number breaks
/// the tie otherwise): a counting sort by the key's first vertex, which keeps the (simplex,
/// facet) order within a vertex, then each vertex's few entries by the whole key (a stable
/// insertion sort). Linear in the entries and vertices, where a comparison sort of the records
/// took most of the orientation's time.
std::vector<FacetEntry> sortedByKey(const std::vector<FacetEntry>& entries) {
  std::uint64_t vertices = 0;
  for (const FacetEntry& e : entries) vertices = std::max(vertices, (e.key >> 32) + 1);
  std::vector<std::size_t> start(vertices + 1, 0);
  for (const FacetEntry& e : entries) ++start[(e.key >> 32) + 1];
  for (std::size_t v = 0; v < vertices; ++v) start[v + 1] += start[v];
  std::vector<FacetEntry> sorted(entries.size());
  std::vector<std::size_t> next(start.begin(), start.end() - 1);
  for (const FacetEntry& e : entries) sorted[next[e.key >> 32]++] = e;
  parallelFor(
      vertices,
      [&](std::size_t v) {
        for (std::size_t i = start[v] + 1; i < start[v + 1]; ++i) {
          const FacetEntry e = sorted[i];
          std::size_t j = i;
          for (; j > start[v] && sorted[j - 1].key > e.key; --j) sorted[j] = sorted[j - 1];
          sorted[j] = e;
        }
      },
      4096);
  return sorted;
}

}  // namespace

bool orientSimplices(int k, std::vector<std::int32_t>& simplices) {
  if (k != 1 && k != 2) return true;
  const int width = k + 1;
  const std::size_t count = simplices.size() / width;
  // Facet -> the simplices on it: the facets of all simplices sorted by key (then simplex),
  // so that those on one facet are adjacent (no hash node or vector per facet).
  std::vector<FacetEntry> entries(count * width);
  parallelFor(
      count,
      [&](std::size_t s) {
        const auto facets = facetsOf(k, &simplices[s * width]);
        for (int i = 0; i < width; ++i) {
          const std::uint64_t key = (std::uint64_t(std::uint32_t(facets[i].key[0])) << 32) |
                                    std::uint32_t(facets[i].key[1]);
          entries[s * width + i] = {key, static_cast<std::uint32_t>(s), i, facets[i].sign};
        }
      },
      4096);
  entries = sortedByKey(entries);
  // For each facet i of simplex s: the entry of the other simplex on it when exactly two
  // simplices share it, else -1 (boundary or non-manifold: nothing to agree with).
  // Each pair is found from its first entry, so the entries are looked at in parallel.
  std::vector<std::int64_t> across(count * width, -1);
  const auto sameKey = [&](std::size_t a, std::size_t b) {
    return entries[a].key == entries[b].key;
  };
  parallelFor(
      entries.size(),
      [&](std::size_t b) {
        if (b > 0 && sameKey(b - 1, b)) return;  // not the first of its facet
        if (b + 1 >= entries.size() || !sameKey(b, b + 1)) return;
        if (b + 2 < entries.size() && sameKey(b, b + 2)) return;  // more than two
        across[std::size_t(entries[b].simplex) * width + entries[b].facet] = std::int64_t(b + 1);
        across[std::size_t(entries[b + 1].simplex) * width + entries[b + 1].facet] =
            std::int64_t(b);
      },
      4096);
  // Breadth-first per component: flip[s] = -1 when s is to be reversed.
  std::vector<int> flip(count, 0);
  bool orientable = true;
  std::vector<std::size_t> queue;
  queue.reserve(count);
  for (std::size_t start = 0; start < count; ++start) {
    if (flip[start]) continue;
    flip[start] = 1;
    queue.assign(1, start);
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t s = queue[head];
      const auto facets = facetsOf(k, &simplices[s * width]);
      for (int i = 0; i < width; ++i) {
        const std::int64_t other = across[s * width + i];
        if (other < 0) continue;
        const std::size_t u = entries[std::size_t(other)].simplex;
        const int sign = entries[std::size_t(other)].sign;
        // Opposite induced orientations: flip[s] * f.sign = -flip[u] * sign.
        const int wanted = -flip[s] * facets[i].sign * sign;
        if (!flip[u]) {
          flip[u] = wanted;
          queue.push_back(u);
        } else if (flip[u] != wanted) {
          orientable = false;
        }
      }
    }
  }
  for (std::size_t s = 0; s < count; ++s)
    if (flip[s] < 0) std::swap(simplices[s * width + k - 1], simplices[s * width + k]);
  return orientable;
}

}  // namespace ndc
