// The run and CrossingConnection::connect. Included only by adaptive_crossing_{double,mpfr}.cpp.
#pragma once

#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include <algorithm>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>

#include "framework/problem/budget.hpp"
#include "strategies/connection/crossing.hpp"
#include "strategies/connection/crossing/dual_complex.hpp"
#include "strategies/connection/crossing/higher_crossing.hpp"

namespace ndc::crossing_detail {

namespace {

/// The name of a failure in uncertified.csv.
const char* failureName(Failure f) {
  switch (f) {
    case Failure::kCrossing:
      return "crossing";
    case Failure::kGraph:
      return "graph";
    case Failure::kFaceGraph:
      return "face-graph";
    case Failure::kLink:
      return "link";
    case Failure::kBoundary:
      return "domain-boundary";
    case Failure::kNone:
      break;
  }
  return "";
}

}  // namespace

template <class S>
AdaptiveCrossing<S>::AdaptiveCrossing(const ConnectionInput<S>& in, int maxFaceDepth)
    : in_(in),
      grid_(in.cells.grid),
      n_(grid_.n),
      k_(in.k),
      m_(n_ - k_),
      maxFaceDepth_(maxFaceDepth),
      domain_(toScalar<S>(grid_.domain)),
      cellForms_(in.system.equations(), grid_, domain_,
                 in.problem.roots.empty() ? 0 : in.problem.rootLevel),
      position_(in, grid_),
      graphTest_(grid_.n, grid_.n - in.k),
      tree_(grid_, std::max(grid_.depth, in.refine ? in.maxLevel : grid_.depth)),
      faces_(grid_.n) {
  for (int a = 0; a < n_; ++a) {
    if (k_ == 1) fixedAxes_.push_back({a, -1});
    for (int b = a + 1; k_ == 2 && b < n_; ++b) fixedAxes_.push_back({a, b});
  }
  // Evaluation first only for programs of arithmetic operations: a program with a
  // tensor-product patch as a leaf (the applications' surfaces) encloses it by de Casteljau
  // on every run, as dear as the Bernstein path, and for nearly degenerate rational patches
  // (weights of 1e-300) so loosely that nothing is decided and every face pays twice.
  byEvaluation_ = true;
  for (const Expression& e : in.system.equations())
    byEvaluation_ = byEvaluation_ && e.tape().leaves().empty();
  // Without dense forms where they would be large (kMaxLeafCoefficients).
  for (const Expression& e : in.system.equations()) degrees_.push_back(e.degrees());
  double coefficients = 0;
  for (const Expression& e : in.system.equations()) coefficients += denseCoefficients(e);
  dense_ = !byEvaluation_ || coefficients <= kMaxLeafCoefficients;
  cheapForms_ = !byEvaluation_ || coefficients <= kCheapLeafCoefficients;
  noForms_.margins.assign(std::size_t(m_), S(0));
  touchLeaves_.reset(grid_.depth, tree_.maxLevel());
  unprovenOfEmpty_.reset(grid_.depth, tree_.maxLevel());
  setBudget(in.cells.size(), in.tolerance > 0, in.refineSeconds);
}

template <class S>
ConnectionOutput<S> AdaptiveCrossing<S>::run() {
  ConnectionOutput<S> out = attempts();
  out.topology.facesSolved = facesSolved_;
  if (out.topology.certified || refined_ == 0) return out;
  const std::int64_t refinedDefects = nonmanifold(out.complex);
  const int reached = out.topology.maxLevel;
  refining_ = false;
  ConnectionOutput<S> base = attempts();
  out.topology.facesSolved = base.topology.facesSolved = facesSolved_;
  const std::int64_t baseDefects = nonmanifold(base.complex);
  if (baseDefects >= refinedDefects) return out;
  base.topology.reason += "; refinement down to level " + std::to_string(reached) +
                          " did not certify and left " + std::to_string(refinedDefects) +
                          " non-manifold edges or branch vertices, so the base grid's mesh is kept";
  return base;
}

template <class S>
ConnectionOutput<S> AdaptiveCrossing<S>::attempts() {
  ConnectionOutput<S> out;
  out.complex.n = n_;
  out.complex.k = k_;
  // General position: try levels until no crossing is within rounding of a face boundary.
  std::int64_t degenerate = 0;
  for (int attempt = 0;; ++attempt) {
    // For m = 1 the sign rule decides (the level set F = -delta, delta -> 0+): level 0.
    level_ = m_ == 1 ? std::vector<S>(1, S(0)) : position_.level(attempt);
    degenerate = refineAndCertify();
    out.perturbation.attempts = attempt + 1;
    out.perturbation.degenerateCrossings = degenerate;
    out.perturbation.level.clear();
    if (m_ > 1) {
      for (const S& c : level_) out.perturbation.level.push_back(toDouble(c));
    }
    if (degenerate == 0 || m_ == 1 || attempt + 1 == GeneralPosition<S>::kAttempts) break;
  }
  record(out.topology, degenerate);
  buildComplex(out);
  return out;
}

template <class S>
std::int64_t AdaptiveCrossing<S>::nonmanifold(const Complex<S>& complex) {
  std::unordered_map<std::uint64_t, int> uses;
  const std::size_t count = complex.simplexCount();
  const int k = complex.k;
  for (std::size_t t = 0; t < count; ++t) {
    const std::int32_t* v = complex.simplices.data() + t * (k + 1);
    if (k == 1) {
      ++uses[std::uint64_t(v[0])], ++uses[std::uint64_t(v[1])];
      continue;
    }
    for (int i = 0; i < 3; ++i) {
      const auto a = std::uint64_t(std::min(v[i], v[(i + 1) % 3]));
      const auto b = std::uint64_t(std::max(v[i], v[(i + 1) % 3]));
      ++uses[a << 32 | b];
    }
  }
  return std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second > 2; });
}

