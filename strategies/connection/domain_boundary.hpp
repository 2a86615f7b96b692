/// \file domain_boundary.hpp
/// Where a leaf of the crossing connection meets the boundary of the domain: the faces of its
/// box that lie in faces of the domain box (docs/certificate.md, "The domain's boundary").
/// The certificate asks every level set between M and M_c to cross each of them transversally
/// or to miss it, so that M ∩ D and M_c ∩ D are the same manifold with boundary. Internal to
/// the crossing connection.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "framework/core/box.hpp"

namespace ndc::crossing_detail {

/// A face of a leaf's box inside a face of the domain of dimension n - j: the j axes it fixes
/// at the domain's ends, the others (free), and its box.
template <class S>
struct DomainStratum {
  std::vector<int> fixed, free;
  Box<S> box;
};

/// The faces of the leaf `box` that lie in faces of the domain of codimension 1 to `deepest`,
/// in order of codimension. `sides[j]`: bit 0 when the leaf's lower end on axis j is the
/// domain's, bit 1 its upper end. A face of higher codimension lies inside one of these.
template <class S>
std::vector<DomainStratum<S>> domainStrata(const Box<S>& box, std::span<const std::uint8_t> sides,
                                           int deepest) {
  const int n = box.dim();
  // (axis, upper) for every end of the leaf on the domain's boundary.
  std::vector<std::pair<int, bool>> ends;
  for (int j = 0; j < n; ++j) {
    if (sides[j] & 1) ends.emplace_back(j, false);
    if (sides[j] & 2) ends.emplace_back(j, true);
  }
  std::vector<DomainStratum<S>> out;
  std::vector<int> chosen;
  // Every choice of j ends on distinct axes, j = 1 .. deepest, by increasing j.
  const auto choose = [&](auto&& self, std::size_t from, int left) -> void {
    if (left == 0) {
      DomainStratum<S> s{{}, {}, box};
      std::vector<char> fixed(n, 0);
      for (int e : chosen) {
        const auto [axis, upper] = ends[e];
        s.fixed.push_back(axis);
        fixed[axis] = 1;
        s.box.lo[axis] = s.box.hi[axis] = upper ? box.hi[axis] : box.lo[axis];
      }
      for (int j = 0; j < n; ++j)
        if (!fixed[j]) s.free.push_back(j);
      out.push_back(std::move(s));
      return;
    }
    for (std::size_t e = from; e < ends.size(); ++e) {
      const bool sameAxis = !chosen.empty() && ends[chosen.back()].first == ends[e].first;
      if (sameAxis) continue;  // both ends of one axis (a one-cell grid): no common face
      chosen.push_back(static_cast<int>(e));
      self(self, e + 1, left - 1);
      chosen.pop_back();
    }
  };
  for (int j = 1; j <= deepest && j <= n; ++j) choose(choose, 0, j);
  return out;
}

}  // namespace ndc::crossing_detail
