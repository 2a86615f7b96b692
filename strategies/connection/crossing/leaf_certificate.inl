// Each leaf's certificate. Included only by adaptive_crossing_{double,mpfr}.cpp.
// See docs/certificate.md.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <numeric>
#include <vector>

#include "strategies/connection/crossing/domain_boundary.hpp"
#include "strategies/connection/crossing/enclosure.hpp"

namespace ndc::crossing_detail {

template <class S>
void AdaptiveCrossing<S>::certify() {
  const Incidence incident(polygons_, tree_.size());
  std::fill(perLeaf_.failure.begin(), perLeaf_.failure.end(), Failure::kNone);
  std::vector<std::int32_t> leaves;
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
    if (tree_.active(c)) leaves.push_back(c);
  }
  grow();  // certifyLeaf writes per-leaf slots only: none may grow now
  const std::vector<const RootForms*> forms = rootFormsOf(leaves);
  parallelFor(leaves.size(),
              [&](std::size_t i) { certifyLeaf(leaves[i], *forms[i], incident[leaves[i]]); });
  mergeBlocks(incident, leaves, forms);
}

template <class S>
void AdaptiveCrossing<S>::certifyLeaf(std::int32_t c, const RootForms& rf,
                                      std::span<const std::int32_t> ps) {
  std::vector<Bernstein<S>> own;
  LeafTests t{leafScratch(own), {}, graphTest_, false, -1, false, {}};
  if (perLeaf_.empty[c] == 1) {
    // M_c misses the leaf; M may not (it lies 1e-8 h away): where it meets the leaf, the
    // isotopy from M to M_c needs the Jacobian's rank there, and on the domain's boundary
    // transversality to its faces.
    // (For m = 1 the sign rule lets F = 0 pass as empty: the boundary's test is strict.)
    const bool missed = perLeaf_.bandEmpty[c] || intervalEmpty(leafBox(c), true);
    if (!missed && !cellGraph(c, rf, t))
      perLeaf_.failure[c] = Failure::kGraph;
    else if ((!missed || m_ == 1) && !boundaryTransverse(c, rf, t, true))
      perLeaf_.failure[c] = Failure::kBoundary;
    return;
  }
  if (perLeaf_.unproven[c]) {
    perLeaf_.failure[c] = Failure::kCrossing;
  } else if (!cellGraph(c, rf, t) && !intervalEmpty(leafBox(c), true)) {
    perLeaf_.failure[c] = Failure::kGraph;
  } else if (k_ == 2 && !facesGraph(c, rf, t)) {
    perLeaf_.failure[c] = Failure::kFaceGraph;
  } else if (!simpleLink(k_, c, polygons_, ps)) {
    perLeaf_.failure[c] = Failure::kLink;
  } else if (!boundaryTransverse(c, rf, t, true)) {
    perLeaf_.failure[c] = Failure::kBoundary;
  }
}

template <class S>
bool AdaptiveCrossing<S>::cellGraph(std::int32_t leaf, const RootForms& rf, LeafTests& t) {
  if (perLeaf_.graph[leaf] < 0) {
    // By evaluation first (polynomial in n); the Bernstein hulls where it does not prove it.
    thread_local std::vector<int> all;
    all.resize(n_);
    std::iota(all.begin(), all.end(), 0);
    const bool evaluated = byEvaluation_ && leafJacobian(leaf, t) &&
                           t.test.graph(std::span<const Interval<S>>(t.whole), all);
    // Evaluation only: a failure is not the test's answer (the hulls may prove it): not kept.
    if (!evaluated && t.evaluationOnly) return false;
    perLeaf_.graph[leaf] = evaluated;
    if (!evaluated && dense_) {
      prepare(leaf, rf, t);
      perLeaf_.graph[leaf] = graphOf(t.patches, rf.margins, t.jacobian, t.test);
    }
  }
  return perLeaf_.graph[leaf] == 1;
}

template <class S>
bool AdaptiveCrossing<S>::leafJacobian(std::int32_t leaf, LeafTests& t) const {
  if (t.wholeKnown < 0)
    t.wholeKnown = evaluatedJacobian(leafBox(leaf), t.whole, t.wholeExcluded) ? 1 : 0;
  return t.wholeKnown == 1;
}

template <class S>
bool AdaptiveCrossing<S>::evaluatedGraph(const Box<S>& box, int fixed, bool& excluded,
                                         LeafTests& t) const {
  if (!evaluatedJacobian(box, t.jacobian, excluded)) return false;
  return excluded || t.test.graph(t.jacobian, freeAxes(fixed));
}

