// A window's task per leaf. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <cmath>
#include <cstdlib>
#include <optional>
#include <vector>

#include "strategies/connection/crossing/enclosure.hpp"
#include "strategies/connection/crossing/jacobian_work.hpp"

namespace ndc::crossing_detail {

namespace {

/// The local degree of F on a face from its roots: the sum of the signs of the face Jacobian's
/// determinant (columns of the free axes). A piece of M that dips through the face and back
/// gives two roots of opposite sign that cancel; two strands crossing the face the same way (a
/// self-intersection) add up and keep the curve connected. The count is odd exactly when the
/// number of roots is odd, so closedness mod 2 is kept. Near a singular point, where the
/// orientation of M is undefined and two strands may cross one face with opposite signs, every
/// root counts, rather than cut M.
template <class S>
int faceDegree(const System<S>& system, const std::vector<std::vector<S>>& roots,
               const std::vector<int>& freeAxes) {
  const int m = system.m();
  std::optional<JacobianWork<S>> fresh;
  JacobianWork<S>& w = threadScratch<S, JacobianWork<S>>(fresh);
  int degree = 0;
  bool singular = false;
  for (const auto& r : roots) {
    const Matrix<S>& full = w.jacobianAt(system, std::span<const S>(r));
    Matrix<S>& j = w.square;
    j.resize(m, m);
    for (int col = 0; col < m; ++col) j.col(col) = full.col(freeAxes[col]);
    const S det = w.lu.compute(j).determinant();
    degree += det > 0 ? 1 : (det < 0 ? -1 : 0);
    // One equation: one singular value, never below a tenth of itself. Most roots are
    // clearly regular (a Cholesky test); the singular values decide the others.
    if (m == 1 || singular || w.clearlyRegular(S(0.1))) continue;
    const Vector<S>& sigma = w.singularValues();
    singular = sigma(m - 1) < sigma(0) / 10;
  }
  const int count = static_cast<int>(roots.size());
  if (count % 2 == 1 && degree == 0) degree = 1;  // a root of unknown orientation
  if (count >= 2 && std::abs(degree) < count && singular) degree = count;
  return degree;
}

}  // namespace

template <class S>
void AdaptiveCrossing<S>::prefetchLeaf(std::int32_t c, std::int8_t prior, std::uint64_t priorFacets,
                                       const RootForms& rf, LeafFaces& out) const {
  PrefetchedLeaf leaf(c, rf, out);
  if (prior < 0) prefetchEmptiness(leaf);
  // A prior emptiness is never 1 (startWindow skips those leaves).
  if (out.empty == 1) return;
  prefetchFacets(leaf, priorFacets);
  prefetchFaces(leaf);
}

template <class S>
void AdaptiveCrossing<S>::restrictOnce(PrefetchedLeaf& leaf) const {
  if (leaf.restricted) return;
  leaf.restricted = true;
  if (!dense_) {
    // No forms: nothing proven empty (prefetchEmptiness decides before, for m >= 2).
    if (leaf.out.empty < 0) leaf.out.empty = 0, leaf.out.band = 0;
    return;
  }
  bool band = false;
  const bool empty = restrictLeaf(leaf.c, leaf.rf, leaf.patches, band);
  if (leaf.out.empty < 0) leaf.out.empty = empty ? 1 : 0, leaf.out.band = band ? 1 : 0;
}

template <class S>
void AdaptiveCrossing<S>::modelOnce(PrefetchedLeaf& leaf) const {
  // For m >= 2 (where faces are solved by evaluation) the leaf's affine model, built on the
  // first face not solved yet, or for the emptiness test.
  if (leaf.modelled) return;
  buildLeafModel(threadEvaluators(in_.system), leafBox(leaf.c), std::span<const S>(level_),
                 leaf.model);
  leaf.modelled = true;
}

template <class S>
void AdaptiveCrossing<S>::prefetchEmptiness(PrefetchedLeaf& leaf) const {
  LeafFaces& out = leaf.out;
  // A leaf where every F_i - c_i provably takes both signs is not empty by its Bernstein
  // forms either: its patches are restricted only if a face needs them.
  if (m_ > 1 && byEvaluation_) {
    modelOnce(leaf);
    if (levelsMet(leaf.model, leafBox(leaf.c))) {
      out.empty = 0, out.band = 0;
    } else if (modelExcludesBand(leaf.model)) {
      // Neither M_c nor any level set between it and M meets the leaf (most children of a
      // refined leaf): no need for the forms' coefficients.
      out.empty = 1, out.band = 1;
    } else {
      // Undecided by the model: the forms' coefficients prove such a leaf empty about once
      // in 600 leaves (near M, the rotated 2-sphere in R^7), at the price of restricting
      // m dense forms. Not proven empty, its faces are solved, each proving its own
      // exclusion, and its certificate takes the path of a leaf M_c may meet.
      out.empty = 0, out.band = 0;
    }
  }
  if (out.empty < 0) restrictOnce(leaf);
}

template <class S>
void AdaptiveCrossing<S>::prefetchFacets(PrefetchedLeaf& leaf, std::uint64_t priorFacets) const {
  leaf.out.facets = priorFacets;
  if (k_ == 2 && m_ > 1 && byEvaluation_ && priorFacets == kAllFacets) {
    modelOnce(leaf);
    thread_local std::vector<char> met;
    std::optional<LinearizedSystem<S>> fresh;
    facetsOfModel(leaf.model, threadScratch<S, LinearizedSystem<S>>(fresh), met);
    leaf.out.facets = facetMask(met);
  }
}

template <class S>
void AdaptiveCrossing<S>::prefetchFaces(PrefetchedLeaf& leaf) const {
  const std::int32_t c = leaf.c;
  LeafFaces& out = leaf.out;
  // The faces c owns, per thread: the slot keeps only those the walk visits.
  thread_local std::vector<OwnedFace> owned;
  ownedFaces(c, out.facets, owned);
  // The Krawczyk preconditioners of the faces' axis choices, each built when a face of that
  // choice is the first that the model's enclosure alone does not exclude.
  thread_local std::vector<FacePreconditioner<S>> pre;
  thread_local std::vector<std::uint8_t> built;
  if (pre.size() < fixedAxes_.size()) pre.resize(fixedAxes_.size());
  built.assign(fixedAxes_.size(), 0);
  for (const OwnedFace& f : owned) {
    const std::uint32_t kind = faceKind(f.a, f.side);
    // A face of an earlier round: copied from faces_ if the walk visits it.
    if (const FaceRecord* kept = faces_.find(c, kind)) {
      if (quiet(*kept)) continue;
      out.kept.push_back(faces_.result(c, *kept));
      out.visit.emplace_back(f, -static_cast<std::int32_t>(out.kept.size()));
      continue;
    }
    // A new face: solved, with the leaf's patches and model on demand.
    const auto restricted = [&]() -> const std::vector<Bernstein<S>>& {
      restrictOnce(leaf);
      return leaf.patches;
    };
    if (m_ > 1 && byEvaluation_) modelOnce(leaf);
    const auto preconditioner = [&]() -> const FacePreconditioner<S>* {
      if (!built[f.a]) {
        buildFacePreconditioner(leaf.model, std::span<const int>(fixedAxes_[f.a].data(), k_),
                                pre[f.a]);
        built[f.a] = 1;
      }
      return &pre[f.a];
    };
    facesSolved_.fetch_add(1, std::memory_order_relaxed);
    FaceResult<S> r = solveFace(c, fixedAxes_[f.a], f.side, restricted, leaf.rf.margins,
                                leaf.modelled ? &leaf.model : nullptr, preconditioner);
    if (!quiet(r)) out.visit.emplace_back(f, static_cast<std::int32_t>(out.faces.size()));
    out.faces.emplace_back(kind, std::move(r));
  }
}

template <class S>
bool AdaptiveCrossing<S>::emptyOf(std::int32_t c, const LeafFaces& known) {
  perLeaf_.bandEmpty[c] = known.band;
  return known.empty == 1;
}

template <class S>
bool AdaptiveCrossing<S>::modelExcludesBand(const LeafModel<S>& model) const {
  std::optional<LinearizedSystem<S>> fresh;
  return bandExcluded(model, std::span<const S>(level_),
                      threadScratch<S, LinearizedSystem<S>>(fresh), kFaceMultiplierSteps);
}

template <class S>
bool AdaptiveCrossing<S>::levelsMet(const LeafModel<S>& model, const Box<S>& box) const {
  using std::abs;
  if (!model.valid) return false;
  std::vector<MidRadEvaluator<S>>& evaluators = threadEvaluators(in_.system);
  std::optional<CornerWork> fresh;
  CornerWork& w = threadScratch<S, CornerWork>(fresh);
  std::vector<S>&corner = w.corner, &zero = w.zero;
  corner.resize(n_);
  zero.assign(n_, S(0));
  const S eps = 2 * ScalarTraits<S>::epsilon();
  for (int i = 0; i < m_; ++i) {
    const S& mid = model.valueMid[i];
    const S& rad = model.valueRad[i];
    if (!(mid - rad > 0) && !(mid + rad < 0)) return false;  // F_i at the centre is near c_i
    const bool positive = mid - rad > 0;
    for (int j = 0; j < n_; ++j) {
      const S& g = model.gradMid[std::size_t(i) * n_ + j];
      corner[j] = (g > 0) == positive ? box.lo[j] : box.hi[j];
    }
    MidRadEvaluator<S>& e = evaluators[i];
    if (!e.run(std::span<const S>(corner), std::span<const S>(zero), false)) return false;
    const S value = e.mid(0) - level_[i];
    const S radius = e.rad(0) + eps * abs(value);
    if (positive ? !(value + radius < 0) : !(value - radius > 0)) return false;
  }
  return true;
}

template <class S>
template <class Face>
bool AdaptiveCrossing<S>::quiet(const Face& r) {
  return r.degree == 0 && r.roots <= 1 && r.proven && r.certain && !r.withinRounding &&
         r.degenerate == 0;
}

template <class S>
double AdaptiveCrossing<S>::faceCoefficients(const std::array<int, 2>& axes) const {
  double coefficients = 0;
  for (const std::vector<int>& d : degrees_) {
    double size = 1;
    for (int j = 0; j < n_; ++j) {
      if (j != axes[0] && (k_ == 1 || j != axes[1])) size *= double(d[j] + 1);
    }
    coefficients += size;
  }
  return coefficients;
}

template <class S>
template <class Patches, class Preconditioner>
FaceResult<S> AdaptiveCrossing<S>::solveFace(std::int32_t leaf, const std::array<int, 2>& axes,
                                             int side, Patches&& patches,
                                             std::span<const S> margins, const LeafModel<S>* model,
                                             Preconditioner&& preconditioner) const {
  std::optional<FaceWork> fresh;
  FaceWork& w = threadScratch<S, FaceWork>(fresh);
  cellBoxInto(tree_.grid(tree_.level(leaf)), domain_, tree_.index(leaf), w.box);
  const Box<S>& box = w.box;
  const auto ci = tree_.index(leaf);
  const std::int64_t top = tree_.grid(tree_.level(leaf)).cellsPerAxis();
  w.ends.lower.clear(), w.ends.upper.clear();
  w.freeAxes.clear();
  w.faceBox.lo.clear(), w.faceBox.hi.clear();
  w.point.assign(box.lo.begin(), box.lo.end());
  for (int j = 0; j < n_; ++j) {
    if (j == axes[0] || j == axes[1]) continue;
    w.freeAxes.push_back(j);
    w.faceBox.lo.push_back(box.lo[j]);
    w.faceBox.hi.push_back(box.hi[j]);
    w.ends.lower.push_back(ci[j] == 0);
    w.ends.upper.push_back(ci[j] + 1 == top);
  }
  for (int t = 0; t < k_; ++t) {
    const bool upper = (side >> t) & 1;
    w.point[axes[t]] = upper ? box.hi[axes[t]] : box.lo[axes[t]];
  }
  w.roots.clear();
  FaceResult<S> r;
  // The leaf's affine model first: it excludes most faces without an evaluation on them.
  const std::span<const int> fixed(axes.data(), static_cast<std::size_t>(k_));
  if (model) {
    const FacePreconditioner<S>* pre = nullptr;
    if (faceExcluded(*model, box, fixed, side) ||
        ((pre = preconditioner()) && faceKrawczykExcludes(*model, *pre, box, fixed, side)))
      return faceOutcome(std::move(r), w.roots, box, w.freeAxes, w.ends);
  }
  // The model's multiplier test, where the solver's first round on the face decides nothing
  // (most faces it excludes would take the solver many boxes; most others one round).
  const auto multipliersExclude = [&] {
    return model && faceMultipliersExclude(*model, box, fixed, side, kFaceMultiplierSteps);
  };
  FaceSolver<S>& solver = w.solver;
  solver.reset(in_.system, maxFaceDepth_, std::span<const S>(level_), position_.slack);
  // Solved on its Bernstein slices where evaluation does not decide it, unless they are large,
  // or dear (more than kCheapFaceCoefficients) while its leaf may still be refined: then it
  // stays unproven, not stuck, and the next level's smaller faces are decided by evaluation
  // (a circle in R^9 at depth 3: 0.47 s in the Bernstein solves of 8-dimensional faces, for
  // 62 cells that depth 4 certifies in 0.02 s).
  const double coefficients = faceCoefficients(axes);
  const bool mayRefine = in_.refine && refining_ && tree_.level(leaf) < tree_.maxLevel();
  const bool slices = dense_ && coefficients <= kMaxFaceCoefficients &&
                      (coefficients <= kCheapFaceCoefficients || !mayRefine);
  solver.setBernsteinCost(coefficients, slices);
  if (m_ > 1 && byEvaluation_ &&
      solver.solveByEvaluation(w.point, w.freeAxes, w.faceBox, w.ends, w.roots,
                               multipliersExclude)) {
    r.certain = r.proven = true;
  } else if (m_ > 1 && byEvaluation_ && !slices) {
    // Slices of (d + 1)^m coefficients would cost more than the whole leaf is worth: the face
    // stays unproven (its leaves fail their certificate and may be refined, where evaluation
    // decides a smaller face), not stuck.
    w.roots.clear();
    r.certain = true;
    r.proven = false;
  } else {
    w.roots.clear();
    faceSlices(patches(), axes, side, w.face, w.cut);
    r.certain = solver.solve(w.point, w.freeAxes, w.face, w.ends, w.roots, margins);
    r.proven = solver.proven();
    r.withinRounding = solver.withinRounding();
  }
  return faceOutcome(std::move(r), w.roots, box, w.freeAxes, w.ends);
}

template <class S>
void AdaptiveCrossing<S>::faceSlices(const std::vector<Bernstein<S>>& patches,
                                     const std::array<int, 2>& axes, int side,
                                     std::vector<Bernstein<S>>& face,
                                     std::vector<Bernstein<S>>& cut) const {
  face.resize(m_);
  cut.resize(m_);
  for (int i = 0; i < m_; ++i) {
    if (k_ == 1) {
      patches[i].faceSliceInto(axes[0], side & 1, face[i]);
      continue;
    }
    // Slice the higher fixed axis first so that the lower axis number stays valid.
    patches[i].faceSliceInto(axes[1], (side >> 1) & 1, cut[i]);
    cut[i].faceSliceInto(axes[0], side & 1, face[i]);
  }
}

template <class S>
FaceResult<S> AdaptiveCrossing<S>::faceOutcome(FaceResult<S> r,
                                               const std::vector<std::vector<S>>& roots,
                                               const Box<S>& box, const std::vector<int>& freeAxes,
                                               const FaceEnds& ends) const {
  if (m_ > 1) r.degenerate = position_.nearBoundary(roots, box, freeAxes, ends);
  r.roots = static_cast<int>(roots.size());
  if (!roots.empty()) {
    r.degree = faceDegree(in_.system, roots, freeAxes);
    r.root = roots.front();
  }
  return r;
}

}  // namespace ndc::crossing_detail
