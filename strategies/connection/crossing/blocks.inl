// Blocks of 2^n leaves certified together. Included only by adaptive_crossing_{double,mpfr}.cpp.
// See docs/certificate.md, "Blocks".
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <numeric>
#include <vector>

#include "strategies/connection/crossing/domain_boundary.hpp"

namespace ndc::crossing_detail {

template <class S>
bool AdaptiveCrossing<S>::tangentToGridPlane(std::int32_t c,
                                             std::vector<signed char>& faceMemo) const {
  // Its unproven faces: M tangent to an m-face's plane gives two crossings there closer than
  // any refinement separates. An m-face is shared by 2^k leaves: probed once (faceMemo).
  for (const std::int32_t f : perLeaf_.unprovenOf[c]) {
    if (faceMemo[f] >= 0) {
      if (faceMemo[f]) return true;
      continue;
    }
    const FaceRef& face = unprovenFaces_[f];
    DomainStratum<S> stratum;
    stratum.box = cellBox(tree_.grid(face.level), domain_, face.corner);
    for (int j = 0; j < n_; ++j) {
      if (j == face.axes[0] || (k_ == 2 && j == face.axes[1])) {
        stratum.fixed.push_back(j);
        stratum.box.hi[j] = stratum.box.lo[j];
      } else {
        stratum.free.push_back(j);
      }
    }
    faceMemo[f] = tangentToFace(in_.system, stratum) ? 1 : 0;
    if (faceMemo[f]) return true;
  }
  return perLeaf_.failure[c] == Failure::kFaceGraph && tangentToFacetPlane(c);
}

template <class S>
bool AdaptiveCrossing<S>::tangentToFacetPlane(std::int32_t c) const {
  // M tangent to a facet's hyperplane (a sphere touching it, a circle of a torus lying in it)
  // fails the face graph test at every level. Only the facets M_c may meet (their graph test
  // is the one that failed).
  const Box<S> box = leafBox(c);
  for (int a = 0; a < n_; ++a)
    for (int side = 0; side < 2; ++side) {
      if (!facetMet(perLeaf_.facetsMet[c], a, side)) continue;
      DomainStratum<S> stratum{{a}, freeAxes(a), box};
      stratum.box.lo[a] = stratum.box.hi[a] = side ? box.hi[a] : box.lo[a];
      if (tangentToFace(in_.system, stratum)) return true;
    }
  return false;
}

template <class S>
void AdaptiveCrossing<S>::mergeBlocks(const Incidence& incident,
                                      const std::vector<std::int32_t>& leaves,
                                      const std::vector<const RootForms*>& forms) {
  blocks_.clear(), blockLo_.clear(), blockLevel_.clear(), blockSaved_.clear();
  blockEmpties_.clear();
  // certify grew the per-leaf table to every leaf of the tree.
  std::fill(perLeaf_.block.begin(), perLeaf_.block.end(), -1);
  // A block has 2^n regions, each looked up: none past kMaxBlockDimension.
  if (n_ > kMaxBlockDimension) return;
  // The leaves that try blocks, with their root forms: not a leaf whose own graph test fails
  // (the graph test on a block around it would fail too, on a wider box with wider Jacobian
  // enclosures; only refinement can help), nor one M may touch the domain's boundary in
  // (a block proves nothing there), nor one that refinement will still try unless M is tangent
  // to one of its grid planes (tangentToGridPlane): where M only comes near a grid plane, the
  // next level proves it, and a block of 2^n regions costs more than the refinement (the 2-sphere
  // in R^9 at depth 3: 12.0 s with blocks tried everywhere, 89 % of it in blocks that failed;
  // docs/certificate.md, "Blocks").
  std::vector<std::int32_t> trying;
  std::vector<const RootForms*> tryingForms;
  std::vector<signed char> faceMemo(unprovenFaces_.size(), -1);
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const Failure f = perLeaf_.failure[leaves[i]];
    if (f == Failure::kNone || f == Failure::kGraph || f == Failure::kBoundary) continue;
    if (!blocksEverywhere_ && refinable(leaves[i]) && !tangentToGridPlane(leaves[i], faceMemo))
      continue;
    trying.push_back(leaves[i]);
    tryingForms.push_back(forms[i]);
  }
  const std::vector<std::vector<std::int32_t>> clusters = blockClusters(trying);
  std::vector<BlockWork> work(clusters.size(), BlockWork{{}, {}, graphTest_, {}});
  parallelFor(clusters.size(), [&](std::size_t k) {
    for (const std::int32_t i : clusters[k]) {
      const std::int32_t c = trying[i];
      if (perLeaf_.block[c] >= 0) continue;  // in a block of an earlier leaf of the cluster
      blocksOf(c, *tryingForms[i], incident, work[k]);
    }
  });
  bool tentative = false;
  for (const NewBlock& b : orderedBlocks(work)) {
    for (std::int32_t c : b.members) perLeaf_.block[c] = static_cast<std::int32_t>(blocks_.size());
    blocks_.push_back(b.members);
    blockLo_.push_back(b.lo);
    blockLevel_.push_back(b.level);
    blockEmpties_.push_back(b.empties);
    blockSaved_.push_back(b.saved);
    tentative = tentative || b.tentative;
  }
  if (tentative) verifyBlocks(incident);
}

