// The open-addressing map of cell keys (framework/util/flat_map.hpp) against std::unordered_map
// on generated operation sequences: inserts, lookups and erases (backward shift) of clustered
// keys, 64- and 128-bit, across many growths.
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <unordered_map>
#include <vector>

#include "framework/numeric/grid.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/util/flat_map.hpp"

namespace {

/// Runs `operations` random operations on both maps and checks that they always agree. Keys
/// come from a small range (many collisions of home slots, long probe runs, erases inside
/// them), shifted into the high half for 128-bit keys.
template <class Key>
void agree(std::uint32_t seed, int operations, std::uint64_t range) {
  std::mt19937_64 rng(seed);
  ndc::FlatMap<Key, std::int32_t> flat;
  std::unordered_map<std::uint64_t, std::int32_t> reference;
  const auto keyOf = [](std::uint64_t x) {
    Key key = static_cast<Key>(x);
    if constexpr (sizeof(Key) > 8) key |= static_cast<Key>(x) << 64;
    return key;
  };
  for (int op = 0; op < operations; ++op) {
    const std::uint64_t x = rng() % range;
    const auto value = static_cast<std::int32_t>(rng() % 1000);
    switch (rng() % 3) {
      case 0: {
        const auto [stored, inserted] = flat.insert(keyOf(x), value);
        const auto [it, added] = reference.emplace(x, value);
        REQUIRE(inserted == added);
        REQUIRE(*stored == it->second);
        break;
      }
      case 1:
        REQUIRE(flat.erase(keyOf(x)) == (reference.erase(x) == 1));
        break;
      default: {
        const std::int32_t* found = flat.find(keyOf(x));
        const auto it = reference.find(x);
        REQUIRE((found != nullptr) == (it != reference.end()));
        if (found) REQUIRE(*found == it->second);
      }
    }
    REQUIRE(flat.size() == reference.size());
  }
  // Every key of the range, at the end.
  for (std::uint64_t x = 0; x < range; ++x)
    REQUIRE(flat.contains(keyOf(x)) == (reference.count(x) == 1));
}

}  // namespace

TEST_CASE("flat map: agrees with std::unordered_map on generated operations", "[flat-map]") {
  for (std::uint32_t seed = 0; seed < 8; ++seed) {
    agree<std::uint64_t>(seed, 20000, 64 + 1000 * seed);
    agree<ndc::CellKey>(seed, 20000, 64 + 1000 * seed);
  }
}

TEST_CASE("flat map: reserve, clear and growth keep every entry", "[flat-map]") {
  ndc::FlatMap<ndc::CellKey, std::int32_t> map;
  map.reserve(1000);
  for (std::int32_t i = 0; i < 100000; ++i) REQUIRE(map.insert(ndc::CellKey(i) * 7919, i).second);
  REQUIRE(map.size() == 100000);
  for (std::int32_t i = 0; i < 100000; ++i) REQUIRE(*map.find(ndc::CellKey(i) * 7919) == i);
  REQUIRE_FALSE(map.contains(1));
  map.clear();
  REQUIRE(map.empty());
  REQUIRE(map.find(0) == nullptr);
  REQUIRE_FALSE(map.erase(0));
}

TEST_CASE("flat map: keys inserted concurrently are found, erased and grown like inserted ones",
          "[flat-map][threads]") {
  // Clustered keys (long probe runs, where concurrent claims race for the same slots), on 1, 2
  // and 4 threads (4 oversubscribes a 2-core machine: preemption mid-claim).
  for (int threads : {1, 2, 4}) {
    CAPTURE(threads);
    const std::size_t count = 50000;
    std::vector<ndc::CellKey> keys(count);
    for (std::size_t i = 0; i < count; ++i)
      keys[i] = (ndc::CellKey(i / 64) << 70) | ndc::CellKey(i % 64);
    ndc::FlatMap<ndc::CellKey, std::int32_t> map;
    map.insert(ndc::CellKey(1) << 100, -1);  // an entry from before
    map.reserve(count + 1);
    ndc::withThreads(threads, [&] {
      ndc::parallelFor(count, [&](std::size_t i) {
        map.insertNewConcurrently(keys[i], static_cast<std::int32_t>(i));
      });
    });
    map.addCount(count);
    REQUIRE(map.size() == count + 1);
    bool all = true;
    for (std::size_t i = 0; i < count; ++i) {
      const std::int32_t* value = map.find(keys[i]);
      all = all && value && *value == static_cast<std::int32_t>(i);
    }
    CHECK(all);
    CHECK(*map.find(ndc::CellKey(1) << 100) == -1);
    // Erasing every other key (backward shifts through the concurrently built runs), then
    // growing the map, keeps the rest.
    for (std::size_t i = 0; i < count; i += 2) REQUIRE(map.erase(keys[i]));
    for (std::int32_t i = 0; i < 100000; ++i)
      map.insert((ndc::CellKey(7) << 90) + ndc::CellKey(i), i);
    for (std::size_t i = 0; i < count; ++i) {
      const std::int32_t* value = map.find(keys[i]);
      all =
          all && (i % 2 == 0 ? value == nullptr : value && *value == static_cast<std::int32_t>(i));
    }
    CHECK(all);
    CHECK(map.size() == count / 2 + 1 + 100000);
  }
}
