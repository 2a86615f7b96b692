/// \file flat_map.hpp
/// An open-addressing hash map for integer keys (cell and face keys): one flat array of slots,
/// linear probing, deletion by backward shift. Where std::unordered_map allocates a node per
/// entry and follows a pointer per lookup, this allocates only when it grows, and a lookup
/// reads one or two adjacent slots (docs/performance.md).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace ndc {

/// A 64-bit mix of an integer key of up to 128 bits (splitmix64's finaliser on the folded
/// halves): packed cell indices are far from uniform in their low bits.
template <class Key>
std::uint64_t mixKey(Key key) {
  auto x = static_cast<std::uint64_t>(key);
  if constexpr (sizeof(Key) > 8) x ^= static_cast<std::uint64_t>(key >> 64) * 0x9E3779B97F4A7C15ull;
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  x ^= x >> 31;
  return x;
}

/// Maps integer keys to values of type V. Pointers returned by find stay valid until the next
/// insert or erase.
template <class Key, class V>
class FlatMap {
 public:
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  void clear() {
    slots_.clear();
    used_.clear();
    size_ = 0;
  }

  /// Room for `count` entries without growing.
  void reserve(std::size_t count) {
    std::size_t capacity = 16;
    while (capacity * 3 < count * 4) capacity *= 2;  // load at most 3/4
    if (capacity > slots_.size()) rehash(capacity);
  }

  /// The value of `key`, or nullptr.
  const V* find(Key key) const {
    if (size_ == 0) return nullptr;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = mixKey(key) & mask;; i = (i + 1) & mask) {
      if (!used_[i]) return nullptr;
      if (slots_[i].first == key) return &slots_[i].second;
    }
  }
  V* find(Key key) { return const_cast<V*>(std::as_const(*this).find(key)); }
  bool contains(Key key) const { return find(key) != nullptr; }

  /// Inserts (key, value) when key is new; returns the value stored for key and whether it
  /// was inserted.
  std::pair<V*, bool> insert(Key key, V value) {
    if ((size_ + 1) * 4 > slots_.size() * 3) rehash(slots_.empty() ? 16 : 2 * slots_.size());
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = mixKey(key) & mask;
    for (; used_[i]; i = (i + 1) & mask) {
      if (slots_[i].first == key) return {&slots_[i].second, false};
    }
    used_[i] = 1;
    slots_[i] = {key, std::move(value)};
    ++size_;
    return {&slots_[i].second, true};
  }

  /// Inserts keys known to be new and distinct from several threads at once: the map must
  /// have room for all of them (reserve), nothing else may run on it meanwhile, and the caller
  /// adds their number with `addCount` afterwards. A slot is claimed by an atomic exchange of
  /// its `used` byte, so where a key lands depends on the threads' timing, which no lookup,
  /// insert or erase can tell (the map has no iteration).
  void insertNewConcurrently(Key key, V value) {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = mixKey(key) & mask;; i = (i + 1) & mask) {
      std::atomic_ref<std::uint8_t> used(used_[i]);
      if (used.load(std::memory_order_relaxed) == 0 &&
          used.exchange(1, std::memory_order_acq_rel) == 0) {
        slots_[i] = {key, std::move(value)};
        return;
      }
    }
  }
  /// Counts `count` keys inserted by insertNewConcurrently.
  void addCount(std::size_t count) { size_ += count; }

  /// Removes key if present; returns whether it was.
  bool erase(Key key) {
    if (size_ == 0) return false;
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = mixKey(key) & mask;
    while (used_[i] && slots_[i].first != key) i = (i + 1) & mask;
    if (!used_[i]) return false;
    // Backward shift: move later entries of the probe run into the hole when their home
    // slot does not lie strictly between the hole and them.
    for (std::size_t j = (i + 1) & mask; used_[j]; j = (j + 1) & mask) {
      const std::size_t home = mixKey(slots_[j].first) & mask;
      const bool between = i <= j ? (i < home && home <= j) : (i < home || home <= j);
      if (between) continue;
      slots_[i] = std::move(slots_[j]);
      i = j;
    }
    used_[i] = 0;
    slots_[i] = {};
    --size_;
    return true;
  }

 private:
  void rehash(std::size_t capacity) {
    std::vector<std::pair<Key, V>> old = std::move(slots_);
    std::vector<std::uint8_t> oldUsed = std::move(used_);
    slots_.assign(capacity, {});
    used_.assign(capacity, 0);
    size_ = 0;
    for (std::size_t i = 0; i < old.size(); ++i) {
      if (oldUsed[i]) insert(old[i].first, std::move(old[i].second));
    }
  }

  std::vector<std::pair<Key, V>> slots_;
  std::vector<std::uint8_t> used_;
  std::size_t size_ = 0;
};

}  // namespace ndc