template <class S>
void AdaptiveCrossing<S>::record(TopologyRecord& t, std::int64_t degenerate) const {
  t.baseLevel = grid_.depth;
  t.maxDepth = tree_.maxLevel();
  t.maxLevel = grid_.depth;
  t.refinedCells = refined_;
  for (const auto& block : blocks_) t.blockCells += static_cast<std::int64_t>(block.size());
  std::map<std::string, std::int64_t> reasons;
  std::int64_t stuck = 0, tangent = 0;
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
    if (!tree_.active(c)) continue;
    t.maxLevel = std::max(t.maxLevel, tree_.level(c));
    if (perLeaf_.failure[c] == Failure::kNone) {
      ++t.certifiedCells;
      continue;
    }
    ++t.uncertifiedCells;
    ++reasons[failureName(perLeaf_.failure[c])];
    stuck += perLeaf_.failure[c] == Failure::kCrossing && perLeaf_.stuck[c];
    tangent += perLeaf_.failure[c] == Failure::kBoundary && perLeaf_.stuck[c];
    UncertifiedCell u;
    const Box<double> box = cellBox(tree_.grid(tree_.level(c)), grid_.domain, tree_.index(c));
    u.lo = box.lo;
    u.hi = box.hi;
    u.level = tree_.level(c);
    u.reason = failureName(perLeaf_.failure[c]);
    t.uncertified.push_back(std::move(u));
  }
  std::ostringstream why;
  if (t.uncertifiedCells > 0) {
    why << t.uncertifiedCells << " cell" << (t.uncertifiedCells == 1 ? "" : "s")
        << " uncertified down to level " << t.maxLevel << " of " << t.maxDepth << " (";
    bool first = true;
    for (const auto& [name, count] : reasons) {
      why << (first ? "" : ", ") << name << ": " << count;
      first = false;
    }
    why << ")";
    if (stuck > 0) {
      why << "; " << stuck << " next to crossings no refinement separates (M touches a grid "
          << "plane, or a singular point)";
    }
    if (reasons.count(failureName(Failure::kBoundary))) {
      why << "; M may touch the domain's boundary (tangent to a face of the domain, or through "
          << "a face of it of dimension below n - k = " << m_ << ")";
      if (tangent > 0)
        why << ", " << tangent << " next to a point of M where refinement cannot prove it (M "
            << "tangent to the domain's boundary there, or through a corner of it)";
    }
    if (budgetSpent_) {
      why << "; refinement stopped at its budget of " << maxSolutionLeaves_
          << " solution leaves and " << kMaxLeaves << " leaves";
    }
  } else if (degenerate > 0) {
    why << degenerate << " crossings within rounding of a face boundary";
  }
  t.reason = why.str();
  t.certified = t.reason.empty();
}

template <class S>
void AdaptiveCrossing<S>::buildComplex(ConnectionOutput<S>& out) {
  collapseBlocks(out.topology.certified);
  buildDualComplex(
      DualInput<S>{in_, tree_, domain_, polygons_, rootPoints_, perLeaf_.singular, position_.slack},
      out);
}

}  // namespace ndc::crossing_detail

namespace ndc {

template <class S>
ConnectionOutput<S> CrossingConnection::connect(const ConnectionInput<S>& in) const {
  // k >= 3: the uniform grid's dual cubes split by Kuhn's rule (docs/crossing.md, "Any k").
  if (in.k >= 3) return crossing_detail::higherCrossing(in, maxFaceDepth);
  return crossing_detail::AdaptiveCrossing<S>(in, maxFaceDepth).run();
}

}  // namespace ndc
