// The pass over the minimal m-faces. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <cstdlib>
#include <utility>
#include <vector>

namespace ndc::crossing_detail {

template <class S>
std::int64_t AdaptiveCrossing<S>::crossFaces() {
  polygons_.clear();
  rootPoints_.clear();
  unprovenFaces_.clear();
  for (std::vector<std::int32_t>& faces : perLeaf_.unprovenOf) faces.clear();
  unprovenOfEmpty_.clear();
  touchLeaves_.clear();
  std::int64_t degenerate = 0;
  TaskBeside beside;  // a local: an exception out of the walk never leaves the task running
  Window* now = &windows_[0];
  Window* next = &windows_[1];
  std::int32_t from = 0;
  bool ready = false;  // whether `now` holds the window at `from`, solved
  while (true) {
    if (!ready) {
      startWindow(beside, from, *now, nullptr);
      finishWindow(beside);
    }
    if (now->from == now->end) return degenerate;  // every leaf walked and its faces kept
    startWindow(beside, now->end, *next, now);
    degenerate += walkWindow(*now);
    reportProgress(now->end);
    finishWindow(beside);
    std::swap(now, next);
    // An empty next window: the tree ended there when it started (touch leaves may follow).
    ready = now->from < now->end;
    from = now->from;
  }
}

template <class S>
void AdaptiveCrossing<S>::startWindow(TaskBeside& beside, std::int32_t from, Window& w,
                                      const Window* keep) {
  grow();
  w.from = from;
  w.end = std::min(static_cast<std::int32_t>(tree_.size()), from + kWindowLeaves);
  w.leaves.clear();
  w.prior.clear();
  w.priorFacets.clear();
  for (std::int32_t c = from; c < w.end; ++c) {
    if (!tree_.active(c) || perLeaf_.empty[c] == 1) continue;
    w.leaves.push_back(c);
    w.prior.push_back(perLeaf_.empty[c]);
    w.priorFacets.push_back(perLeaf_.facetsMet[c]);
  }
  w.forms = rootFormsOf(w.leaves);
  w.slots.resize(kWindowLeaves);
  beside.start([this, &w, keep] {
    if (keep) keepFaces(*keep);
    // The slots' answers from the window's last use first (they hold the faces' roots).
    parallelFor(std::exchange(w.used, std::size_t(w.end - w.from)),
                [&](std::size_t i) { w.slots[i].clear(); });
    parallelFor(w.leaves.size(), [&](std::size_t i) {
      prefetchLeaf(w.leaves[i], w.prior[i], w.priorFacets[i], *w.forms[i],
                   w.slots[std::size_t(w.leaves[i] - w.from)]);
    });
  });
}

template <class S>
void AdaptiveCrossing<S>::finishWindow(TaskBeside& beside) {
  beside.wait();
  addDeferredLeaves();
}

template <class S>
void AdaptiveCrossing<S>::keepFaces(const Window& w) {
  faces_.addBlocks(
      w.leaves, [&](std::size_t i) -> const auto& {
        return w.slots[std::size_t(w.leaves[i] - w.from)].faces;
      });
}

template <class S>
std::int64_t AdaptiveCrossing<S>::walkWindow(const Window& w) {
  std::int64_t degenerate = 0;
  std::vector<std::int32_t> corner(n_), ci;
  std::array<Occupant, 4> around;
  for (std::int32_t c = w.from; c < w.end; ++c) {
    if (!tree_.active(c)) continue;
    grow();
    const LeafFaces& known = w.slots[std::size_t(c - w.from)];
    if (perLeaf_.empty[c] < 0) perLeaf_.empty[c] = emptyOf(c, known) ? 1 : 0;
    if (perLeaf_.empty[c] == 1) continue;  // no level set between M and M_c meets it
    if (known.facets != kAllFacets) perLeaf_.facetsMet[c] = known.facets;
    const int level = tree_.level(c);
    ci.assign(tree_.index(c).begin(), tree_.index(c).end());
    for (const auto& [f, face] : known.visit) {
      faceAround(ci, f, corner, around);
      degenerate += addFace(known.face(face), around, level, corner, fixedAxes_[f.a]);
    }
  }
  return degenerate;
}

template <class S>
std::int64_t AdaptiveCrossing<S>::addFace(const FaceResult<S>& r, std::array<Occupant, 4>& around,
                                          int level, const std::vector<std::int32_t>& corner,
                                          const std::array<int, 2>& axes) {
  const int quadrants = 1 << k_;
  const bool unproven = !r.proven || r.roots > 1 || std::abs(r.degree) > 1 || r.degenerate;
  const bool singular = !r.certain || std::abs(r.degree) > 1;
  // Roots the face solver could not isolate at its finest face level, or within rounding
  // of the face's boundary: a finer cell has the same trouble (a tangency, or a feature at
  // the scale of the level offset c), so such leaves are not refined.
  const bool stuck = !r.certain || r.withinRounding || r.degenerate;
  for (int q = 0; q < quadrants; ++q) {
    if (around[q].kind != Occ::kLeaf) continue;
    if (stuck) perLeaf_.stuck[around[q].leaf] = 1;
    if (unproven) perLeaf_.unproven[around[q].leaf] = 1;
    if (singular) perLeaf_.singular[around[q].leaf] = 1;
    if (unproven)
      setTrouble(around[q].leaf, r.roots > 0 ? std::span<const S>(r.root)
                                             : std::span<const S>(faceCentre(level, corner, axes)));
  }
  if (r.degree == 0) {
    if (unproven) recordUnproven(around, FaceRef{level, corner, axes});
    return r.degenerate;
  }
  Polygon p;
  for (int q = 0; q < quadrants; ++q) {
    std::int64_t node = 0;
    if (around[q].kind == Occ::kEmpty) {
      // A cell the level set F = c enters where M only touches it: a touch leaf.
      around[q].kind = Occ::kLeaf;
      around[q].leaf = deferTouchLeaf(emptyCellOf(around[q]));
      if (unproven) perLeaf_.unproven[around[q].leaf] = 1;
      if (singular) perLeaf_.singular[around[q].leaf] = 1;
    }
    if (around[q].kind == Occ::kLeaf) {
      node = around[q].leaf;
    } else {
      node = -1 - static_cast<std::int64_t>(around[q].key);
      p.outside = true;
    }
    if (p.size > 0 && p.node[p.size - 1] == node) continue;
    p.node[p.size++] = node;
  }
  if (p.size > 1 && p.node[p.size - 1] == p.node[0]) --p.size;
  if (unproven) recordUnproven(around, FaceRef{level, corner, axes});
  p.root = static_cast<std::int32_t>(rootPoints_.size() / n_);
  rootPoints_.insert(rootPoints_.end(), r.root.begin(), r.root.end());
  for (int copy = 0; copy < std::abs(r.degree); ++copy) polygons_.push_back(p);
  return r.degenerate;
}

template <class S>
std::int32_t AdaptiveCrossing<S>::deferTouchLeaf(const EmptyCell& cell) {
  const auto leaf = static_cast<std::int32_t>(leafCount());
  deferred_.push_back(cell);
  touchLeaves_[cell] = leaf;
  grow();
  return leaf;
}

template <class S>
void AdaptiveCrossing<S>::addDeferredLeaves() {
  std::vector<std::int32_t> index(n_);
  for (const EmptyCell& cell : deferred_) {
    tree_.grid(cell.level).unpack(cell.key, index);
    tree_.addLeaf(cell.level, index, false);
  }
  deferred_.clear();
}

template <class S>
std::size_t AdaptiveCrossing<S>::leafCount() const {
  return tree_.size() + deferred_.size();
}

template <class S>
std::vector<S> AdaptiveCrossing<S>::faceCentre(int level, const std::vector<std::int32_t>& corner,
                                               const std::array<int, 2>& axes) const {
  std::vector<S> centre(n_);
  const Grid& g = tree_.grid(level);
  for (int j = 0; j < n_; ++j) {
    const bool fixed = j == axes[0] || (k_ == 2 && j == axes[1]);
    centre[j] = domain_.lo[j] + S((corner[j] + (fixed ? 0.0 : 0.5)) * g.cellWidth(j));
  }
  return centre;
}

template <class S>
void AdaptiveCrossing<S>::recordUnproven(const std::array<Occupant, 4>& around,
                                         const FaceRef& face) {
  const auto f = static_cast<std::int32_t>(unprovenFaces_.size());
  for (int q = 0; q < (1 << k_); ++q) {
    if (around[q].kind == Occ::kLeaf) {
      grow();
      perLeaf_.unprovenOf[around[q].leaf].push_back(f);
    } else if (around[q].kind == Occ::kEmpty) {
      unprovenOfEmpty_[emptyCellOf(around[q])].push_back(f);
    }
  }
  unprovenFaces_.push_back(face);
}

template <class S>
void AdaptiveCrossing<S>::setTrouble(std::int32_t leaf, std::span<const S> point) {
  grow();
  if (perLeaf_.hasTrouble[leaf]) return;
  perLeaf_.hasTrouble[leaf] = 1;
  std::copy(point.begin(), point.end(), perLeaf_.trouble.begin() + std::ptrdiff_t(leaf) * n_);
}

template <class S>
void AdaptiveCrossing<S>::faceTrouble(std::int32_t leaf, int a, bool upper) {
  const Box<S> box = leafBox(leaf);
  std::vector<S> centre(n_);
  for (int j = 0; j < n_; ++j) centre[j] = (box.lo[j] + box.hi[j]) / 2;
  centre[a] = upper ? box.hi[a] : box.lo[a];
  setTrouble(leaf, centre);
}

template <class S>
void AdaptiveCrossing<S>::reportProgress(std::int32_t walked) {
  if (!in_.progress) return;
  // The share of the leaves the round started with (touch leaves join on the way), below 100 %
  // (the pipeline ends the stage).
  const double leaves = static_cast<double>(std::max<std::size_t>(progressLeaves_, 1));
  in_.progress(progressLabel_.c_str(), std::min(0.99, static_cast<double>(walked) / leaves));
}

template <class S>
void AdaptiveCrossing<S>::grow() {
  perLeaf_.grow(leafCount(), n_);
}

}  // namespace ndc::crossing_detail