template <class S>
void AdaptiveCrossing<S>::blocksOf(std::int32_t c, const RootForms& rf, const Incidence& incident,
                                   BlockWork& w) {
  for (const std::vector<std::int32_t>& lo : blockCandidates(c)) {
    if (tryBlock(c, lo, incident, false, rf, w)) return;
  }
  for (const std::vector<std::int32_t>& lo : latticeBlocks(c)) {
    if (tryBlock(c, lo, incident, true, rf, w)) return;
  }
}

template <class S>
auto AdaptiveCrossing<S>::orderedBlocks(std::vector<BlockWork>& work) -> std::vector<NewBlock> {
  std::vector<NewBlock> all;
  for (BlockWork& w : work) {
    for (NewBlock& b : w.made) all.push_back(std::move(b));
  }
  std::sort(all.begin(), all.end(),
            [](const NewBlock& a, const NewBlock& b) { return a.leaf < b.leaf; });
  return all;
}

template <class S>
std::vector<std::vector<std::int32_t>> AdaptiveCrossing<S>::blockClusters(
    const std::vector<std::int32_t>& trying) const {
  const auto count = static_cast<std::int32_t>(trying.size());
  // By level, then along the axis where the leaves spread most (a curve of tangency lies in
  // a grid plane): the leaves near one are a run of this order.
  const int axis = spreadAxis(trying);
  std::vector<std::int32_t> order(static_cast<std::size_t>(count));
  std::iota(order.begin(), order.end(), 0);
  const auto key = [&](std::int32_t i) {
    return std::pair{tree_.level(trying[i]), tree_.index(trying[i])[axis]};
  };
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return std::pair{key(a), a} < std::pair{key(b), b};
  });
  UnionFind sets{std::vector<int>(static_cast<std::size_t>(count))};
  std::iota(sets.parent.begin(), sets.parent.end(), 0);
  for (std::size_t x = 0; x < order.size(); ++x) {
    const auto a = tree_.index(trying[order[x]]);
    for (std::size_t y = x + 1; y < order.size(); ++y) {
      const auto [level, first] = key(order[y]);
      if (level != key(order[x]).first || first > a[axis] + 2) break;
      const auto b = tree_.index(trying[order[y]]);
      bool near = true;
      for (int j = 0; j < n_ && near; ++j) near = std::abs(a[j] - b[j]) <= 2;
      if (near) sets.unite(order[x], order[y]);
    }
  }
  std::vector<std::vector<std::int32_t>> clusters;
  std::vector<std::int32_t> clusterOf(static_cast<std::size_t>(count), -1);
  for (std::int32_t i = 0; i < count; ++i) {
    std::int32_t& k = clusterOf[sets.find(i)];
    if (k < 0) {
      k = static_cast<std::int32_t>(clusters.size());
      clusters.emplace_back();
    }
    clusters[k].push_back(i);
  }
  return clusters;
}

template <class S>
int AdaptiveCrossing<S>::spreadAxis(const std::vector<std::int32_t>& leaves) const {
  int best = 0;
  std::size_t most = 0;
  std::vector<std::pair<int, std::int32_t>> at(leaves.size());
  for (int j = 0; j < n_; ++j) {
    for (std::size_t i = 0; i < leaves.size(); ++i)
      at[i] = {tree_.level(leaves[i]), tree_.index(leaves[i])[j]};
    std::sort(at.begin(), at.end());
    const auto distinct = static_cast<std::size_t>(std::unique(at.begin(), at.end()) - at.begin());
    if (distinct > most) best = j, most = distinct;
  }
  return best;
}