template <class S>
bool AdaptiveCrossing<S>::evaluatedJacobian(const Box<S>& box, std::vector<Interval<S>>& jacobian,
                                            bool& excluded) const {
  thread_local std::vector<S> centre, radius;
  thread_local std::vector<Interval<S>> fy;
  thread_local std::vector<int> all;
  centreAndRadius(box, centre, radius);
  all.resize(n_);
  std::iota(all.begin(), all.end(), 0);
  excluded = false;
  return encloseSystem(threadEvaluators(in_.system), std::span<const S>(centre),
                       std::span<const S>(radius), std::span<const S>(level_),
                       std::span<const int>(all), jacobian, fy, excluded, false);
}

template <class S>
bool AdaptiveCrossing<S>::graphOf(const std::vector<Bernstein<S>>& patches,
                                  std::span<const S> margins, std::vector<Interval<S>>& jacobian,
                                  GraphTest<S>& test) const {
  std::vector<int> axes(n_);
  std::iota(axes.begin(), axes.end(), 0);
  return hullGraph(patches, margins, axes, jacobian, test);
}

template <class S>
bool AdaptiveCrossing<S>::hullGraph(const std::vector<Bernstein<S>>& patches,
                                    std::span<const S> margins, const std::vector<int>& axes,
                                    std::vector<Interval<S>>& jacobian, GraphTest<S>& test) const {
  jacobian.assign(std::size_t(m_) * n_, Interval<S>());
  for (int i = 0; i < m_; ++i) {
    for (int j = 0; j < n_; ++j)
      jacobian[std::size_t(i) * n_ + j] = derivativeHull(patches[i], j, margins[i]);
  }
  return test.graph(jacobian, axes);
}

template <class S>
bool AdaptiveCrossing<S>::intervalEmpty(const Box<S>& box, bool band) const {
  using I = Interval<S>;
  std::vector<I> x;
  for (int j = 0; j < n_; ++j) x.emplace_back(box.lo[j], box.hi[j]);
  for (int i = 0; i < m_; ++i) {
    const I f = in_.system.equations()[i].template evaluate<S>(std::span<const I>(x));
    if (m_ == 1 && (f.lower() >= 0 || f.upper() < 0)) return true;
    const S c = level_[i];
    const S lo = band ? std::min<S>(S(0), c) : c, hi = band ? std::max<S>(S(0), c) : c;
    if (m_ > 1 && (f.lower() > hi || f.upper() < lo)) return true;
  }
  return false;
}

template <class S>
bool AdaptiveCrossing<S>::facesGraph(std::int32_t leaf, const RootForms& rf, LeafTests& t) {
  if (perLeaf_.faceGraph[leaf] < 0) {
    // Face by face in failingFacesOf's order, by evaluation first and on the Bernstein
    // slices where that does not prove it.
    const Box<S> box = leafBox(leaf);
    // J over the whole leaf encloses J over each face: one evaluation proves most faces
    // (a face's own evaluation where it does not).
    const bool wholeKnown = byEvaluation_ && leafJacobian(leaf, t);
    const std::vector<Interval<S>>& whole = t.whole;
    int failed = -1;
    // A facet the leaf model shows M_c misses needs no test (docs/crossing.md, "Facets
    // first").
    const auto met = [&](int a, int side) { return facetMet(perLeaf_.facetsMet[leaf], a, side); };
    // Every facet's graph test on the whole leaf's J at once (GraphTest::facetGraphs), each
    // axis it leaves by the test of its own blocks.
    std::uint64_t wanted = 0, proven = 0;
    for (int a = 0; a < n_ && a < 64; ++a) {
      if (met(a, 0) || met(a, 1)) wanted |= std::uint64_t(1) << a;
    }
    if (wholeKnown && n_ <= 64)
      proven = t.test.facetGraphs(std::span<const Interval<S>>(whole), wanted);
    for (int a = 0; a < n_ && failed < 0; ++a) {
      if (!met(a, 0) && !met(a, 1)) continue;
      if (a < 64 && ((proven >> a) & 1)) continue;
      if (wholeKnown && t.test.graph(std::span<const Interval<S>>(whole), freeAxes(a))) continue;
      for (int side = 0; side < 2 && failed < 0; ++side) {
        if (!met(a, side)) continue;
        Box<S> face = box;
        face.lo[a] = face.hi[a] = side == 1 ? box.hi[a] : box.lo[a];
        bool excluded = false;
        if (byEvaluation_ && evaluatedGraph(face, a, excluded, t)) continue;
        if (!dense_ || t.evaluationOnly) {
          failed = 2 * a + side;
          continue;
        }
        prepare(leaf, rf, t);
        if (!faceGraphOf(t.patches, rf.margins, a, side == 1, freeAxes(a), t.jacobian, t.test))
          failed = 2 * a + side;
      }
    }
    if (failed >= 0 && t.evaluationOnly) return false;
    perLeaf_.faceGraph[leaf] = failed < 0;
    if (failed >= 0) faceTrouble(leaf, failed / 2, failed % 2 == 1);
  }
  return perLeaf_.faceGraph[leaf] == 1;
}

