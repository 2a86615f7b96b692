#include "strategies/connection/crossing/higher_crossing.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/cell_forms.hpp"
#include "framework/problem/problem.hpp"
#include "framework/util/errors.hpp"
#include "framework/util/flat_map.hpp"
#include "strategies/connection/crossing/certificate.hpp"
#include "strategies/connection/crossing/domain_boundary.hpp"
#include "strategies/connection/crossing/enclosure.hpp"
#include "strategies/connection/crossing/face_solver.hpp"
#include "strategies/connection/crossing/general_position.hpp"
#include "strategies/connection/crossing/kuhn.hpp"
#include "strategies/connection/crossing/leaf_model.hpp"

namespace ndc::crossing_detail {
namespace {

/// A minimal m-face of the grid: its lower corner (a grid vertex, packed) and its fixed axes.
struct FaceKey {
  CellKey corner = 0;
  std::uint64_t mask = 0;
  bool operator==(const FaceKey&) const = default;
};

struct FaceKeyHash {
  std::size_t operator()(const FaceKey& f) const noexcept {
    return CellKeyHash{}(f.corner) * 0x9e3779b97f4a7c15ULL ^ f.mask;
  }
};

/// What solving one face found.
template <class S>
struct FaceSolution {
  std::int32_t roots = 0;   ///< the roots found (odd: the face is crossed)
  bool proven = false;      ///< every decision a proof
  bool degenerate = false;  ///< a root within rounding of the face's boundary
  int orientation = 1;      ///< sign of det [J; e_A] at the crossing
  std::vector<S> root;      ///< the first root (n)
};

/// Why a cell is not certified, by the first test it fails.
enum class CellFailure : std::uint8_t { kNone, kCrossing, kGraph, kLink, kBoundary, kUndecided };

const char* failureName(CellFailure f) {
  switch (f) {
    case CellFailure::kCrossing:
      return "crossing";
    case CellFailure::kGraph:
      return "face-graph";
    case CellFailure::kLink:
      return "link";
    case CellFailure::kBoundary:
      return "domain-boundary";
    case CellFailure::kUndecided:
      return "link-undecided";
    case CellFailure::kNone:
      break;
  }
  return "";
}

/// The builder: faces, certificate and mesh of one run.
template <class S>
class HigherCrossing {
 public:
  HigherCrossing(const ConnectionInput<S>& in, int maxFaceDepth)
      : in_(in),
        grid_(in.cells.grid),
        n_(grid_.n),
        k_(in.k),
        m_(n_ - k_),
        top_(std::int32_t(grid_.cellsPerAxis())),
        bits_(grid_.depth + 2),
        maxFaceDepth_(maxFaceDepth),
        domain_(toScalar<S>(grid_.domain)),
        position_(in, grid_),
        subsets_(axisSubsets(n_, k_)),
        chains_(kuhnChains(k_)) {
    for (int fixedCount = 0; fixedCount < k_; ++fixedCount) {
      for (std::vector<int>& fixed : axisSubsets(n_, fixedCount)) {
        FixedChoice choice{std::move(fixed), {}};
        for (int j = 0; j < n_; ++j)
          if (std::find(choice.fixed.begin(), choice.fixed.end(), j) == choice.fixed.end())
            choice.freeAxes.push_back(j);
        fewerFixed_.push_back(std::move(choice));
      }
    }
    // A face's key: its corner, bits_ per axis, then its subset in kSubsetBits.
    if (n_ * bits_ + kSubsetBits > kCellKeyBits || subsets_.size() >= (1u << kSubsetBits)) {
      throw InputError("k = " + std::to_string(k_) + " in R^" + std::to_string(n_) +
                       " supports --depth up to " +
                       std::to_string((kCellKeyBits - kSubsetBits) / n_ - 2));
    }
    // Bernstein slices decide the faces evaluation leaves open (polynomial input only).
    double coefficients = 0;
    for (const Expression& e : in.system.equations()) coefficients += denseCoefficients(e);
    if (in.problem.roots.empty() && coefficients <= 262144) {
      forms_.emplace(in.system.equations(), grid_, domain_, 0);
      const std::vector<std::int32_t> origin(std::size_t(n_), 0);
      rootForms_ = &forms_->root(origin, grid_.depth);
      const S unit = ScalarTraits<S>::epsilon();
      for (std::size_t i = 0; i < rootForms_->size(); ++i) {
        using std::abs;
        const auto [lo, hi] = (*rootForms_)[i].coefficientRange();
        const double relative = i < in.coefficientError.size() ? in.coefficientError[i] : 0.0;
        margins_.push_back((S(relative) + 1024 * unit) * std::max<S>(abs(lo), abs(hi)));
      }
    }
  }

  ConnectionOutput<S> run() {
    ConnectionOutput<S> out;
    out.complex.n = n_;
    out.complex.k = k_;
    addCells();
    // General position: levels until no crossing is within rounding of a face boundary.
    std::int64_t degenerate = 0;
    for (int attempt = 0;; ++attempt) {
      // For m = 1 the sign rule decides (the level set F = -delta, delta -> 0+): level 0.
      level_ = m_ == 1 ? std::vector<S>(1, S(0)) : position_.level(attempt);
      degenerate = solveFaces();
      out.perturbation.attempts = attempt + 1;
      out.perturbation.degenerateCrossings = degenerate;
      out.perturbation.level.clear();
      for (const S& c : level_) out.perturbation.level.push_back(toDouble(c));
      if (degenerate == 0 || m_ == 1 || attempt + 1 == GeneralPosition<S>::kAttempts) break;
    }
    certify(out, degenerate);
    buildMesh(out);
    return out;
  }