template <class S>
std::vector<std::vector<std::int32_t>> AdaptiveCrossing<S>::blockCandidates(std::int32_t c) const {
  constexpr std::size_t kBlockTries = 16;
  const auto ci = tree_.index(c);
  const Box<S> box = leafBox(c);
  std::uint32_t below = 0;  // bit j: the preferred block extends below the leaf along j
  for (int j = 0; j < n_; ++j) {
    const S t = perLeaf_.hasTrouble[c] ? perLeaf_.trouble[std::size_t(c) * n_ + j] : box.lo[j];
    if (t < (box.lo[j] + box.hi[j]) / 2) below |= 1u << j;
  }
  std::vector<std::uint32_t> flips(std::size_t{1} << n_);
  std::iota(flips.begin(), flips.end(), 0u);
  std::stable_sort(flips.begin(), flips.end(), [](std::uint32_t a, std::uint32_t b) {
    return std::popcount(a) < std::popcount(b);
  });
  std::vector<std::vector<std::int32_t>> out;
  for (std::size_t t = 0; t < std::min(kBlockTries, flips.size()); ++t) {
    std::vector<std::int32_t> lo(ci.begin(), ci.end());
    for (int j = 0; j < n_; ++j) lo[j] -= static_cast<std::int32_t>(((below ^ flips[t]) >> j) & 1);
    out.push_back(std::move(lo));
  }
  return out;
}

template <class S>
std::vector<std::vector<std::int32_t>> AdaptiveCrossing<S>::latticeBlocks(std::int32_t c) const {
  const int level = tree_.level(c);
  const auto ci = tree_.index(c);
  // (axis, plane index at this level) pairs common to every unproven face.
  std::vector<std::pair<int, std::int64_t>> common;
  bool first = true;
  for (std::int32_t f : perLeaf_.unprovenOf[c]) {
    const FaceRef& face = unprovenFaces_[f];
    const int shift = face.level - level;
    if (shift < 0) return {};
    std::vector<std::pair<int, std::int64_t>> planes;
    for (int t = 0; t < k_; ++t) {
      const int j = face.axes[t];
      const std::int64_t x = face.corner[j];
      if ((x & ((std::int64_t{1} << shift) - 1)) != 0) continue;
      const std::int64_t p = x >> shift;
      if (p == ci[j] || p == ci[j] + 1) planes.emplace_back(j, p);
    }
    if (first)
      common = planes;
    else
      std::erase_if(common, [&](const auto& q) {
        return std::find(planes.begin(), planes.end(), q) == planes.end();
      });
    first = false;
  }
  std::vector<std::vector<std::int32_t>> blocks;
  for (const auto& [axis, plane] : common) {
    std::vector<std::int32_t> lo(n_);
    for (int j = 0; j < n_; ++j) lo[j] = ci[j] & ~std::int32_t{1};
    lo[axis] = static_cast<std::int32_t>(plane - 1);
    blocks.push_back(std::move(lo));
  }
  return blocks;
}