template <class S>
std::vector<int> AdaptiveCrossing<S>::freeAxes(int a) const {
  std::vector<int> axes;
  for (int j = 0; j < n_; ++j) {
    if (j != a) axes.push_back(j);
  }
  return axes;
}

template <class S>
std::vector<std::pair<int, bool>> AdaptiveCrossing<S>::failingFacesOf(
    const std::vector<Bernstein<S>>& patches, std::span<const S> margins, bool all,
    std::vector<Interval<S>>& jacobian, GraphTest<S>& test) const {
  std::vector<std::pair<int, bool>> failing;
  for (int a = 0; a < n_; ++a) {
    const std::vector<int> axes = freeAxes(a);
    for (int side = 0; side < 2; ++side) {
      if (faceGraphOf(patches, margins, a, side == 1, axes, jacobian, test)) continue;
      failing.emplace_back(a, side == 1);
      if (!all) return failing;
    }
  }
  return failing;
}

template <class S>
bool AdaptiveCrossing<S>::faceGraphOf(const std::vector<Bernstein<S>>& patches,
                                      std::span<const S> margins, int a, bool upper,
                                      const std::vector<int>& axes,
                                      std::vector<Interval<S>>& jacobian,
                                      GraphTest<S>& test) const {
  jacobian.assign(std::size_t(m_) * n_, Interval<S>());
  for (int i = 0; i < m_; ++i) {
    const Bernstein<S> face = patches[i].faceSlice(a, upper);
    if (clearsRange(face, level_[i], level_[i], margins[i])) return true;
    for (int j : axes)
      jacobian[std::size_t(i) * n_ + j] = derivativeHull(face, j < a ? j : j - 1, margins[i]);
  }
  if (test.graph(jacobian, axes)) return true;
  Box<S> face = patches.front().domain();
  face.lo[a] = face.hi[a] = upper ? face.hi[a] : face.lo[a];
  // Near a point where M is tangent to the face's hyperplane no block is regular, and M
  // usually misses the face although each equation alone meets it.
  return combinationExcludes(in_.system, std::span<const S>(level_), face,
                             std::span<const Interval<S>>(jacobian), axes) ||
         intervalEmpty(face, false);
}

template <class S>
bool AdaptiveCrossing<S>::boundaryTransverse(std::int32_t c, const RootForms& rf, LeafTests& t,
                                             bool mark) {
  std::vector<std::uint8_t> sides(n_, 0);
  const std::int64_t top = tree_.grid(tree_.level(c)).cellsPerAxis();
  bool touches = false;
  for (int j = 0; j < n_; ++j) {
    const std::int32_t i = tree_.index(c)[j];
    sides[j] = std::uint8_t((i == 0 ? 1 : 0) | (i + 1 == top ? 2 : 0));
    touches = touches || sides[j] != 0;
  }
  if (!touches) return true;
  for (const DomainStratum<S>& face : domainStrata(leafBox(c), sides, k_ + 1)) {
    if (levelsMiss(in_.system, face.box, std::span<const S>(level_), byEvaluation_)) continue;
    if (dense_) {
      prepare(c, rf, t);
      if (slicesMiss(t.patches, std::span<const S>(rf.margins), leafBox(c), face,
                     std::span<const S>(level_)))
        continue;
    }
    const auto fail = [&] {
      if (mark && tangentToFace(in_.system, face)) perLeaf_.stuck[c] = 1;
      return false;
    };
    if (static_cast<int>(face.fixed.size()) > k_) return fail();
    // J over the leaf holds J over the face; the face's own enclosure, then the Bernstein
    // hulls, where that does not prove it.
    if (byEvaluation_ && leafJacobian(c, t) && t.test.graph(t.whole, face.free)) continue;
    bool excluded = false;
    if (byEvaluation_ && evaluatedJacobian(face.box, t.jacobian, excluded) &&
        t.test.graph(t.jacobian, face.free))
      continue;
    if (!dense_ || !hullGraph(t.patches, rf.margins, face.free, t.jacobian, t.test)) return fail();
  }
  return true;
}

}  // namespace ndc::crossing_detail