 private:
  // ---- cells and faces
  /// The solution cells, then every cell around a crossed face that is not one (M_c enters it
  /// although M only touches it), until no face adds a cell.
  void addCells() {
    for (std::size_t c = 0; c < in_.cells.size(); ++c) addCell(in_.cells.cell(c));
  }

  std::int32_t addCell(std::span<const std::int32_t> index) {
    const CellKey key = grid_.pack(index);
    const auto [it, fresh] = cellOf_.try_emplace(key, std::int32_t(cellCount()));
    if (fresh) cellIndex_.insert(cellIndex_.end(), index.begin(), index.end());
    return it->second;
  }

  std::size_t cellCount() const { return cellIndex_.size() / std::size_t(n_); }
  std::span<const std::int32_t> cellIndex(std::size_t c) const {
    return {cellIndex_.data() + c * n_, std::size_t(n_)};
  }

  /// Packs coordinates in -1 .. 2^L (one more than the grid on each side), bits_ per axis.
  CellKey packWide(std::span<const std::int32_t> v) const {
    CellKey key = 0;
    for (int j = 0; j < n_; ++j) key = (key << bits_) | CellKey(std::uint32_t(v[j] + 1));
    return key;
  }

  /// The faces of cells [from, cellCount()): every m-face of each, once.
  void enumerateFaces(std::size_t from) {
    std::vector<std::int32_t> corner(static_cast<std::size_t>(n_));
    ownedFrom_.resize(from);
    cellFaces_.resize(from * facesPerCell());
    for (std::size_t c = from; c < cellCount(); ++c) {
      ownedFrom_.push_back(std::int32_t(faceAxes_.size()));
      const auto index = cellIndex(c);
      for (std::size_t a = 0; a < subsets_.size(); ++a) {
        const std::vector<int>& axes = subsets_[a];
        for (int side = 0; side < (1 << k_); ++side) {
          std::copy(index.begin(), index.end(), corner.begin());
          for (int t = 0; t < k_; ++t) corner[std::size_t(axes[t])] += (side >> t) & 1;
          const CellKey key = (packWide(corner) << kSubsetBits) | CellKey(a);
          const auto [id, fresh] = faceOf_.insert(key, std::int32_t(faceAxes_.size()));
          cellFaces_.push_back(*id);
          if (fresh) {
            faceCorner_.insert(faceCorner_.end(), corner.begin(), corner.end());
            faceAxes_.push_back(std::int32_t(a));
            faceSide_.push_back(std::uint8_t(side));
          }
        }
      }
    }
  }

  std::span<const std::int32_t> faceCorner(std::size_t f) const {
    return {faceCorner_.data() + f * n_, std::size_t(n_)};
  }

  /// Solves every face at the current level; adds the cells around crossed faces and solves
  /// their faces too. Returns the crossings within rounding of a face boundary.
  std::int64_t solveFaces() {
    faceOf_.clear(), faceCorner_.clear(), faceAxes_.clear(), faceSide_.clear();
    cellFaces_.clear();
    solution_.clear();
    cellIndex_.resize(in_.cells.size() * std::size_t(n_));
    for (auto it = cellOf_.begin(); it != cellOf_.end();)
      it = it->second >= std::int32_t(in_.cells.size()) ? cellOf_.erase(it) : std::next(it);
    std::size_t cellsDone = 0;
    while (cellsDone < cellCount()) {
      const std::size_t facesBefore = faceAxes_.size(), cellsBefore = cellsDone;
      enumerateFaces(cellsDone);
      cellsDone = cellCount();
      ownedFrom_.push_back(std::int32_t(faceAxes_.size()));
      solution_.resize(faceAxes_.size());
      // Each cell's new faces, on its affine model first.
      parallelFor(cellsDone - cellsBefore, [&](std::size_t i) { solveOwned(cellsBefore + i); });
      ownedFrom_.pop_back();
      touchCells(facesBefore);
    }
    facesSolved_ += std::int64_t(faceAxes_.size());
    std::int64_t degenerate = 0;
    for (const FaceSolution<S>& s : solution_) degenerate += s.degenerate;
    return degenerate;
  }

  /// The cells inside the grid around the crossed faces from `from` on, added when new.
  void touchCells(std::size_t from) {
    std::vector<std::int32_t> node(static_cast<std::size_t>(n_));
    for (std::size_t f = from; f < faceAxes_.size(); ++f) {
      if (solution_[f].roots % 2 == 0) continue;
      for (int b = 0; b < (1 << k_); ++b) {
        if (nodeOf(f, b, node)) addCell(node);
      }
    }
  }

  /// Node b of face f's dual cube: the cell corner - 1_A + b (bit t of b raises axis A[t]).
  /// True when it lies inside the grid.
  bool nodeOf(std::size_t f, int b, std::vector<std::int32_t>& node) const {
    const auto corner = faceCorner(f);
    std::copy(corner.begin(), corner.end(), node.begin());
    const std::vector<int>& axes = subsets_[std::size_t(faceAxes_[f])];
    bool inside = true;
    for (int t = 0; t < k_; ++t) {
      std::int32_t& x = node[std::size_t(axes[t])];
      x += ((b >> t) & 1) - 1;
      inside = inside && x >= 0 && x < top_;
    }
    return inside;
  }

