// --tolerance: leaves beyond the chord error. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <array>
#include <vector>

namespace ndc::crossing_detail {

template <class S>
std::vector<std::int32_t> AdaptiveCrossing<S>::chordLeaves() const {
  const std::size_t count = tree_.size();
  const auto owner = [&](std::int64_t c) { return static_cast<std::size_t>(blockNode(c)); };
  std::vector<S> vertex(count * n_, S(0));
  std::vector<std::int32_t> crossings(count, 0);
  for (const Polygon& poly : polygons_) {
    for (int i = 0; i < poly.size; ++i) {
      if (poly.node[i] < 0) continue;  // beyond the domain (its crossing counts for the leaf)
      const std::size_t c = owner(poly.node[i]);
      for (int j = 0; j < n_; ++j)
        vertex[c * n_ + j] += rootPoints_[std::size_t(poly.root) * n_ + j];
      ++crossings[c];
    }
  }
  std::vector<std::uint8_t> usable(count, 0);
  std::vector<S> x(n_);
  for (std::size_t c = 0; c < count; ++c) {
    if (crossings[c] == 0) continue;
    for (int j = 0; j < n_; ++j) x[j] = vertex[c * n_ + j] / crossings[c];
    usable[c] = in_.project(x).converged;
    std::copy(x.begin(), x.end(), vertex.begin() + std::ptrdiff_t(c * n_));
  }
  for (std::size_t c = 0; c < count; ++c) {  // block members share the block's vertex
    const std::size_t o = owner(std::int64_t(c));
    if (o == c) continue;
    usable[c] = usable[o];
    std::copy_n(vertex.begin() + std::ptrdiff_t(o * n_), n_,
                vertex.begin() + std::ptrdiff_t(c * n_));
  }
  const S tolerance = S(in_.tolerance);
  std::vector<std::uint8_t> marked(count, 0);
  for (const Polygon& poly : polygons_) {
    if (poly.outside || !usable[poly.node[0]]) continue;
    bool all = true;
    for (int i = 0; i < poly.size; ++i) all = all && usable[poly.node[i]];
    if (!all || !chordAbove(poly, vertex, tolerance)) continue;
    for (int i = 0; i < poly.size; ++i) {
      const auto c = static_cast<std::size_t>(poly.node[i]);
      if (tree_.level(std::int32_t(c)) < tree_.maxLevel()) marked[c] = 1;
    }
  }
  std::vector<std::int32_t> leaves;
  for (std::size_t c = 0; c < count; ++c) {
    if (marked[c] && tree_.active(std::int32_t(c))) leaves.push_back(std::int32_t(c));
  }
  return leaves;
}

template <class S>
bool AdaptiveCrossing<S>::chordAbove(const Polygon& poly, const std::vector<S>& vertex,
                                     const S& tolerance) const {
  const auto at = [&](int i, int j) -> const S& {
    return vertex[std::size_t(poly.node[i]) * n_ + j];
  };
  std::vector<std::array<int, 3>> simplices;
  if (poly.size == 2) simplices.push_back({0, 1, -1});
  if (poly.size == 3) simplices.push_back({0, 1, 2});
  if (poly.size == 4) {
    S d02 = 0, d13 = 0;
    for (int j = 0; j < n_; ++j) {
      d02 += (at(0, j) - at(2, j)) * (at(0, j) - at(2, j));
      d13 += (at(1, j) - at(3, j)) * (at(1, j) - at(3, j));
    }
    if (d02 <= d13)
      simplices.insert(simplices.end(), {{0, 1, 2}, {0, 2, 3}});
    else
      simplices.insert(simplices.end(), {{0, 1, 3}, {1, 2, 3}});
  }
  std::vector<S> centre(n_), projected(n_);
  for (const auto& s : simplices) {
    const int corners = s[2] < 0 ? 2 : 3;
    for (int j = 0; j < n_; ++j) {
      S sum = 0;
      for (int t = 0; t < corners; ++t) sum += at(s[t], j);
      centre[j] = sum / corners;
    }
    projected = centre;
    if (!in_.project(projected).converged) continue;  // the analysis leaves it out too
    S d2 = 0;
    for (int j = 0; j < n_; ++j) d2 += (projected[j] - centre[j]) * (projected[j] - centre[j]);
    if (d2 > tolerance * tolerance) return true;
  }
  return false;
}

}  // namespace ndc::crossing_detail
