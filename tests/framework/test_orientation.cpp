// Consistent orientation of output meshes (framework/mesh/orientation.hpp): generated
// triangulations of a torus, a sphere-like closed surface and a Möbius band, with seeded random
// flips of their triangles, and closed polylines with reversed segments.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "framework/mesh/orientation.hpp"

using ndc::orientSimplices;

namespace {

/// An a x b grid of quads, each split into two triangles; `twist` glues the last column to the
/// first with the rows reversed (a Möbius band when the rows are not also glued), `wrapRows`
/// glues the last row to the first (a torus with both).
std::vector<std::int32_t> gridSurface(int a, int b, bool wrapRows, bool twist) {
  const auto vertex = [&](int i, int j) {
    if (i == a) {
      i = 0;
      if (twist) j = b - j;
    }
    if (wrapRows && j == b) j = 0;
    return static_cast<std::int32_t>(i * (b + 1) + j);
  };
  std::vector<std::int32_t> t;
  for (int i = 0; i < a; ++i)
    for (int j = 0; j < b; ++j) {
      const std::int32_t p = vertex(i, j), q = vertex(i + 1, j), r = vertex(i + 1, j + 1),
                         s = vertex(i, j + 1);
      t.insert(t.end(), {p, q, r, p, r, s});
    }
  return t;
}

/// Randomly reverses simplices (swapping their last two vertices) and shuffles their order.
void scramble(std::vector<std::int32_t>& simplices, int width, std::mt19937_64& random) {
  std::vector<std::vector<std::int32_t>> list;
  for (std::size_t s = 0; s < simplices.size(); s += width) {
    std::vector<std::int32_t> one(simplices.begin() + s, simplices.begin() + s + width);
    if (random() % 2) std::swap(one[width - 2], one[width - 1]);
    list.push_back(one);
  }
  std::shuffle(list.begin(), list.end(), random);
  simplices.clear();
  for (const auto& one : list) simplices.insert(simplices.end(), one.begin(), one.end());
}

/// Directed edges used more than once (0 on a consistently oriented manifold surface).
int repeatedDirectedEdges(const std::vector<std::int32_t>& t) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
  for (std::size_t s = 0; s < t.size(); s += 3)
    for (int e = 0; e < 3; ++e) ++uses[{t[s + e], t[s + (e + 1) % 3]}];
  int repeated = 0;
  for (const auto& [edge, count] : uses) repeated += count > 1;
  return repeated;
}

}  // namespace

TEST_CASE("orientation: scrambled tori come out consistently oriented", "[analysis][orientation]") {
  std::mt19937_64 random(20261204);
  for (int trial = 0; trial < 20; ++trial) {
    const int a = 3 + static_cast<int>(random() % 6), b = 3 + static_cast<int>(random() % 6);
    std::vector<std::int32_t> t = gridSurface(a, b, true, false);
    scramble(t, 3, random);
    REQUIRE(repeatedDirectedEdges(t) > 0);
    const std::vector<std::int32_t> before = t;
    CHECK(orientSimplices(2, t));
    CHECK(repeatedDirectedEdges(t) == 0);
    // The same triangles, only reordered within.
    for (std::size_t s = 0; s < t.size(); s += 3) {
      std::vector<std::int32_t> x(t.begin() + s, t.begin() + s + 3),
          y(before.begin() + s, before.begin() + s + 3);
      std::sort(x.begin(), x.end());
      std::sort(y.begin(), y.end());
      CHECK(x == y);
    }
  }
}

TEST_CASE("orientation: a Möbius band is found non-orientable, an annulus is not",
          "[analysis][orientation]") {
  std::mt19937_64 random(7);
  for (int trial = 0; trial < 10; ++trial) {
    const int a = 4 + static_cast<int>(random() % 5), b = 2 + static_cast<int>(random() % 3);
    std::vector<std::int32_t> mobius = gridSurface(a, b, false, true);
    scramble(mobius, 3, random);
    CHECK_FALSE(orientSimplices(2, mobius));
    std::vector<std::int32_t> annulus = gridSurface(a, b, false, false);
    scramble(annulus, 3, random);
    CHECK(orientSimplices(2, annulus));
    CHECK(repeatedDirectedEdges(annulus) == 0);
  }
}

TEST_CASE("orientation: closed polylines run one way round", "[analysis][orientation]") {
  std::mt19937_64 random(11);
  for (int trial = 0; trial < 20; ++trial) {
    // Two closed loops of random lengths.
    std::vector<std::int32_t> segments;
    std::int32_t first = 0;
    for (int loop = 0; loop < 2; ++loop) {
      const int length = 3 + static_cast<int>(random() % 10);
      for (int i = 0; i < length; ++i)
        segments.insert(segments.end(), {first + i, first + (i + 1) % length});
      first += length;
    }
    scramble(segments, 2, random);
    CHECK(orientSimplices(1, segments));
    // Each vertex is the head of one segment and the tail of one.
    std::map<std::int32_t, int> heads, tails;
    for (std::size_t s = 0; s < segments.size(); s += 2)
      ++tails[segments[s]], ++heads[segments[s + 1]];
    for (const auto& [v, count] : heads) CHECK(count == 1);
    for (const auto& [v, count] : tails) CHECK(count == 1);
  }
}