  /// The coordinate of grid plane v along axis j, as cellBoxInto computes cell ends.
  S plane(int j, std::int32_t v) const {
    if (v >= top_) return domain_.hi[j];
    const S w = (domain_.hi[j] - domain_.lo[j]) / S(double(top_));
    return domain_.lo[j] + w * S(double(v));
  }

  /// Per-thread storage of solveFace.
  struct FaceWork {
    FaceSolver<S> solver;
    std::vector<S> point;
    std::vector<int> freeAxes;
    Box<S> faceBox, cellBox;
    FaceEnds ends;
    std::vector<std::vector<S>> roots;
    std::vector<Bernstein<S>> patches, slice, cut;
    std::vector<std::int32_t> cell;
  };

  /// Solves face f: by evaluation, then on the Bernstein slices of a cell next to it.
  void solveFace(std::size_t f) {
    std::optional<FaceWork> fresh;
    FaceWork& w = threadScratch<S, FaceWork>(fresh);
    const auto corner = faceCorner(f);
    const std::vector<int>& axes = subsets_[std::size_t(faceAxes_[f])];
    // The face: fixed coordinates on their planes, free ones over one cell.
    w.point.assign(std::size_t(n_), S(0));
    w.freeAxes.clear(), w.faceBox.lo.clear(), w.faceBox.hi.clear();
    w.ends.lower.clear(), w.ends.upper.clear();
    w.cell.assign(corner.begin(), corner.end());
    for (int j = 0; j < n_; ++j) {
      const bool fixed = std::find(axes.begin(), axes.end(), j) != axes.end();
      if (fixed) {
        w.point[j] = plane(j, corner[j]);
        if (corner[j] == top_) --w.cell[std::size_t(j)];
        continue;
      }
      w.freeAxes.push_back(j);
      w.faceBox.lo.push_back(plane(j, corner[j]));
      w.faceBox.hi.push_back(plane(j, corner[j] + 1));
      w.ends.lower.push_back(corner[j] == 0);
      w.ends.upper.push_back(corner[j] + 1 == top_);
    }
    cellBoxInto(grid_, domain_, std::span<const std::int32_t>(w.cell), w.cellBox);
    FaceSolution<S> r;
    w.roots.clear();
    w.solver.reset(in_.system, maxFaceDepth_, std::span<const S>(level_), position_.slack);
    w.solver.setBernsteinCost(sliceCoefficients(axes), rootForms_ != nullptr);
    // Evaluation first for m >= 2; a grid edge (m = 1) by the sign rule on its slice.
    if (m_ > 1 && w.solver.solveByEvaluation(w.point, w.freeAxes, w.faceBox, w.ends, w.roots)) {
      r.proven = true;
    } else if (rootForms_) {
      // The cell's patches, sliced on the fixed axes from the highest down.
      w.roots.clear();
      w.patches.resize(std::size_t(m_)), w.slice.resize(std::size_t(m_));
      for (int i = 0; i < m_; ++i) {
        (*rootForms_)[std::size_t(i)].restrictInto(w.cellBox, w.patches[std::size_t(i)]);
        for (int t = k_ - 1; t >= 0; --t) {
          const bool upper = corner[std::size_t(axes[t])] != w.cell[std::size_t(axes[t])];
          w.patches[std::size_t(i)].faceSliceInto(axes[t], upper, w.slice[std::size_t(i)]);
          std::swap(w.patches[std::size_t(i)], w.slice[std::size_t(i)]);
        }
      }
      const bool certain = w.solver.solve(w.point, w.freeAxes, w.patches, w.ends, w.roots,
                                          std::span<const S>(margins_));
      r.proven = certain && w.solver.proven();
    } else {
      w.roots.clear();
    }
    r.roots = std::int32_t(w.roots.size());
    // An edge's ends are shared by all its edges, so the sign rule needs no general position.
    r.degenerate = m_ > 1 && position_.nearBoundary(w.roots, w.cellBox, w.freeAxes, w.ends) > 0;
    if (!w.roots.empty()) {
      r.root = w.roots.front();
      r.orientation = orientationAt(r.root, axes);
    }
    solution_[f] = std::move(r);
  }

  /// Per-thread storage of solveOwned.
  struct ModelWork {
    LeafModel<S> model;
    Box<S> box;
    std::vector<FacePreconditioner<S>> pre;  ///< per subset of fixed axes
    std::vector<std::uint8_t> built;
  };