template <class S>
bool AdaptiveCrossing<S>::tryBlock(std::int32_t c, const std::vector<std::int32_t>& lo,
                                   const Incidence& incident, bool tentative, const RootForms& rf,
                                   BlockWork& w) {
  // Without dense forms (quadrics from R^12 on) no block: its 2^n lookups and evaluations cost
  // more than they prove (the circle in R^12 at depth 3: 0.23 s without blocks, 0.97 s with,
  // certified either way).
  if (!dense_) return false;
  const int level = tree_.level(c);
  std::vector<std::int32_t> members;
  std::vector<EmptyCell> empties;
  if (!blockMembers(level, lo, members, empties)) return false;
  // Every unproven face next to the block's regions lies inside it (tentative: or inside
  // one face of its box, for verifyBlocks to check the leaves across).
  const auto within = [&](const std::vector<std::int32_t>& faces, bool relaxed) {
    return std::all_of(faces.begin(), faces.end(), [&](std::int32_t f) {
      return inside(unprovenFaces_[f], level, lo) ||
             (relaxed && onOneBlockFace(unprovenFaces_[f], level, lo));
    });
  };
  for (std::int32_t c : members) {
    if (!within(perLeaf_.unprovenOf[c], tentative)) return false;
  }
  for (const EmptyCell& e : empties) {
    const std::vector<std::int32_t>* faces = unprovenOfEmpty_.find(e);
    if (faces && !within(*faces, tentative)) return false;
  }
  // The link: now, or (tentative) once the neighbour blocks exist, in verifyBlocks.
  std::vector<Polygon> link;
  std::vector<std::int32_t> ps;
  if (!tentative &&
      (!blockLink(members, incident, link, ps) || !simpleLink(k_, members.front(), link, ps)))
    return false;
  // The graph tests on the block's box.
  std::vector<std::int32_t> hi(lo);
  for (std::int32_t& i : hi) ++i;
  Box<S> box = cellBox(tree_.grid(level), domain_, lo);
  box.hi = cellBox(tree_.grid(level), domain_, hi).hi;
  if (!evaluatedBlockGraphs(box, w)) {
    // The Bernstein hulls where evaluation does not prove them.
    w.patches.resize(m_);
    for (int i = 0; i < m_; ++i) (*rf.forms)[i].restrictInto(box, w.patches[i]);
    if (!graphOf(w.patches, rf.margins, w.jacobian, w.test) && !intervalEmpty(box, true))
      return false;
    // k = 2: a face of the block's box that fails as a whole: a tentative block may prove it
    // leaf face by leaf face (subFacesGraph).
    const auto failing = k_ == 2
                             ? failingFacesOf(w.patches, rf.margins, tentative, w.jacobian, w.test)
                             : std::vector<std::pair<int, bool>>{};
    for (const auto& [a, upper] : failing) {
      if (!tentative || !subFacesGraph(level, lo, members, a, upper, rf, w)) return false;
    }
  }
  // A block proves nothing about the domain's boundary: its members must each.
  for (std::int32_t d : members) {
    std::vector<Bernstein<S>> own;
    LeafTests t{leafScratch(own), {}, graphTest_, false, -1, false, {}};
    if (!boundaryTransverse(d, rf, t, false)) return false;
  }
  // The members are taken (perLeaf_.block >= 0 until mergeBlocks numbers the block).
  NewBlock b{c, level, tentative, lo, std::move(members), std::move(empties), {}};
  for (std::int32_t d : b.members) {
    perLeaf_.block[d] = 0;
    b.saved.push_back(perLeaf_.failure[d]);
    perLeaf_.failure[d] = Failure::kNone;
  }
  w.made.push_back(std::move(b));
  return true;
}

template <class S>
bool AdaptiveCrossing<S>::evaluatedBlockGraphs(const Box<S>& box, BlockWork& w) const {
  if (!byEvaluation_) return false;
  bool excluded = false;
  if (!evaluatedJacobian(box, w.jacobian, excluded)) return false;
  if (excluded) return true;  // M_c misses the box: nothing to test
  const std::span<const Interval<S>> whole(w.jacobian);
  std::vector<int> all(n_);
  std::iota(all.begin(), all.end(), 0);
  if (!w.test.graph(whole, all)) return false;
  // J over the box holds J over each of its facets: the facets' graph tests (k = 2) too.
  for (int a = 0; k_ == 2 && a < n_; ++a) {
    if (!w.test.graph(whole, freeAxes(a))) return false;
  }
  return true;
}

template <class S>
bool AdaptiveCrossing<S>::blockMembers(int level, const std::vector<std::int32_t>& lo,
                                       std::vector<std::int32_t>& members,
                                       std::vector<EmptyCell>& empties) const {
  const std::int64_t top = tree_.grid(level).cellsPerAxis();
  const int patchLevel = in_.problem.roots.empty() ? 0 : in_.problem.rootLevel;
  for (int j = 0; j < n_; ++j) {
    if (lo[j] < 0 || lo[j] + 2 > top) return false;
    if ((lo[j] >> (level - patchLevel)) != ((lo[j] + 1) >> (level - patchLevel))) return false;
  }
  std::vector<std::int32_t> position(n_);
  for (std::uint32_t corner = 0; corner < (1u << n_); ++corner) {
    for (int j = 0; j < n_; ++j) position[j] = lo[j] + static_cast<std::int32_t>((corner >> j) & 1);
    const Occupant o = tree_.find(level, position);
    // A cell the bounding excluded: M_c does not enter it (it would be a touch leaf).
    if (o.kind == Occ::kEmpty) {
      if (std::find(empties.begin(), empties.end(), emptyCellOf(o)) == empties.end())
        empties.push_back(emptyCellOf(o));
      continue;
    }
    if (o.kind != Occ::kLeaf || tree_.level(o.leaf) != level || !tree_.active(o.leaf) ||
        perLeaf_.block[o.leaf] >= 0)
      return false;
    members.push_back(o.leaf);
  }
  return !members.empty();
}

