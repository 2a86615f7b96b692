// Consistent orientation of a welded mesh by a breadth-first search over shared facets.
#include "framework/core/orientation.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <deque>
#include <unordered_map>
#include <utility>

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

struct KeyHash {
  std::size_t operator()(const std::array<std::int32_t, 2>& k) const {
    return std::hash<std::uint64_t>()((std::uint64_t(std::uint32_t(k[0])) << 32) |
                                      std::uint32_t(k[1]));
  }
};

}  // namespace

bool orientSimplices(int k, std::vector<std::int32_t>& simplices) {
  if (k != 1 && k != 2) return true;
  const int width = k + 1;
  const std::size_t count = simplices.size() / width;
  // Facet -> the simplices on it, with their signs.
  std::unordered_map<std::array<std::int32_t, 2>, std::vector<std::pair<std::size_t, int>>, KeyHash>
      on;
  on.reserve(count * width);
  for (std::size_t s = 0; s < count; ++s)
    for (int i = 0; i < width; ++i) {
      const Facet f = facetsOf(k, &simplices[s * width])[i];
      on[f.key].emplace_back(s, f.sign);
    }
  // Breadth-first per component: flip[s] = -1 when s is to be reversed.
  std::vector<int> flip(count, 0);
  bool orientable = true;
  std::deque<std::size_t> queue;
  for (std::size_t start = 0; start < count; ++start) {
    if (flip[start]) continue;
    flip[start] = 1;
    queue.push_back(start);
    while (!queue.empty()) {
      const std::size_t s = queue.front();
      queue.pop_front();
      for (int i = 0; i < width; ++i) {
        const Facet f = facetsOf(k, &simplices[s * width])[i];
        const auto& sharing = on[f.key];
        if (sharing.size() != 2) continue;  // boundary or non-manifold: nothing to agree with
        const auto& [u, sign] = sharing[0].first == s ? sharing[1] : sharing[0];
        // Opposite induced orientations: flip[s] * f.sign = -flip[u] * sign.
        const int wanted = -flip[s] * f.sign * sign;
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