  /// The faces cell c added (ownedFrom_[c] .. ownedFrom_[c + 1]): those the cell's affine model
  /// proves M_c misses (faceExcluded, then the face's Krawczyk test) have no crossing; the
  /// others are solved (docs/crossing.md, "Faces by evaluation": the same model as for k = 2).
  void solveOwned(std::size_t c) {
    const auto first = std::size_t(ownedFrom_[c]), last = std::size_t(ownedFrom_[c + 1]);
    if (first == last) return;
    std::optional<ModelWork> fresh;
    ModelWork& w = threadScratch<S, ModelWork>(fresh);
    cellBoxInto(grid_, domain_, cellIndex(c), w.box);
    buildLeafModel(threadEvaluators(in_.system), w.box, std::span<const S>(level_), w.model);
    w.pre.resize(subsets_.size());
    w.built.assign(subsets_.size(), 0);
    for (std::size_t f = first; f < last; ++f) {
      const auto a = std::size_t(faceAxes_[f]);
      const std::span<const int> axes(subsets_[a]);
      if (w.model.valid) {
        if (faceExcluded(w.model, w.box, axes, faceSide_[f])) {
          solution_[f] = excludedFace();
          continue;
        }
        if (!w.built[a]) buildFacePreconditioner(w.model, axes, w.pre[a]), w.built[a] = 1;
        if (w.pre[a].valid && faceKrawczykExcludes(w.model, w.pre[a], w.box, axes, faceSide_[f])) {
          solution_[f] = excludedFace();
          continue;
        }
      }
      solveFace(f);
    }
  }

  /// A face proven to hold no crossing.
  static FaceSolution<S> excludedFace() {
    FaceSolution<S> r;
    r.proven = true;
    return r;
  }

  /// The Bernstein coefficients of all m equations' slices of a face fixing `axes`.
  double sliceCoefficients(const std::vector<int>& axes) const {
    double total = 0;
    for (const Expression& e : in_.system.equations()) {
      const std::vector<int> d = e.degrees();
      double size = 1;
      for (int j = 0; j < n_; ++j)
        if (std::find(axes.begin(), axes.end(), j) == axes.end()) size *= double(d[j] + 1);
      total += size;
    }
    return total;
  }

  /// The sign of det [J(x); e_A] (the rows of J, then the unit rows of the fixed axes): the
  /// orientation M_c induces on the dual cube's axes at its crossing (docs/crossing.md, "Any
  /// k"). Computed in double: only its sign is used, and a crossing proven unique has J's free
  /// block regular.
  int orientationAt(const std::vector<S>& x, const std::vector<int>& axes) const {
    std::vector<S> f(static_cast<std::size_t>(m_)), jacobian(static_cast<std::size_t>(m_ * n_));
    in_.system.evaluate(std::span<const S>(x), std::span<S>(f), std::span<S>(jacobian));
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n_, n_);
    for (int i = 0; i < m_; ++i)
      for (int j = 0; j < n_; ++j) a(i, j) = toDouble(jacobian[std::size_t(i) * n_ + j]);
    for (int t = 0; t < k_; ++t) a(m_ + t, axes[t]) = 1;
    return a.partialPivLu().determinant() < 0 ? -1 : 1;
  }

  // ---- the certificate
  /// Per-thread storage of certifyCell.
  struct CellWork {
    std::vector<S> centre, radius, zero;
    std::vector<Interval<S>> jacobian, fy, intervals;
    std::vector<Interval<S>> whole;  ///< J over the whole cell
    GraphTest<S> test{0, 0};
    Box<S> box, face;
    std::vector<std::int32_t> corner;
  };

  /// Certifies every cell; the record's counts and reason.
  void certify(ConnectionOutput<S>& out, std::int64_t degenerate) {
    failure_.assign(cellCount(), CellFailure::kNone);
    parallelFor(cellCount(), [&](std::size_t c) { failure_[c] = certifyCell(c); });
    TopologyRecord& t = out.topology;
    t.baseLevel = t.maxLevel = grid_.depth;
    t.maxDepth = in_.maxLevel;
    t.facesSolved = facesSolved_;
    std::array<std::int64_t, 6> counts{};
    for (std::size_t c = 0; c < cellCount(); ++c) {
      ++counts[std::size_t(failure_[c])];
      if (failure_[c] == CellFailure::kNone) continue;
      UncertifiedCell u;
      const Box<double> box = cellBox(grid_, grid_.domain, cellIndex(c));
      u.lo = box.lo, u.hi = box.hi;
      u.level = grid_.depth;
      u.reason = failureName(failure_[c]);
      t.uncertified.push_back(std::move(u));
    }
    t.certifiedCells = counts[0];
    t.uncertifiedCells = std::int64_t(cellCount()) - counts[0];
    std::ostringstream why;
    if (t.uncertifiedCells > 0) {
      why << t.uncertifiedCells << " of " << cellCount() << " cells not certified (";
      const char* sep = "";
      for (std::size_t f = 1; f < counts.size(); ++f) {
        if (counts[f] == 0) continue;
        why << sep << failureName(CellFailure(f)) << ": " << counts[f];
        sep = ", ";
      }
      why << ")";
      if (counts[std::size_t(CellFailure::kUndecided)] > 0)
        why << "; for k >= 4 a cell's crossings are only shown to form a homology sphere, "
               "which does not prove a ball";
      why << "; k >= 3 has no adaptive refinement or blocks yet: a larger --depth may certify, "
             "but not where M folds over grid faces at every depth, as a round 3-sphere does "
             "(docs/certificate.md, \"Any k\")";
    }
    if (degenerate > 0) {
      why << (t.uncertifiedCells > 0 ? "; " : "") << degenerate
          << " crossings within rounding of a face boundary";
    }
    t.reason = why.str();
    t.certified = t.reason.empty();
  }

