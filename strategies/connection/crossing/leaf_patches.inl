// A leaf's Bernstein patches. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

namespace ndc::crossing_detail {

template <class S>
auto AdaptiveCrossing<S>::rootForms(std::span<const std::int32_t> index, int level)
    -> const RootForms& {
  if (!dense_) return noForms_;
  const std::vector<Bernstein<S>>& forms = cellForms_.root(index, level);
  auto it = rootForms_.find(&forms);
  if (it != rootForms_.end()) return it->second;
  RootForms rf{&forms, {}};
  const S unit = ScalarTraits<S>::epsilon();
  for (std::size_t i = 0; i < forms.size(); ++i) {
    const auto [lo, hi] = forms[i].coefficientRange();
    using std::abs;
    const double relative = i < in_.coefficientError.size() ? in_.coefficientError[i] : 0.0;
    rf.margins.push_back((S(relative) + 1024 * unit) * std::max<S>(abs(lo), abs(hi)));
  }
  return rootForms_.emplace(&forms, std::move(rf)).first->second;
}

template <class S>
auto AdaptiveCrossing<S>::rootFormsOf(const std::vector<std::int32_t>& leaves)
    -> std::vector<const RootForms*> {
  std::vector<const RootForms*> forms;
  forms.reserve(leaves.size());
  for (std::int32_t c : leaves) forms.push_back(&rootForms(tree_.index(c), tree_.level(c)));
  return forms;
}

template <class S>
Box<S> AdaptiveCrossing<S>::leafBox(std::int32_t leaf) const {
  return cellBox(tree_.grid(tree_.level(leaf)), domain_, tree_.index(leaf));
}

template <class S>
bool AdaptiveCrossing<S>::restrictLeaf(std::int32_t leaf, const RootForms& rf,
                                       std::vector<Bernstein<S>>& patches, bool& band) const {
  const Box<S> box = leafBox(leaf);
  patches.resize(m_);
  bool empty = false;
  band = false;
  for (int i = 0; i < m_; ++i) {
    (*rf.forms)[i].restrictInto(box, patches[i]);
    const S c = level_[i];
    empty = empty || clearsRange(patches[i], c, c, rf.margins[i]);
    band =
        band || clearsRange(patches[i], std::min<S>(S(0), c), std::max<S>(S(0), c), rf.margins[i]);
  }
  return empty;
}

template <class S>
std::vector<Bernstein<S>>& AdaptiveCrossing<S>::leafScratch(std::vector<Bernstein<S>>& own) {
  if constexpr (std::is_same_v<S, double>) {
    thread_local std::vector<Bernstein<S>> scratch;
    return scratch;
  } else {
    return own;
  }
}

template <class S>
void AdaptiveCrossing<S>::prepare(std::int32_t leaf, const RootForms& rf, LeafTests& t) const {
  if (t.ready) return;
  bool band = false;
  restrictLeaf(leaf, rf, t.patches, band);
  t.ready = true;
}

}  // namespace ndc::crossing_detail