template <class S>
bool AdaptiveCrossing<S>::blockLink(const std::vector<std::int32_t>& members,
                                    const Incidence& incident, std::vector<Polygon>& link,
                                    std::vector<std::int32_t>& ps) const {
  for (std::int32_t p : blockPolygons(members, incident)) {
    const Polygon q = collapsed(polygons_[p], [&](std::int64_t node) {
      return std::find(members.begin(), members.end(), node) != members.end() ? members.front()
                                                                              : node;
    });
    if (q.size < (k_ == 1 ? 2 : 3)) continue;  // inside the block
    if (std::count(q.node.begin(), q.node.begin() + q.size, members.front()) != 1) return false;
    ps.push_back(static_cast<std::int32_t>(link.size()));
    link.push_back(q);
  }
  return true;
}

template <class S>
bool AdaptiveCrossing<S>::subFacesGraph(int level, const std::vector<std::int32_t>& lo,
                                        const std::vector<std::int32_t>& members, int a, bool upper,
                                        const RootForms& rf, BlockWork& w) {
  const std::vector<int> axes = freeAxes(a);
  for (std::int32_t c : members) {
    if (tree_.index(c)[a] != (upper ? lo[a] + 1 : lo[a])) continue;
    for (std::int32_t f : perLeaf_.unprovenOf[c]) {
      bool up = false;
      if (blockFaceAxis(unprovenFaces_[f], level, lo, up) == a && up == upper) return false;
    }
    bool band = false;
    restrictLeaf(c, rf, w.patches, band);
    perLeaf_.bandEmpty[c] = band;  // c is this task's (mergeBlocks)
    if (!faceGraphOf(w.patches, rf.margins, a, upper, axes, w.jacobian, w.test)) return false;
  }
  return true;
}

template <class S>
int AdaptiveCrossing<S>::blockFaceAxis(const FaceRef& face, int level,
                                       const std::vector<std::int32_t>& lo, bool& upper) const {
  const std::int64_t scale = std::int64_t{1} << (face.level - level);
  int axis = -1;
  for (int j = 0; j < n_; ++j) {
    const std::int64_t a = lo[j] * scale, b = (lo[j] + 2) * scale, x = face.corner[j];
    const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
    if (fixed && (x == a || x == b)) {
      if (axis >= 0) return -1;  // on an edge of the block's box
      axis = j;
      upper = x == b;
      continue;
    }
    if (fixed ? (x <= a || x >= b) : (x < a || x + 1 > b)) return -1;
  }
  return axis;
}

template <class S>
bool AdaptiveCrossing<S>::onOneBlockFace(const FaceRef& face, int level,
                                         const std::vector<std::int32_t>& lo) const {
  bool upper = false;
  return blockFaceAxis(face, level, lo, upper) >= 0;
}

template <class S>
bool AdaptiveCrossing<S>::inside(const FaceRef& face, int level,
                                 const std::vector<std::int32_t>& lo) const {
  const std::int64_t scale = std::int64_t{1} << (face.level - level);
  for (int j = 0; j < n_; ++j) {
    const std::int64_t a = lo[j] * scale, b = (lo[j] + 2) * scale, x = face.corner[j];
    const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
    if (fixed ? (x <= a || x >= b) : (x < a || x + 1 > b)) return false;
  }
  return true;
}

template <class S>
void AdaptiveCrossing<S>::verifyBlocks(const Incidence& incident) {
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      if (blocks_[b].empty() || blockStands(b, incident)) continue;
      for (std::size_t i = 0; i < blocks_[b].size(); ++i) {
        perLeaf_.block[blocks_[b][i]] = -1;
        perLeaf_.failure[blocks_[b][i]] = blockSaved_[b][i];
      }
      blocks_[b].clear();
      changed = true;
    }
  }
}