  /// The certificate of cell c (docs/certificate.md, "Any k").
  CellFailure certifyCell(std::size_t c) {
    const auto index = cellIndex(c);
    // Its crossed faces, as (subset, side) with every crossing proven.
    std::vector<std::pair<std::int32_t, int>> crossed;
    const std::int32_t* faces = cellFaces_.data() + c * facesPerCell();
    for (std::size_t a = 0; a < subsets_.size(); ++a) {
      for (int side = 0; side < (1 << k_); ++side) {
        const FaceSolution<S>& s = solution_[std::size_t(*faces++)];
        if (!s.proven || s.roots > 1 || s.degenerate) return CellFailure::kCrossing;
        if (s.roots == 1) crossed.emplace_back(std::int32_t(a), side);
      }
    }
    std::optional<CellWork> fresh;
    CellWork& w = threadScratch<S, CellWork>(fresh);
    cellBoxInto(grid_, domain_, index, w.box);
    // A cell no level set between M and M_c meets needs nothing more.
    if (crossed.empty() && bandMisses(w.box, w)) return CellFailure::kNone;
    if (!graphTests(w)) return CellFailure::kGraph;
    if (!domainBoundary(index, w)) return CellFailure::kBoundary;
    return linkTests(crossed);
  }

  /// Whether no level set F = t c, t in [0, 1], meets `box` (some F_i over it misses the hull
  /// of 0 and c_i): the mean value form F(centre) + J(X) (X - centre), outward rounded.
  bool bandMisses(const Box<S>& box, CellWork& w) const {
    return naturalMisses(box, w) || (encloseAt(box, w) && bandMissed(w));
  }

  /// bandMisses by the natural interval extension of each F_i over `box` (outward rounded): as
  /// tight as the mean value form where it is loose (x^2 over [0.1, 0.2]), and the reverse.
  bool naturalMisses(const Box<S>& box, CellWork& w) const {
    using I = Interval<S>;
    w.intervals.clear();
    for (int j = 0; j < n_; ++j) w.intervals.emplace_back(box.lo[j], box.hi[j]);
    for (int i = 0; i < m_; ++i) {
      const I f = in_.system.equations()[std::size_t(i)].template evaluate<S>(
          std::span<const I>(w.intervals));
      const S lo = std::min<S>(S(0), level_[i]), hi = std::max<S>(S(0), level_[i]);
      if (f.lower() > hi || f.upper() < lo) return true;
    }
    return false;
  }

  /// bandMisses on the enclosure encloseAt left in w.
  bool bandMissed(const CellWork& w) const {
    for (int i = 0; i < m_; ++i) {
      Interval<S> value = w.fy[std::size_t(i)];
      for (int j = 0; j < n_; ++j)
        value += w.jacobian[std::size_t(i) * n_ + j] * Interval<S>(-w.radius[j], w.radius[j]);
      const S lo = std::min<S>(S(0), level_[i]), hi = std::max<S>(S(0), level_[i]);
      if (value.lower() > hi || value.upper() < lo) return true;
    }
    return false;
  }

  /// J(X) over `box` and F at its centre (level 0) into w; false when a run fails.
  bool encloseAt(const Box<S>& box, CellWork& w) const {
    centreAndRadius(box, w.centre, w.radius);
    w.zero.assign(std::size_t(m_), S(0));
    std::vector<int> all(static_cast<std::size_t>(n_));
    std::iota(all.begin(), all.end(), 0);
    bool excluded = false;
    return encloseSystem(threadEvaluators(in_.system), std::span<const S>(w.centre),
                         std::span<const S>(w.radius), std::span<const S>(w.zero),
                         std::span<const int>(all), w.jacobian, w.fy, excluded, false);
  }

  /// The graph test on every face of the cell of dimension above m (fixing fewer than k axes):
  /// on J over the whole cell for each choice of fixed axes, then on each face's own J where
  /// that does not prove it. A face no level set meets passes.
  bool graphTests(CellWork& w) {
    w.test = GraphTest<S>(n_, m_);
    if (!encloseAt(w.box, w)) return false;
    w.whole = w.jacobian;
    for (const FixedChoice& choice : fewerFixed_) {
      const std::vector<int>& fixed = choice.fixed;
      if (w.test.graph(w.whole, choice.freeAxes)) continue;
      // Each face of this choice (the cell itself for none fixed) on its own enclosure.
      for (int side = 0; side < (1 << fixed.size()); ++side) {
        w.face = w.box;
        for (std::size_t t = 0; t < fixed.size(); ++t) {
          const int j = fixed[t];
          w.face.lo[j] = w.face.hi[j] = (side >> t) & 1 ? w.box.hi[j] : w.box.lo[j];
        }
        if (!faceGraph(w, choice.freeAxes)) return false;
      }
    }
    return true;
  }

  /// The graph test of the face w.face on its own enclosure (or no level set meets it), and
  /// where that fails, on the part of the face that the level sets can meet (shrunk).
  bool faceGraph(CellWork& w, const std::vector<int>& freeAxes) const {
    if (naturalMisses(w.face, w)) return true;
    if (!encloseAt(w.face, w)) return false;
    if (bandMissed(w) || w.test.graph(w.jacobian, freeAxes)) return true;
    if (!shrink(w.face, freeAxes, w)) return false;
    return encloseAt(w.face, w) && (bandMissed(w) || w.test.graph(w.jacobian, freeAxes));
  }

