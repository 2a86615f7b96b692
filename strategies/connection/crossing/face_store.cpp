#include "strategies/connection/crossing/face_store.hpp"

#include <algorithm>

#include "framework/numeric/parallel.hpp"

namespace ndc::crossing_detail {

template <class S>
void FaceStore<S>::clear() {
  blocks_.clear();
  chunks_.assign(1, Chunk{});
}

template <class S>
const FaceRecord* FaceStore<S>::find(std::int32_t leaf, std::uint32_t kind) const {
  if (std::size_t(leaf) >= blocks_.size()) return nullptr;
  const Block& b = blocks_[std::size_t(leaf)];
  if (b.count == 0) return nullptr;
  const std::vector<FaceRecord>& records = chunks_[std::size_t(b.chunk)].records;
  const auto first = records.begin() + b.first, last = first + b.count;
  const auto it = std::lower_bound(first, last, kind, byKind);
  return it != last && it->kind == kind ? &*it : nullptr;
}

template <class S>
FaceResult<S> FaceStore<S>::result(std::int32_t leaf, const FaceRecord& r) const {
  std::vector<S> root;
  if (r.root >= 0) {
    const auto& pool = chunks_[std::size_t(blocks_[std::size_t(leaf)].chunk)].roots;
    root.assign(pool.begin() + r.root, pool.begin() + r.root + n_);
  }
  return FaceResult<S>{std::move(root), r.roots,          r.degree,    r.certain,
                       r.proven,        r.withinRounding, r.degenerate};
}

template <class S>
void FaceStore<S>::add(std::int32_t leaf, std::uint32_t kind, const FaceResult<S>& r) {
  if (std::size_t(leaf) >= blocks_.size()) blocks_.resize(std::size_t(leaf) + 1);
  Block& b = blocks_[std::size_t(leaf)];
  Chunk& tail = chunks_.front();
  const auto end = static_cast<std::int64_t>(tail.records.size());
  if (b.count > 0 && (b.chunk != 0 || b.first + b.count != end)) {
    // The leaf's block is elsewhere (a window's chunk, or not last): copy it, with its roots,
    // to the end of the first chunk, where it can grow (through copies: a vector may not
    // insert a range of itself).
    const Chunk& from = chunks_[std::size_t(b.chunk)];
    std::vector<FaceRecord> block(from.records.begin() + b.first,
                                  from.records.begin() + b.first + b.count);
    std::vector<S> roots;
    for (FaceRecord& moved : block) {
      if (moved.root < 0) continue;
      const auto at = from.roots.begin() + moved.root;
      moved.root = static_cast<std::int64_t>(tail.roots.size() + roots.size());
      roots.insert(roots.end(), at, at + n_);
    }
    tail.records.insert(tail.records.end(), block.begin(), block.end());
    tail.roots.insert(tail.roots.end(), roots.begin(), roots.end());
    b.first = end;
    b.chunk = 0;
  } else if (b.count == 0) {
    b.first = end;
    b.chunk = 0;
  }
  const FaceRecord kept = record(kind, r, r.root.empty() ? -1 : std::int64_t(tail.roots.size()));
  tail.roots.insert(tail.roots.end(), r.root.begin(), r.root.end());
  // The block is the last one now: insert in kind order.
  const auto at =
      std::lower_bound(tail.records.begin() + b.first, tail.records.end(), kind, byKind);
  tail.records.insert(at, kept);
  ++b.count;
}

template <class S>
void FaceStore<S>::addBlocks(std::span<const std::int32_t> leaves,
                             FunctionRef<const Solved&(std::size_t)> solved) {
  if (leaves.empty()) return;
  if (blocks_.size() <= std::size_t(leaves.back())) blocks_.resize(std::size_t(leaves.back()) + 1);
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (blocks_[std::size_t(leaves[i])].count == 0) continue;
    for (const auto& [kind, r] : solved(i)) add(leaves[i], kind, r);
  }
  // The fresh leaves' places: records and roots in leaf order.
  const auto chunk = static_cast<std::int32_t>(chunks_.size());
  std::vector<std::int64_t> rootAt(leaves.size(), -1);
  std::int64_t records = 0;
  std::size_t roots = 0;
  std::vector<std::size_t> fresh;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    Block& b = blocks_[std::size_t(leaves[i])];
    const auto& list = solved(i);
    if (b.count > 0 || list.empty()) continue;
    fresh.push_back(i);
    b = Block{chunk, static_cast<std::int32_t>(list.size()), records};
    records += b.count;
    rootAt[i] = static_cast<std::int64_t>(roots);
    for (const auto& entry : list) roots += entry.second.root.size();
  }
  if (fresh.empty()) return;
  Chunk& c = chunks_.emplace_back();
  c.records.resize(std::size_t(records));
  c.roots.resize(roots);
  parallelFor(fresh.size(), [&](std::size_t f) {
    const std::size_t i = fresh[f];
    auto out = c.records.begin() + blocks_[std::size_t(leaves[i])].first;
    std::int64_t root = rootAt[i];
    for (const auto& [kind, r] : solved(i)) {
      *out++ = record(kind, r, r.root.empty() ? -1 : root);
      std::copy(r.root.begin(), r.root.end(), c.roots.begin() + root);
      root += static_cast<std::int64_t>(r.root.size());
    }
  });
}

template class FaceStore<double>;
template class FaceStore<Mpfr>;

}  // namespace ndc::crossing_detail