template <class S>
bool AdaptiveCrossing<S>::blockStands(std::size_t b, const Incidence& incident) const {
  const int level = blockLevel_[b];
  const std::vector<std::int32_t>& lo = blockLo_[b];
  const auto stands = [&](const std::vector<std::int32_t>& faces) {
    return std::all_of(faces.begin(), faces.end(), [&](std::int32_t f) {
      return inside(unprovenFaces_[f], level, lo) || sharedBlockFace(unprovenFaces_[f], level, lo);
    });
  };
  for (std::int32_t c : blocks_[b]) {
    if (!stands(perLeaf_.unprovenOf[c])) return false;
  }
  for (const EmptyCell& e : blockEmpties_[b]) {
    const std::vector<std::int32_t>* faces = unprovenOfEmpty_.find(e);
    if (faces && !stands(*faces)) return false;
  }
  std::vector<Polygon> link;
  std::vector<std::int32_t> ps;
  const std::int64_t front = blocks_[b].front();
  for (std::int32_t p : blockPolygons(blocks_[b], incident)) {
    const Polygon q = collapsed(polygons_[p], [&](std::int64_t node) { return blockNode(node); });
    if (q.size < (k_ == 1 ? 2 : 3)) continue;  // inside the block, or between two blocks
    if (std::count(q.node.begin(), q.node.begin() + q.size, front) != 1) return false;
    ps.push_back(static_cast<std::int32_t>(link.size()));
    link.push_back(q);
  }
  return simpleLink(k_, front, link, ps);
}

template <class S>
std::vector<std::int32_t> AdaptiveCrossing<S>::blockPolygons(
    const std::vector<std::int32_t>& members, const Incidence& incident) {
  std::vector<std::int32_t> around;
  for (std::int32_t c : members)
    around.insert(around.end(), incident[c].begin(), incident[c].end());
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  return around;
}

template <class S>
bool AdaptiveCrossing<S>::sharedBlockFace(const FaceRef& face, int level,
                                          const std::vector<std::int32_t>& lo) const {
  const int shift = face.level - level;
  const std::int64_t scale = std::int64_t{1} << shift;
  bool upper = false;
  const int axis = blockFaceAxis(face, level, lo, upper);
  if (axis < 0) return false;
  // The leaves across: one index along the axis, one or two along the other fixed axis.
  std::vector<std::int32_t> across(n_);
  int other = -1;
  for (int j = 0; j < n_; ++j) {
    const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
    across[j] = static_cast<std::int32_t>(face.corner[j] >> shift);
    if (j == axis)
      across[j] = upper ? lo[j] + 2 : lo[j] - 1;
    else if (fixed && (face.corner[j] & (scale - 1)) == 0)
      other = j;  // on a leaf plane
  }
  for (int s = 0; s < (other >= 0 ? 2 : 1); ++s) {
    std::vector<std::int32_t> index = across;
    if (other >= 0) index[other] -= s;
    const Occupant o = tree_.find(level, index);
    if (o.kind != Occupant::Kind::kLeaf || tree_.level(o.leaf) != level ||
        perLeaf_.block[o.leaf] < 0)
      return false;
  }
  return true;
}

template <class S>
std::int64_t AdaptiveCrossing<S>::blockNode(std::int64_t node) const {
  const bool inBlock =
      node >= 0 && std::size_t(node) < perLeaf_.block.size() && perLeaf_.block[node] >= 0;
  return inBlock ? std::int64_t{blocks_[perLeaf_.block[node]].front()} : node;
}

template <class S>
template <class Map>
Polygon AdaptiveCrossing<S>::collapsed(const Polygon& poly, const Map& map) {
  Polygon q = poly;
  q.size = 0;
  for (int i = 0; i < poly.size; ++i) {
    const std::int64_t node = map(poly.node[i]);
    if (q.size > 0 && q.node[q.size - 1] == node) continue;
    q.node[q.size++] = node;
  }
  if (q.size > 1 && q.node[q.size - 1] == q.node[0]) --q.size;
  return q;
}

template <class S>
void AdaptiveCrossing<S>::collapseBlocks(bool certified) {
  if (blocks_.empty() || !certified) return;
  std::vector<Polygon> kept;
  for (const Polygon& p : polygons_) {
    const Polygon q = collapsed(p, [&](std::int64_t node) { return blockNode(node); });
    if (q.size >= (k_ == 1 ? 2 : 3)) kept.push_back(q);
  }
  polygons_ = std::move(kept);
}

}  // namespace ndc::crossing_detail