  /// Cuts off the halves of `box` along its free axes that no level set between M and M_c
  /// meets (kShrinkRounds halvings per axis at most): every point of M_c in the box stays in
  /// it, so a graph test on what is left holds for the whole box. Where M's fold lies on a grid
  /// plane (a circle x^2 + y^2 = r^2 on a grid centred at 0), the face next to the plane holds
  /// M only in a part away from the plane, where the Jacobian's column is regular. False when
  /// nothing was cut.
  bool shrink(Box<S>& box, const std::vector<int>& freeAxes, CellWork& w) const {
    bool cut = false;
    Box<S> half;
    for (int round = 0; round < kShrinkRounds; ++round) {
      bool progress = false;
      for (int j : freeAxes) {
        const S mid = (box.lo[j] + box.hi[j]) / 2;
        for (int upper = 0; upper < 2; ++upper) {
          half = box;
          (upper ? half.lo[j] : half.hi[j]) = mid;
          if (!bandMisses(half, w)) continue;
          (upper ? box.hi[j] : box.lo[j]) = mid;
          progress = cut = true;
          break;
        }
      }
      if (!progress) break;
    }
    return cut;
  }

  /// Where the cell meets the domain's boundary along the axes D: M (every level set between
  /// M and M_c) is transverse to each face of the domain of dimension m or more (the graph test
  /// on the face's free columns, done above for dimensions above m, here for m-faces) and
  /// misses those of dimension m - 1 (and so every smaller one inside them).
  bool domainBoundary(std::span<const std::int32_t> index, CellWork& w) {
    std::vector<int> onBoundary;
    for (int j = 0; j < n_; ++j)
      if (index[j] == 0 || index[j] + 1 == top_) onBoundary.push_back(j);
    for (int fixedCount : {k_, k_ + 1}) {
      if (fixedCount > static_cast<int>(onBoundary.size()) || fixedCount > n_) continue;
      for (const std::vector<int>& pick : axisSubsets(int(onBoundary.size()), fixedCount)) {
        if (!domainFaces(index, onBoundary, pick, fixedCount == k_, w)) return false;
      }
    }
    return true;
  }

  /// The faces of the cell on the domain's boundary along onBoundary[pick] (both ends where
  /// the cell spans the domain): transverse (`rank`) or missed.
  bool domainFaces(std::span<const std::int32_t> index, const std::vector<int>& onBoundary,
                   const std::vector<int>& pick, bool rank, CellWork& w) {
    std::vector<int> freeAxes;
    for (int j = 0; j < n_; ++j) {
      bool fixed = false;
      for (int p : pick) fixed = fixed || onBoundary[std::size_t(p)] == j;
      if (!fixed) freeAxes.push_back(j);
    }
    for (int side = 0; side < (1 << pick.size()); ++side) {
      w.face = w.box;
      bool onDomain = true;
      for (std::size_t t = 0; t < pick.size(); ++t) {
        const int j = onBoundary[std::size_t(pick[t])];
        const bool upper = (side >> t) & 1;
        onDomain = onDomain && (upper ? index[j] + 1 == top_ : index[j] == 0);
        w.face.lo[j] = w.face.hi[j] = upper ? w.box.hi[j] : w.box.lo[j];
      }
      if (!onDomain || naturalMisses(w.face, w)) continue;
      if (!encloseAt(w.face, w)) return false;
      if (bandMissed(w)) continue;
      if (!rank || !w.test.graph(w.jacobian, freeAxes)) return false;
    }
    return true;
  }

  /// The crossings on every face G of the cell fixing fewer than k axes form a sphere of
  /// dimension k - 1 - |T| (T: the axes G fixes), or none: each crossed m-face in G is a
  /// simplex on the facets of G that hold it (kuhn.hpp, sphereTest). Smaller faces first, so
  /// that a larger face's test may assume its vertex links are spheres.
  CellFailure linkTests(const std::vector<std::pair<std::int32_t, int>>& crossed) const {
    if (crossed.empty()) return CellFailure::kNone;
    bool undecided = false;
    std::vector<std::vector<int>> simplices;
    // fewerFixed_ holds the choices by fixed count up: the last ones fix the most axes.
    for (auto it = fewerFixed_.rbegin(); it != fewerFixed_.rend(); ++it) {
      const std::vector<int>& fixed = it->fixed;
      const int fixedCount = static_cast<int>(fixed.size());
      for (int side = 0; side < (1 << fixedCount); ++side) {
        simplices.clear();
        for (const auto& [a, s] : crossed) {
          if (!inFace(subsets_[std::size_t(a)], s, fixed, side)) continue;
          // The facets of G holding the face: its other fixed axes with their sides.
          std::vector<int> simplex;
          for (int t = 0; t < k_; ++t) {
            const int axis = subsets_[std::size_t(a)][std::size_t(t)];
            if (std::find(fixed.begin(), fixed.end(), axis) == fixed.end())
              simplex.push_back(2 * axis + ((s >> t) & 1));
          }
          simplices.push_back(std::move(simplex));
        }
        const SphereCheck check = sphereTest(k_ - 1 - fixedCount, simplices);
        if (check == SphereCheck::kNotSphere) return CellFailure::kLink;
        undecided = undecided || check == SphereCheck::kUndecided;
      }
    }
    return undecided ? CellFailure::kUndecided : CellFailure::kNone;
  }

