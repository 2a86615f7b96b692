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

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/system.hpp"

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

/// Whether no level set F = t level, t in [0, 1], meets `box` (M itself included), proven by
/// interval evaluation of each equation over the box, or (`byEvaluation`: programs of
/// arithmetic operations only) by its mean-value form F_i(y) + J_i(X) (X - y) from
/// midpoint-radius runs, which is of second order and so proves much closer faces.
template <class S>
bool levelsMiss(const System<S>& system, const Box<S>& box, std::span<const S> level,
                bool byEvaluation);

/// Whether the Bernstein coefficients of the leaf's `patches` on `face` (a face of the leaf
/// that fixes the axes `fixed` at the ends of the leaf's box `leaf`) prove that no level set
/// F = t level, t in [0, 1], meets it; `margins`: the coefficients' rounding margins.
template <class S>
bool slicesMiss(const std::vector<Bernstein<S>>& patches, std::span<const S> margins,
                const Box<S>& leaf, const DomainStratum<S>& face, std::span<const S> level);

/// Minimum-norm Newton onto M ∩ the plane where every axis but `freeAxes` keeps its value in x
/// (its steps move the free coordinates only), until a step is at the rounding floor. False when
/// the Jacobian's free columns lose rank on the way or a value is not finite; the caller checks
/// convergence.
template <class S>
bool faceNewton(const System<S>& system, std::span<S> x, const std::vector<int>& freeAxes);

/// Whether refinement cannot prove the face of a leaf that failed boundaryTransverse: Newton
/// from its centre (faceNewton, or Gauss-Newton on a face of dimension below m) reaches a point
/// of M in the face's plane, within the face widened by its own width, where the Jacobian's
/// columns of the free axes lose rank (their smallest singular value below 1e-6 of the
/// Jacobian's largest; always, on a face of dimension below m): M is tangent to the face of the
/// domain there, lies in it along a curve, or passes through a corner of the domain, and every
/// finer leaf around the point fails the same way. A heuristic that only decides where
/// refinement is spent; it proves nothing.
template <class S>
bool tangentToFace(const System<S>& system, const DomainStratum<S>& face);

extern template bool faceNewton(const System<double>&, std::span<double>, const std::vector<int>&);
extern template bool faceNewton(const System<Mpfr>&, std::span<Mpfr>, const std::vector<int>&);
extern template bool tangentToFace(const System<double>&, const DomainStratum<double>&);
extern template bool tangentToFace(const System<Mpfr>&, const DomainStratum<Mpfr>&);
extern template bool levelsMiss(const System<double>&, const Box<double>&, std::span<const double>,
                                bool);
extern template bool levelsMiss(const System<Mpfr>&, const Box<Mpfr>&, std::span<const Mpfr>, bool);
extern template bool slicesMiss(const std::vector<Bernstein<double>>&, std::span<const double>,
                                const Box<double>&, const DomainStratum<double>&,
                                std::span<const double>);
extern template bool slicesMiss(const std::vector<Bernstein<Mpfr>>&, std::span<const Mpfr>,
                                const Box<Mpfr>&, const DomainStratum<Mpfr>&,
                                std::span<const Mpfr>);

}  // namespace ndc::crossing_detail
