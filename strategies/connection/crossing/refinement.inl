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
  refineGraphFailures();
  for (int round = 1;; ++round) {
    perLeaf_.clearFaceFlags();
    if (in_.progress) {
      progressLeaves_ = tree_.size();
      progressLabel_ = "connection, round " + std::to_string(round) + ": " +
                       std::to_string(tree_.size()) + " leaves, " + std::to_string(refined_) +
                       " refined";
    }
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
    refineLeaves(refine);
  }
}

template <class S>
void AdaptiveCrossing<S>::refineLeaves(const std::vector<std::int32_t>& refine) {
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

template <class S>
bool AdaptiveCrossing<S>::failsGraphTests(std::int32_t c, const RootForms& rf) {
  std::vector<Bernstein<S>> own;
  LeafTests t{leafScratch(own), {}, graphTest_, false, -1, false, {}, !cheapForms_};
  if (intervalEmpty(leafBox(c), true)) return false;
  if (!cellGraph(c, rf, t)) return true;
  if (k_ != 2) return false;
  // The face graph test (k = 2) on the facets the leaf model shows M_c may meet, as the
  // certificate's (prefetchFacets keeps the mask).
  if (m_ > 1 && byEvaluation_) {
    LeafModel<S> model;
    buildLeafModel(threadEvaluators(in_.system), leafBox(c), std::span<const S>(level_), model);
    thread_local std::vector<char> met;
    std::optional<LinearizedSystem<S>> fresh;
    facetsOfModel(model, threadScratch<S, LinearizedSystem<S>>(fresh), met);
    perLeaf_.facetsMet[c] = facetMask(met);
  }
  // Where M is tangent to a facet's plane the face graph test fails at every level: there the
  // certificate tries blocks (docs/certificate.md, "Blocks"), not refinement.
  return !facesGraph(c, rf, t) && !tangentToFacetPlane(c);
}

template <class S>
void AdaptiveCrossing<S>::refineGraphFailures() {
  // Coarse leaves whose graph test fails are refined before their faces are solved: the
  // certificate would refine them anyway, and a coarse leaf's faces are the dearest to solve
  // (the circle in R^13 at depth 3: 60 % of the run in its 12-dimensional facets). Only down
  // to kEagerLevels below the base grid: near a singular point the graph test fails at every
  // level, and there the crossings decide (stuck leaves are not refined).
  while (in_.refine && refining_) {
    grow();  // the per-leaf tables to every leaf of the tree
    std::vector<std::int32_t> leaves;
    for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
      if (tree_.active(c) && perLeaf_.graph[c] < 0 && tree_.level(c) < grid_.depth + kEagerLevels &&
          refinable(c))
        leaves.push_back(c);
    }
    if (leaves.empty()) return;
    const std::vector<const RootForms*> forms = rootFormsOf(leaves);
    std::vector<char> fails(leaves.size(), 0);
    parallelFor(leaves.size(),
                [&](std::size_t i) { fails[i] = failsGraphTests(leaves[i], *forms[i]) ? 1 : 0; });
    std::vector<std::int32_t> refine;
    for (std::size_t i = 0; i < leaves.size(); ++i) {
      if (fails[i]) refine.push_back(leaves[i]);
    }
    if (refine.empty() || !withinBudget(refine.size())) return;
    refineLeaves(refine);
  }
}

}  // namespace ndc::crossing_detail
