// The minimal m-faces a leaf owns. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <vector>

namespace ndc::crossing_detail {

template <class S>
void AdaptiveCrossing<S>::ownedFaces(std::int32_t c, std::uint64_t facets,
                                     std::vector<OwnedFace>& out) const {
  const int level = tree_.level(c);
  // Per-thread scratch (ownedFaces runs in prefetchLeaf's tasks): no allocation per leaf.
  thread_local std::vector<std::int32_t> ci, position;
  ci.assign(tree_.index(c).begin(), tree_.index(c).end());
  position.resize(n_);
  // The region at c's index moved by d0 along axis a0 and by d1 along a1 (a1 < 0: none).
  const auto lookup = [&](int a0, int d0, int a1, int d1) {
    std::copy(ci.begin(), ci.end(), position.begin());
    position[a0] += d0;
    if (a1 >= 0) position[a1] += d1;
    return tree_.find(level, position);
  };
  // The regions next to c across one face (2 per axis), looked up once: every face choice
  // with that axis meets them, so only the diagonal regions are looked up per choice.
  thread_local std::vector<Occupant> across;
  thread_local std::vector<std::uint8_t> looked;
  across.resize(2 * std::size_t(n_));
  looked.assign(2 * std::size_t(n_), 0);
  const auto acrossOf = [&](int axis, int d) -> const Occupant& {
    const std::size_t slot = 2 * std::size_t(axis) + (d > 0 ? 1 : 0);
    if (!looked[slot]) across[slot] = lookup(axis, d, -1, 0), looked[slot] = 1;
    return across[slot];
  };
  // A face of c is not c's when a region around it is finer (the face is not minimal: its
  // parts belong to the finer leaves) or a leaf of c's level before c (the face belongs to
  // the first leaf of its own level).
  const auto rulesOut = [&](const Occupant& o) {
    return o.kind == Occ::kFiner ||
           (o.kind == Occ::kLeaf && tree_.level(o.leaf) == level && o.leaf < c);
  };
  const Occupant self{Occ::kLeaf, c, 0};
  out.clear();
  out.reserve(fixedAxes_.size() << k_);  // every face kind at most once: one allocation
  std::array<Occupant, 4> around;
  for (std::size_t a = 0; a < fixedAxes_.size(); ++a) {
    const auto& axes = fixedAxes_[a];
    for (int side = 0; side < (1 << k_); ++side) {
      // The face's lower corner is c's moved by `side`; around it, on each fixed axis t, lie
      // c's side and the side across (offset d_t: -1 at the lower face, +1 at the upper).
      const int s0 = side & 1, d0 = s0 ? 1 : -1;
      const Occupant& o0 = acrossOf(axes[0], d0);
      if (k_ == 1) {
        if (rulesOut(o0)) continue;
        around[0] = s0 ? self : o0;
        around[1] = s0 ? o0 : self;
      } else {
        // A face in a facet M_c misses is not crossed (and not recorded: no region is
        // looked up for it). The regions across one face next (looked up once), so that a
        // face that is not c's is rejected before its diagonal region is looked up.
        const int s1 = (side >> 1) & 1, d1 = s1 ? 1 : -1;
        if (!facetMet(facets, axes[0], s0) || !facetMet(facets, axes[1], s1)) continue;
        const Occupant& o1 = acrossOf(axes[1], d1);
        if (rulesOut(o1) || rulesOut(o0)) continue;
        const Occupant diagonal = lookup(axes[0], d0, axes[1], d1);
        if (rulesOut(diagonal)) continue;
        // In cyclic order: (-a,-b), (+a,-b), (+a,+b), (-a,+b) around the lower corner; the
        // quadrant on c's side along both axes is c.
        static constexpr int kBits[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int q = 0; q < 4; ++q) {
          const bool moved0 = kBits[q][0] == s0, moved1 = kBits[q][1] == s1;
          around[q] = moved0 ? (moved1 ? diagonal : o0) : (moved1 ? o1 : self);
        }
      }
      out.push_back({static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(side), around});
    }
  }
}

template <class S>
void AdaptiveCrossing<S>::faceAround(const std::vector<std::int32_t>& ci, const OwnedFace& f,
                                     std::vector<std::int32_t>& corner,
                                     std::array<Occupant, 4>& around) const {
  const auto& axes = fixedAxes_[f.a];
  std::copy(ci.begin(), ci.end(), corner.begin());
  for (int t = 0; t < k_; ++t) corner[axes[t]] += (f.side >> t) & 1;
  around = f.around;
  for (int q = 0; q < (1 << k_); ++q) {
    if (around[q].kind != Occ::kEmpty) continue;
    if (const std::int32_t* leaf = touchLeaves_.find(emptyCellOf(around[q])))
      around[q] = Occupant{Occ::kLeaf, *leaf, 0};
  }
}

template <class S>
std::uint32_t AdaptiveCrossing<S>::faceKind(std::size_t a, int side) const {
  return static_cast<std::uint32_t>(a << k_) + static_cast<std::uint32_t>(side);
}

template <class S>
std::uint64_t AdaptiveCrossing<S>::facetMask(const std::vector<char>& met) const {
  if (n_ > 32 || met.empty()) return kAllFacets;
  std::uint64_t mask = 0;
  for (std::size_t f = 0; f < met.size(); ++f) mask |= std::uint64_t(met[f] != 0) << f;
  return mask;
}

template <class S>
bool AdaptiveCrossing<S>::facetMet(std::uint64_t mask, int a, int side) const {
  return mask == kAllFacets || ((mask >> (2 * a + side)) & 1) != 0;
}

}  // namespace ndc::crossing_detail
