// The refinement loop and its budget. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <vector>

#include "framework/problem/budget.hpp"

namespace ndc::crossing_detail {

template <class S>
void AdaptiveCrossing<S>::setBudget(std::size_t baseCells, bool tolerance, double refineSeconds) {
  maxSolutionLeaves_ =
      std::max<std::size_t>(16 * baseCells, std::size_t{1} << std::max(12, 16 - 4 * (grid_.n - 3)));
  if (tolerance) maxSolutionLeaves_ = std::max<std::size_t>(maxSolutionLeaves_, kMaxLeaves);
  const double byWork = refineSeconds / (workPerCell(in_.problem) * kSecondsPerWork);
  if (byWork < static_cast<double>(maxSolutionLeaves_))
    maxSolutionLeaves_ = static_cast<std::size_t>(std::max(byWork, 1.0));
}

template <class S>
bool AdaptiveCrossing<S>::withinBudget(std::size_t refine) const {
  const double perLeaf =
      refined_ > 0 ? double(solutionChildren_) / double(refined_) : double(1 << k_);
  const auto predicted = static_cast<std::size_t>(double(refine) * perLeaf);
  return tree_.size() + predicted <= kMaxLeaves &&
         tree_.solutionLeaves() + predicted <= maxSolutionLeaves_;
}

template <class S>
bool AdaptiveCrossing<S>::refinable(std::int32_t c) const {
  return in_.refine && refining_ && tree_.level(c) < tree_.maxLevel() && !perLeaf_.stuck[c];
}

template <class S>
std::int64_t AdaptiveCrossing<S>::refineAndCertify() {
  tree_ = CellTree(grid_, tree_.maxLevel());
  tree_.addBaseCells(in_.cells);
  faces_.clear();
  perLeaf_.clear();
  refined_ = 0;
  solutionChildren_ = 0;
  budgetSpent_ = false;
  while (true) {
    perLeaf_.clearFaceFlags();
    const std::int64_t degenerate = crossFaces();
    grow();
    certify();
    // Refine the leaves that fail, above the maximum level.
    std::vector<std::int32_t> refine;
    for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
      if (tree_.active(c) && perLeaf_.failure[c] != Failure::kNone &&
          tree_.level(c) < tree_.maxLevel() &&
          !((perLeaf_.failure[c] == Failure::kCrossing ||
             perLeaf_.failure[c] == Failure::kBoundary) &&
            perLeaf_.stuck[c]))
        refine.push_back(c);
    }
    // Certified (or as far as it goes): then the leaves the chord error asks for.
    if (refine.empty() && in_.tolerance > 0 && refining_) refine = chordLeaves();
    if (refine.empty() || !in_.refine || !refining_) return degenerate;
    if (!withinBudget(refine.size())) {
      // No refinement follows: the leaves it would have proved try blocks after all.
      budgetSpent_ = true;
      blocksEverywhere_ = true;
      certify();
      blocksEverywhere_ = false;
      return degenerate;
    }
    // The children's bounding tests in parallel, the tree's growth in order.
    std::vector<std::vector<std::uint8_t>> children(refine.size());
    parallelFor(refine.size(), [&](std::size_t i) {
      const std::int32_t c = refine[i];
      children[i] = in_.refine(cellBox(tree_.grid(tree_.level(c)), grid_.domain, tree_.index(c)));
    });
    for (std::size_t i = 0; i < refine.size(); ++i) {
      solutionChildren_ += children[i].size() / std::size_t(n_);
      tree_.refine(refine[i], children[i]);
      ++refined_;
    }
    grow();
  }
}

}  // namespace ndc::crossing_detail