  /// Whether the face (axes, side) of a cell lies in its face G that fixes `fixed` at `side`.
  static bool inFace(const std::vector<int>& axes, int side, const std::vector<int>& fixed,
                     int fixedSide) {
    for (std::size_t t = 0; t < fixed.size(); ++t) {
      const auto at = std::find(axes.begin(), axes.end(), fixed[t]);
      if (at == axes.end()) return false;
      const int bit = (side >> (at - axes.begin())) & 1;
      if (bit != ((fixedSide >> t) & 1)) return false;
    }
    return true;
  }

  // ---- the mesh
  /// A node of a dual cube: a cell, or a region beyond the domain, with its pieces.
  struct Node {
    std::vector<std::int32_t> index;
    std::vector<std::int32_t> faces;  ///< its crossed faces
    std::vector<std::int32_t> piece;  ///< per entry of faces: its piece
    std::int32_t pieces = 0, first = -1;
  };

  /// The dual complex: one vertex per piece of each node, k! simplices per crossed face.
  void buildMesh(ConnectionOutput<S>& out) {
    // The nodes of every crossed face, with their incident faces.
    CellMap<std::int32_t> nodeNumber;
    std::vector<Node> nodes;
    std::vector<std::int32_t> index(static_cast<std::size_t>(n_));
    std::vector<std::vector<std::int32_t>> faceNodes(faceAxes_.size());
    for (std::size_t f = 0; f < faceAxes_.size(); ++f) {
      if (solution_[f].roots % 2 == 0) continue;
      for (int b = 0; b < (1 << k_); ++b) {
        nodeOf(f, b, index);
        const auto [it, fresh] =
            nodeNumber.try_emplace(packWide(index), std::int32_t(nodes.size()));
        if (fresh) nodes.push_back(Node{index, {}, {}, 0, -1});
        nodes[std::size_t(it->second)].faces.push_back(std::int32_t(f));
        faceNodes[f].push_back(it->second);
      }
    }
    // Pieces: a node's faces joined where they share an (m+1)-face of it.
    parallelFor(nodes.size(), [&](std::size_t v) { splitPieces(nodes[v]); });
    for (Node& node : nodes) {
      const bool inside = std::all_of(node.index.begin(), node.index.end(),
                                      [this](std::int32_t x) { return x >= 0 && x < top_; });
      if (inside && node.pieces > 1) ++out.ambiguousCells;
    }
    placeVertices(nodes, out);
    writeSimplices(nodes, faceNodes, out.complex);
  }

  /// The pieces of M at a node: its crossed faces joined by shared (m+1)-faces.
  void splitPieces(Node& node) const {
    const std::size_t count = node.faces.size();
    std::vector<int> parent(count);
    std::iota(parent.begin(), parent.end(), 0);
    const auto find = [&parent](int i) {
      while (parent[std::size_t(i)] != i)
        i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
      return i;
    };
    std::unordered_map<FaceKey, int, FaceKeyHash> owner;
    std::vector<std::int32_t> g(static_cast<std::size_t>(n_));
    for (std::size_t q = 0; q < count; ++q) {
      const auto f = std::size_t(node.faces[q]);
      const std::vector<int>& axes = subsets_[std::size_t(faceAxes_[f])];
      const auto corner = faceCorner(f);
      for (int drop = 0; drop < k_; ++drop) {
        // The (m+1)-face of the node: axis `drop` freed over the node's extent.
        std::copy(corner.begin(), corner.end(), g.begin());
        g[std::size_t(axes[drop])] = node.index[std::size_t(axes[drop])];
        std::uint64_t mask = 0;
        for (int t = 0; t < k_; ++t)
          if (t != drop) mask |= std::uint64_t{1} << axes[t];
        const auto [it, fresh] = owner.try_emplace(FaceKey{packWide(g), mask}, int(q));
        if (!fresh) parent[std::size_t(find(int(q)))] = find(it->second);
      }
    }
    node.piece.assign(count, -1);
    std::vector<int> label(count, -1);
    for (std::size_t q = 0; q < count; ++q) {
      const int r = find(int(q));
      if (label[std::size_t(r)] < 0) label[std::size_t(r)] = node.pieces++;
      node.piece[q] = label[std::size_t(r)];
    }
  }

