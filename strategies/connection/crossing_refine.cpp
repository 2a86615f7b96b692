/// \file crossing_refine.cpp
/// The crossing connection, phase 4: level attempts, the refinement loop over crossings and
/// certificates, the chord error refinement and the topology record.
#include "strategies/connection/crossing_detail.hpp"

#include <algorithm>
#include <sstream>
#include <string>

namespace ndc::crossing_detail {

namespace {

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
    case Failure::kNone:
      break;
  }
  return "";
}

}  // namespace

template <class S>
ConnectionOutput<S> AdaptiveCrossing<S>::run() {
  ConnectionOutput<S> out = attempts();
  if (out.topology.certified || refined_ == 0) return out;
  const std::int64_t refinedDefects = nonmanifold(out.complex);
  const int reached = out.topology.maxLevel;
  refining_ = false;
  ConnectionOutput<S> base = attempts();
  const std::int64_t baseDefects = nonmanifold(base.complex);
  if (baseDefects >= refinedDefects) return out;
  base.topology.reason += "; refinement down to level " + std::to_string(reached) +
                          " did not certify and left " + std::to_string(refinedDefects) +
                          " non-manifold edges or branch vertices, so the base grid's mesh is kept";
  return base;
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
std::int64_t AdaptiveCrossing<S>::refineAndCertify() {
  tree_ = CellTree(grid_, tree_.maxLevel());
  for (std::size_t c = 0; c < in_.cells.size(); ++c)
    tree_.addLeaf(grid_.depth, in_.cells.cell(c), true);
  tree_.setBaseCells(static_cast<std::int32_t>(in_.cells.size()));
  faces_.clear();
  empty_.clear(), bandEmpty_.clear(), unproven_.clear(), stuck_.clear(), singular_.clear(),
      graph_.clear(), faceGraph_.clear();
  failure_.clear();
  trouble_.clear(), hasTrouble_.clear();
  refined_ = 0;
  budgetSpent_ = false;
  while (true) {
    std::fill(unproven_.begin(), unproven_.end(), 0);
    std::fill(stuck_.begin(), stuck_.end(), 0);
    std::fill(singular_.begin(), singular_.end(), 0);
    const std::int64_t degenerate = crossFaces();
    grow();
    certify();
    // Refine the leaves that fail, above the maximum level.
    std::vector<std::int32_t> refine;
    for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
      if (tree_.active(c) && failure_[c] != Failure::kNone && tree_.level(c) < tree_.maxLevel() &&
          !(failure_[c] == Failure::kCrossing && stuck_[c]))
        refine.push_back(c);
    }
    // Certified (or as far as it goes): then the leaves the chord error asks for.
    if (refine.empty() && in_.tolerance > 0 && refining_) refine = chordLeaves();
    if (refine.empty() || !in_.refine || !refining_) return degenerate;
    if (tree_.size() + refine.size() * (std::size_t{1} << n_) > maxLeaves_) {
      budgetSpent_ = true;
      return degenerate;
    }
    for (std::int32_t c : refine) {
      const Box<double> box = cellBox(tree_.grid(tree_.level(c)), grid_.domain, tree_.index(c));
      tree_.refine(c, in_.refine(box));
      ++refined_;
    }
    grow();
  }
}

template <class S>
std::vector<std::int32_t> AdaptiveCrossing<S>::chordLeaves() const {
  const std::size_t count = tree_.size();
  const auto owner = [&](std::int64_t c) { return static_cast<std::size_t>(blockNode(c)); };
  std::vector<S> vertex(count * n_, S(0));
  std::vector<std::int32_t> crossings(count, 0);
  for (const Polygon& poly : polygons_) {
    if (poly.outside) continue;
    for (int i = 0; i < poly.size; ++i) {
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

template <class S>
void AdaptiveCrossing<S>::record(TopologyRecord& t, std::int64_t degenerate) const {
  t.baseLevel = grid_.depth;
  t.maxDepth = tree_.maxLevel();
  t.maxLevel = grid_.depth;
  t.refinedCells = refined_;
  for (const auto& block : blocks_) t.blockCells += static_cast<std::int64_t>(block.size());
  std::map<std::string, std::int64_t> reasons;
  std::int64_t stuck = 0;
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
    if (!tree_.active(c)) continue;
    t.maxLevel = std::max(t.maxLevel, tree_.level(c));
    if (failure_[c] == Failure::kNone) {
      ++t.certifiedCells;
      continue;
    }
    ++t.uncertifiedCells;
    ++reasons[failureName(failure_[c])];
    stuck += failure_[c] == Failure::kCrossing && stuck_[c];
    UncertifiedCell u;
    const Box<double> box = cellBox(tree_.grid(tree_.level(c)), grid_.domain, tree_.index(c));
    u.lo = box.lo;
    u.hi = box.hi;
    u.level = tree_.level(c);
    u.reason = failureName(failure_[c]);
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
    if (budgetSpent_) why << "; refinement stopped at " << maxLeaves_ << " leaves";
  } else if (degenerate > 0) {
    why << degenerate << " crossings within rounding of a face boundary";
  }
  t.reason = why.str();
  t.certified = t.reason.empty();
}

// The members of AdaptiveCrossing defined in this file, for double and ndc::Mpfr.
#define NDC_CROSSING_INSTANTIATE(S)                                                                \
  template ConnectionOutput<S> AdaptiveCrossing<S>::run();                                         \
  template std::int64_t AdaptiveCrossing<S>::nonmanifold(const Complex<S>& complex);               \
  template ConnectionOutput<S> AdaptiveCrossing<S>::attempts();                                    \
  template std::int64_t AdaptiveCrossing<S>::refineAndCertify();                                   \
  template std::vector<std::int32_t> AdaptiveCrossing<S>::chordLeaves() const;                     \
  template bool AdaptiveCrossing<S>::chordAbove(const Polygon& poly, const std::vector<S>& vertex, \
                                                const S& tolerance) const;                         \
  template void AdaptiveCrossing<S>::record(TopologyRecord& t, std::int64_t degenerate) const;
NDC_CROSSING_INSTANTIATE(double)
NDC_CROSSING_INSTANTIATE(Mpfr)
#undef NDC_CROSSING_INSTANTIATE

}  // namespace ndc::crossing_detail