  /// Each piece's vertex: the mean of its crossings, projected onto M (a cell) or onto M ∩ the
  /// domain's face (a region beyond the domain; its coordinates beyond are set on the face).
  void placeVertices(std::vector<Node>& nodes, ConnectionOutput<S>& out) const {
    Complex<S>& complex = out.complex;
    std::size_t total = complex.vertexCount();
    for (Node& node : nodes) {
      node.first = std::int32_t(total);
      total += std::size_t(node.pieces);
    }
    const std::size_t base = complex.vertexCount();
    complex.vertices.resize(total * n_);
    complex.vertexCell.resize(total, -1);
    std::vector<std::uint8_t> failed(total - base, 0);
    parallelFor(nodes.size(), [&](std::size_t v) {
      const Node& node = nodes[v];
      std::vector<S> sums(std::size_t(node.pieces) * n_, S(0));
      std::vector<int> counts(std::size_t(node.pieces), 0);
      for (std::size_t q = 0; q < node.faces.size(); ++q) {
        const std::vector<S>& root = solution_[std::size_t(node.faces[q])].root;
        for (int j = 0; j < n_; ++j) sums[std::size_t(node.piece[q]) * n_ + j] += root[j];
        ++counts[std::size_t(node.piece[q])];
      }
      std::vector<int> freeAxes;
      for (int j = 0; j < n_; ++j)
        if (node.index[j] >= 0 && node.index[j] < top_) freeAxes.push_back(j);
      const bool inside = int(freeAxes.size()) == n_;
      const std::int32_t cell =
          inside ? in_.cells.find(grid_.pack(std::span<const std::int32_t>(node.index))) : -1;
      for (int q = 0; q < node.pieces; ++q) {
        const std::size_t at = std::size_t(node.first + q);
        const std::span<S> x(complex.vertices.data() + at * n_, std::size_t(n_));
        for (int j = 0; j < n_; ++j) {
          x[j] = sums[std::size_t(q) * n_ + j] / S(counts[std::size_t(q)]);
          if (node.index[j] < 0) x[j] = domain_.lo[j];
          if (node.index[j] >= top_) x[j] = domain_.hi[j];
        }
        const std::vector<S> mean(x.begin(), x.end());
        const bool ok = inside ? in_.project(x).converged : faceNewton(in_.system, x, freeAxes);
        if (!ok) {
          std::copy(mean.begin(), mean.end(), x.begin());
          failed[at - base] = 1;
        }
        complex.vertexCell[at] = cell;
      }
    });
    out.offManifoldVertices += std::count(failed.begin(), failed.end(), std::uint8_t{1});
  }

  /// k! simplices per crossed face, each a Kuhn chain of its dual cube's nodes, oriented by the
  /// chain's sign times the crossing's orientation.
  void writeSimplices(const std::vector<Node>& nodes,
                      const std::vector<std::vector<std::int32_t>>& faceNodes,
                      Complex<S>& complex) const {
    std::vector<std::int32_t> simplex(static_cast<std::size_t>(k_ + 1));
    for (std::size_t f = 0; f < faceAxes_.size(); ++f) {
      if (faceNodes[f].empty()) continue;
      // The vertex of node b for this face: its piece holding the face.
      const auto vertexOf = [&](int b) {
        const Node& node = nodes[std::size_t(faceNodes[f][std::size_t(b)])];
        const auto q =
            std::find(node.faces.begin(), node.faces.end(), std::int32_t(f)) - node.faces.begin();
        return node.first + node.piece[std::size_t(q)];
      };
      for (const KuhnChain& chain : chains_) {
        int b = 0;
        simplex[0] = vertexOf(b);
        for (int t = 0; t < k_; ++t) {
          b |= 1 << chain.order[std::size_t(t)];
          simplex[std::size_t(t + 1)] = vertexOf(b);
        }
        if (chain.sign * solution_[f].orientation < 0) std::swap(simplex[0], simplex[1]);
        complex.addSimplex(simplex);
      }
    }
  }

  /// The bits of a face key that hold its subset of fixed axes.
  static constexpr int kSubsetBits = 16;
  /// The minimal m-faces of one cell: C(n, k) 2^k.
  std::size_t facesPerCell() const { return subsets_.size() << k_; }

  /// Halvings per axis of shrink.
  static constexpr int kShrinkRounds = 4;

  const ConnectionInput<S>& in_;
  const Grid& grid_;
  int n_, k_, m_;
  std::int32_t top_;  ///< cells per axis
  int bits_;          ///< per axis in packWide
  int maxFaceDepth_;
  Box<S> domain_;
  GeneralPosition<S> position_;
  std::vector<std::vector<int>> subsets_;  ///< the k-subsets of axes a face may fix
  std::vector<KuhnChain> chains_;
  /// A choice of fewer than k fixed axes (a face of dimension above m) and its free axes.
  struct FixedChoice {
    std::vector<int> fixed, freeAxes;
  };
  /// Every such choice, by the number of fixed axes up (none first: the cell itself).
  std::vector<FixedChoice> fewerFixed_;
  std::optional<CellForms<S>> forms_;
  const std::vector<Bernstein<S>>* rootForms_ = nullptr;
  std::vector<S> margins_;
  std::vector<S> level_;
  std::vector<std::int32_t> cellIndex_;  ///< n per cell: solution cells, then touch cells
  CellMap<std::int32_t> cellOf_;
  FlatMap<CellKey, std::int32_t> faceOf_;  ///< by corner and subset
  /// Per cell, its faces in the order (subset, side): facesPerCell() of them.
  std::vector<std::int32_t> cellFaces_;
  std::vector<std::int32_t> faceCorner_;  ///< n per face
  std::vector<std::int32_t> faceAxes_;    ///< its subset
  std::vector<std::uint8_t> faceSide_;    ///< its side in the cell that added it (bit t: axes[t])
  std::vector<std::int32_t> ownedFrom_;   ///< per cell: the first face it added
  std::vector<FaceSolution<S>> solution_;
  std::vector<CellFailure> failure_;
  std::int64_t facesSolved_ = 0;
};

}  // namespace

template <class S>
ConnectionOutput<S> higherCrossing(const ConnectionInput<S>& in, int maxFaceDepth) {
  return HigherCrossing<S>(in, maxFaceDepth).run();
}

template ConnectionOutput<double> higherCrossing(const ConnectionInput<double>&, int);
template ConnectionOutput<Mpfr> higherCrossing(const ConnectionInput<Mpfr>&, int);

}  // namespace ndc::crossing_detail
