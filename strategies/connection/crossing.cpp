#include "strategies/connection/crossing.hpp"

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <sstream>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "framework/core/bernstein.hpp"
#include "framework/core/budget.hpp"
#include "framework/core/cell_forms.hpp"
#include "framework/core/interval.hpp"
#include "framework/core/iteration.hpp"
#include "framework/core/midrad.hpp"
#include "framework/core/parallel.hpp"
#include "strategies/connection/cell_tree.hpp"
#include "strategies/connection/certificate.hpp"
#include "strategies/connection/domain_boundary.hpp"
#include "strategies/connection/dual_complex.hpp"
#include "strategies/connection/dual_polygon.hpp"
#include "strategies/connection/face_solver.hpp"
#include "strategies/connection/jacobian_work.hpp"
#include "strategies/connection/leaf_model.hpp"

namespace ndc {
namespace {

using namespace crossing_detail;

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

/// The level c of the perturbed system F = c whose crossings with the grid faces decide the
/// dual cells (docs/crossing.md, "General position"). M itself may pass through vertices,
/// edges and faces of the grid; by Sard's theorem almost every nearby level set meets every
/// face of the grid transversally and misses its lower-dimensional faces. c_i is a fixed
/// irrational fraction of `kRelative` times the cell width times the gradient scale of F_i,
/// so F = c lies about 1e-8 cell widths from M: far above rounding, far below any feature
/// the grid resolves. The grid, the domain and the B-spline knot planes stay where they are.
template <class S>
struct GeneralPosition {
  static constexpr int kAttempts = 4;
  static constexpr double kRelative = 1.0 / (1 << 26);

  GeneralPosition(const ConnectionInput<S>& in, const Grid& grid) {
    using std::abs;
    using std::sqrt;
    const int n = grid.n, m = in.system.m();
    S width = S(grid.cellWidth(0));
    for (int j = 1; j < n; ++j) width = std::min<S>(width, S(grid.cellWidth(j)));
    // Gradient scale of each F_i: the median gradient norm at (a sample of) the projected cell
    // points that Newton brought onto M. Points where it failed can lie far off M, with
    // gradients orders of magnitude larger (interval bounding keeps many such cells).
    const std::size_t count = in.cells.size();
    std::vector<std::size_t> onM;
    for (std::size_t c = 0; c < count; ++c) {
      if (in.projections.converged[c]) onM.push_back(c);
    }
    if (onM.empty()) {
      for (std::size_t c = 0; c < count; ++c) onM.push_back(c);
    }
    const std::size_t stride = std::max<std::size_t>(1, onM.size() / 256);
    std::vector<std::vector<S>> norms(m);
    std::vector<S> f(m), jacobian(std::size_t(m) * n);
    for (std::size_t t = 0; t < onM.size(); t += stride) {
      in.system.evaluate(in.projections.at(onM[t]), f, jacobian);
      for (int i = 0; i < m; ++i) {
        S norm = 0;
        for (int j = 0; j < n; ++j)
          norm += jacobian[std::size_t(i) * n + j] * jacobian[std::size_t(i) * n + j];
        norms[i].push_back(sqrt(norm));
      }
    }
    scale.assign(m, S(0));
    for (int i = 0; i < m; ++i) {
      auto middle = norms[i].begin() + norms[i].size() / 2;
      std::nth_element(norms[i].begin(), middle, norms[i].end());
      if (middle != norms[i].end()) scale[i] = *middle;
    }
    for (S& g : scale) {
      if (!(g > 0)) g = 1;
      g *= width * S(kRelative);
    }
    slack = 64 * width * S(kRelative);
    tolerance = width * S(kRelative) / 64;
  }

  /// The level of attempt a: c_i = theta_{a,i} * scale_i with theta in [0.5, 1) from the
  /// golden-ratio sequence (no two attempts or equations share a ratio).
  std::vector<S> level(int attempt) const {
    std::vector<S> c(scale.size());
    for (std::size_t i = 0; i < scale.size(); ++i) {
      const double t = std::fmod(0.6180339887498949 * double(attempt * 7 + i + 1), 1.0);
      c[i] = S(0.5 + 0.5 * t) * scale[i];
    }
    return c;
  }

  /// How many of a face's roots lie within the tolerance of one of its grid (not domain)
  /// boundaries: there the face and its neighbour could disagree about the root.
  std::int64_t nearBoundary(const std::vector<std::vector<S>>& roots, const Box<S>& box,
                            const std::vector<int>& freeAxes, const FaceEnds& ends) const {
    using std::abs;
    std::int64_t near = 0;
    for (const auto& r : roots) {
      for (std::size_t t = 0; t < freeAxes.size(); ++t) {
        const int j = freeAxes[t];
        if ((!ends.lower[t] && abs(r[j] - box.lo[j]) < tolerance) ||
            (!ends.upper[t] && abs(box.hi[j] - r[j]) < tolerance)) {
          ++near;
          break;
        }
      }
    }
    return near;
  }

  std::vector<S> scale;  ///< kRelative * cell width * gradient scale, per equation
  S slack;               ///< crossings kept this far outside the domain
  S tolerance;           ///< a root this close to a face boundary is degenerate
};

/// Where a minimal m-face lies: its level, the index of its lower corner there and its k fixed
/// axes.
struct FaceRef {
  int level = 0;
  std::vector<std::int32_t> corner;
  std::array<int, 2> axes{};
};

/// What the face solver found on one minimal m-face (cached: a face is solved once per level c).
template <class S>
struct FaceResult {
  std::vector<S> root;          ///< the first root (n coordinates), if any
  int roots = 0;                ///< how many roots
  int degree = 0;               ///< faceDegree
  bool certain = true;          ///< every root decided (else its cells are singular cells)
  bool proven = true;           ///< every decision a proof (FaceSolver::proven)
  bool withinRounding = false;  ///< FaceSolver::withinRounding
  std::int64_t degenerate = 0;  ///< roots within rounding of the face's boundary
};

/// A solved face as FaceStore keeps it: a FaceResult whose root lies in the store's pool.
struct FaceRecord {
  std::int64_t root = -1;  ///< offset of the first root's coordinates in its chunk's pool, or -1
  std::int64_t degenerate = 0;  ///< as FaceResult
  std::uint32_t kind = 0;       ///< which face of its leaf (AdaptiveCrossing::faceKind)
  int roots = 0, degree = 0;
  bool certain = true, proven = true, withinRounding = false;
};

/// The solved faces of every leaf, kept across the refinement's rounds. A leaf's faces are
/// solved together (one task of a window), so its records form one block, sorted by kind:
/// finding one is a binary search of its leaf's block (up to 4 C(n, 2) records: 60 in R^6).
/// Each window's blocks go into a chunk of their own, sized exactly (nothing is allocated per
/// face, nothing is hashed, and no growing array is copied), with the roots in the chunk's pool.
/// A leaf that gets new faces in a later round moves its block to the first chunk, which grows.
template <class S>
class FaceStore {
 public:
  explicit FaceStore(int n) : n_(n) {}

  void clear() {
    blocks_.clear();
    chunks_.assign(1, Chunk{});
  }

  /// Face `kind` of `leaf`, or null. The pointer stays valid until the next add.
  const FaceRecord* find(std::int32_t leaf, std::uint32_t kind) const {
    if (std::size_t(leaf) >= blocks_.size()) return nullptr;
    const Block& b = blocks_[std::size_t(leaf)];
    if (b.count == 0) return nullptr;
    const std::vector<FaceRecord>& records = chunks_[std::size_t(b.chunk)].records;
    const auto first = records.begin() + b.first, last = first + b.count;
    const auto it = std::lower_bound(first, last, kind, byKind);
    return it != last && it->kind == kind ? &*it : nullptr;
  }

  /// Face `kind` of `leaf` (kept) as the face solver gave it.
  FaceResult<S> result(std::int32_t leaf, const FaceRecord& r) const {
    std::vector<S> root;
    if (r.root >= 0) {
      const auto& pool = chunks_[std::size_t(blocks_[std::size_t(leaf)].chunk)].roots;
      root.assign(pool.begin() + r.root, pool.begin() + r.root + n_);
    }
    return FaceResult<S>{std::move(root), r.roots,          r.degree,    r.certain,
                         r.proven,        r.withinRounding, r.degenerate};
  }

  /// Keeps face `kind` of `leaf` (not kept yet), in the first chunk.
  void add(std::int32_t leaf, std::uint32_t kind, const FaceResult<S>& r) {
    if (std::size_t(leaf) >= blocks_.size()) blocks_.resize(std::size_t(leaf) + 1);
    Block& b = blocks_[std::size_t(leaf)];
    Chunk& tail = chunks_.front();
    const auto end = static_cast<std::int64_t>(tail.records.size());
    if (b.count > 0 && (b.chunk != 0 || b.first + b.count != end)) {
      // The leaf's block is elsewhere (a window's chunk, or not last): copy it, with its roots,
      // to the end of the first chunk, where it can grow (through copies: a vector may not
      // insert a range of itself).
      const Chunk& from = chunks_[std::size_t(b.chunk)];
      std::vector<FaceRecord> block(from.records.begin() + b.first,
                                    from.records.begin() + b.first + b.count);
      std::vector<S> roots;
      for (FaceRecord& moved : block) {
        if (moved.root < 0) continue;
        const auto at = from.roots.begin() + moved.root;
        moved.root = static_cast<std::int64_t>(tail.roots.size() + roots.size());
        roots.insert(roots.end(), at, at + n_);
      }
      tail.records.insert(tail.records.end(), block.begin(), block.end());
      tail.roots.insert(tail.roots.end(), roots.begin(), roots.end());
      b.first = end;
      b.chunk = 0;
    } else if (b.count == 0) {
      b.first = end;
      b.chunk = 0;
    }
    const FaceRecord kept = record(kind, r, r.root.empty() ? -1 : std::int64_t(tail.roots.size()));
    tail.roots.insert(tail.roots.end(), r.root.begin(), r.root.end());
    // The block is the last one now: insert in kind order.
    const auto at =
        std::lower_bound(tail.records.begin() + b.first, tail.records.end(), kind, byKind);
    tail.records.insert(at, kept);
    ++b.count;
  }

  /// Keeps the faces a window of leaves solved: `solved(i)`, a range of (kind, FaceResult) in
  /// kind order, are the new faces of leaves[i] (ascending). A leaf with faces of an earlier
  /// round takes add; the others' blocks go into a new chunk, placed by prefix sums and filled
  /// in parallel, each task writing only its leaf's block.
  template <class Solved>
  void addBlocks(std::span<const std::int32_t> leaves, const Solved& solved) {
    if (leaves.empty()) return;
    if (blocks_.size() <= std::size_t(leaves.back()))
      blocks_.resize(std::size_t(leaves.back()) + 1);
    for (std::size_t i = 0; i < leaves.size(); ++i) {
      if (blocks_[std::size_t(leaves[i])].count == 0) continue;
      for (const auto& [kind, r] : solved(i)) add(leaves[i], kind, r);
    }
    // The fresh leaves' places: records and roots in leaf order.
    const auto chunk = static_cast<std::int32_t>(chunks_.size());
    std::vector<std::int64_t> rootAt(leaves.size(), -1);
    std::int64_t records = 0;
    std::size_t roots = 0;
    std::vector<std::size_t> fresh;
    for (std::size_t i = 0; i < leaves.size(); ++i) {
      Block& b = blocks_[std::size_t(leaves[i])];
      const auto& list = solved(i);
      if (b.count > 0 || list.empty()) continue;
      fresh.push_back(i);
      b = Block{chunk, static_cast<std::int32_t>(list.size()), records};
      records += b.count;
      rootAt[i] = static_cast<std::int64_t>(roots);
      for (const auto& entry : list) roots += entry.second.root.size();
    }
    if (fresh.empty()) return;
    Chunk& c = chunks_.emplace_back();
    c.records.resize(std::size_t(records));
    c.roots.resize(roots);
    parallelFor(fresh.size(), [&](std::size_t f) {
      const std::size_t i = fresh[f];
      auto out = c.records.begin() + blocks_[std::size_t(leaves[i])].first;
      std::int64_t root = rootAt[i];
      for (const auto& [kind, r] : solved(i)) {
        *out++ = record(kind, r, r.root.empty() ? -1 : root);
        std::copy(r.root.begin(), r.root.end(), c.roots.begin() + root);
        root += static_cast<std::int64_t>(r.root.size());
      }
    });
  }

 private:
  struct Block {
    std::int32_t chunk = 0;
    std::int32_t count = 0;
    std::int64_t first = 0;
  };
  struct Chunk {
    std::vector<FaceRecord> records;
    std::vector<S> roots;
  };
  static bool byKind(const FaceRecord& r, std::uint32_t kind) { return r.kind < kind; }
  /// The record of face `kind` solved as `r`, its root at `root` in its chunk's pool (-1: none).
  static FaceRecord record(std::uint32_t kind, const FaceResult<S>& r, std::int64_t root) {
    return FaceRecord{root,     r.degenerate, kind,     r.roots,
                      r.degree, r.certain,    r.proven, r.withinRounding};
  }
  int n_;
  std::vector<Block> blocks_;                          ///< per leaf
  std::vector<Chunk> chunks_ = std::vector<Chunk>(1);  ///< the first grows (add); then per window
};

/// Why a leaf is not certified (docs/certificate.md); the names go to uncertified.csv.
enum class Failure : std::uint8_t { kNone, kCrossing, kGraph, kFaceGraph, kLink, kBoundary };

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

/// The crossing connection on an adaptive 2^n-tree: crossings on the minimal m-faces, the
/// certificate of every leaf, refinement of the leaves that fail it, and the dual complex.
template <class S>
class AdaptiveCrossing {
 public:
  /// Reweighted least-squares steps of a face's multiplier test (faceMultipliersExclude), as in
  /// the linearized bounding.
  static constexpr int kFaceMultiplierSteps = 8;
  /// A leaf's facet mask (facetMask) when nothing is known: every facet may meet M_c.
  static constexpr std::uint64_t kAllFacets = ~std::uint64_t{0};

  AdaptiveCrossing(const ConnectionInput<S>& in, int maxFaceDepth)
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
    setBudget(in.cells.size(), in.tolerance > 0, in.refineSeconds);
  }

  /// The certified mesh, refining where the certificate fails. When refinement does not reach a
  /// certificate and its mesh has more non-manifold defects than the base grid's (crossings at
  /// the scale of the level offset c, docs/certificate.md "Status"), the base grid's is kept.
  ConnectionOutput<S> run() {
    ConnectionOutput<S> out = attempts();
    if (out.topology.certified || refined_ == 0) return out;
    const std::int64_t refinedDefects = nonmanifold(out.complex);
    const int reached = out.topology.maxLevel;
    refining_ = false;
    ConnectionOutput<S> base = attempts();
    const std::int64_t baseDefects = nonmanifold(base.complex);
    if (baseDefects >= refinedDefects) return out;
    base.topology.reason +=
        "; refinement down to level " + std::to_string(reached) + " did not certify and left " +
        std::to_string(refinedDefects) +
        " non-manifold edges or branch vertices, so the base grid's mesh is kept";
    return base;
  }

  /// The refinement budget (docs/certificate.md "Adaptive refinement"). Solution leaves, those
  /// the bounding cannot exclude, carry the cost of certification: thin features need a few
  /// times the base cells (genus2 at depth 5: 8x, the thin torus at depth 3: 50x, so at least
  /// 65536 in R^3); where refinement cannot succeed (tangency along a curve through grid
  /// vertices) it bounds the cost. A leaf costs more as n grows, so the floor shrinks by 16 per
  /// dimension, to 4096 from R^4 on. The children the bounding excludes cost one bounding test
  /// each, but a refinement makes 2^n of them (a curve in R^7: 128 per refined cell, about 2 of
  /// them solution leaves), so they get their own, wider budget: 2^(n-k) times the first (the
  /// children that come with each solution child; at least 2 times), at most 2^22 leaves
  /// (memory). A chord error the user asks for (--tolerance) may need many more solution
  /// leaves: up to 2^22 (a few hundred MB); the CLI warns when it is not reached.
  /// A leaf of high degree costs more (restricting a form of degree 512 costs 2.4e6
  /// operations, a torus's 1875): the solution leaves are also capped by their work,
  /// `refineSeconds` of the time model (budget.hpp; a quarter of --timeout when that is less),
  /// so x^512 + y^2 + z^2 - 1, whose forms exclude nothing in double, stops refining at once
  /// instead of running for an hour.
  void setBudget(std::size_t baseCells, bool tolerance, double refineSeconds) {
    maxSolutionLeaves_ = std::max<std::size_t>(
        16 * baseCells, std::size_t{1} << std::max(12, 16 - 4 * (grid_.n - 3)));
    if (tolerance) maxSolutionLeaves_ = std::max<std::size_t>(maxSolutionLeaves_, kMaxLeaves);
    const double byWork = refineSeconds / (workPerCell(in_.problem) * kSecondsPerWork);
    if (byWork < static_cast<double>(maxSolutionLeaves_))
      maxSolutionLeaves_ = static_cast<std::size_t>(std::max(byWork, 1.0));
    const std::size_t perSolutionChild = std::size_t{1} << std::max(1, n_ - k_);
    maxLeaves_ = maxSolutionLeaves_ >= kMaxLeaves / perSolutionChild
                     ? kMaxLeaves
                     : perSolutionChild * maxSolutionLeaves_;
  }

  /// Whether refining `refine` leaves stays within the budget: the leaves it adds at most, and
  /// the solution leaves it adds, predicted from the solution children per refined leaf so far
  /// (2^k before the first refinement: a k-manifold through a cell meets about 2^k children).
  bool withinBudget(std::size_t refine) const {
    const std::size_t children = refine << n_;
    const double perLeaf =
        refined_ > 0 ? double(solutionChildren_) / double(refined_) : double(1 << k_);
    const auto predicted = static_cast<std::size_t>(double(refine) * perLeaf);
    return tree_.size() + children <= maxLeaves_ &&
           tree_.solutionLeaves() + predicted <= maxSolutionLeaves_;
  }

  /// Edges of more than two triangles (k = 2) or vertices of more than two edges (k = 1).
  static std::int64_t nonmanifold(const Complex<S>& complex) {
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

  /// Level offsets until no crossing is within rounding of a face boundary, each with its
  /// refinement and certificate; the complex of the last.
  ConnectionOutput<S> attempts() {
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

 private:
  using Occ = Occupant::Kind;

  /// The root forms a leaf's patches are restricted from (cellForms_: the domain's, or the
  /// B-spline patch's), with the rounding margin of each equation.
  struct RootForms {
    const std::vector<Bernstein<S>>* forms = nullptr;
    std::vector<S> margins;
  };

  /// The patches of one leaf, restricted on first use, and the graph tests' scratch.
  struct LeafTests {
    std::vector<Bernstein<S>>& patches;  ///< leafScratch's
    std::vector<Interval<S>> jacobian;
    GraphTest<S> test;
    bool ready = false;
    /// J over the whole leaf by evaluation (leafJacobian): -1 not yet, 0 a run failed, 1 in
    /// `whole`, with `wholeExcluded` (some F_i - c_i provably has no zero on the leaf).
    std::int8_t wholeKnown = -1;
    bool wholeExcluded = false;
    std::vector<Interval<S>> whole;
  };

  /// A block certified by a task of mergeBlocks, before it is numbered.
  struct NewBlock {
    std::int32_t leaf = -1;  ///< the leaf that made it
    int level = 0;
    bool tentative = false;
    std::vector<std::int32_t> lo, members;
    std::vector<CellKey> empties;
    std::vector<Failure> saved;  ///< the members' failures before
  };

  /// A task of mergeBlocks: the scratch of a block's graph tests and the blocks it made.
  struct BlockWork {
    std::vector<Bernstein<S>> patches;
    std::vector<Interval<S>> jacobian;
    GraphTest<S> test;
    std::vector<NewBlock> made;
  };

  const RootForms& rootForms(std::span<const std::int32_t> index, int level) {
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

  Box<S> leafBox(std::int32_t leaf) const {
    return cellBox(tree_.grid(tree_.level(leaf)), domain_, tree_.index(leaf));
  }

  /// The leaf's Bernstein patches into `patches`, whether they prove that M_c misses the
  /// closed leaf (returned; then no face of it is crossed) and whether no level set
  /// F = t c, t in [0, 1], meets it either (`band`: M itself, and the isotopy from M to M_c).
  /// Reads only: safe in parallel tasks.
  bool restrictLeaf(std::int32_t leaf, const RootForms& rf, std::vector<Bernstein<S>>& patches,
                    bool& band) const {
    const Box<S> box = leafBox(leaf);
    patches.resize(m_);
    bool empty = false;
    band = false;
    for (int i = 0; i < m_; ++i) {
      (*rf.forms)[i].restrictInto(box, patches[i]);
      const S c = level_[i];
      empty = empty || clearsRange(patches[i], c, c, rf.margins[i]);
      band = band ||
             clearsRange(patches[i], std::min<S>(S(0), c), std::max<S>(S(0), c), rf.margins[i]);
    }
    return empty;
  }

  /// The root forms of every leaf in `leaves` (rootForms, which fills its cache: call it
  /// before a parallel loop reads them).
  std::vector<const RootForms*> rootFormsOf(const std::vector<std::int32_t>& leaves) {
    std::vector<const RootForms*> forms;
    forms.reserve(leaves.size());
    for (std::int32_t c : leaves) forms.push_back(&rootForms(tree_.index(c), tree_.level(c)));
    return forms;
  }

  /// solveFace's working storage, per thread (threadScratch): a face solved allocates little
  /// besides the roots it finds.
  struct FaceWork {
    FaceSolver<S> solver;
    std::vector<Bernstein<S>> face, cut;  ///< the face slices, and the first cut when k = 2
    FaceEnds ends;
    std::vector<int> freeAxes;
    std::vector<S> point;
    Box<S> box, faceBox;
    std::vector<std::vector<S>> roots;
  };

  /// Solves face (axes, side) of `leaf`; reads only, so faces are solved in parallel (a
  /// FaceSolver per thread, reset per call). For m >= 2 the face is first solved by evaluation of
  /// the programs (FaceSolver::solveByEvaluation); only a face that decides nothing so is solved on
  /// the Bernstein slices of the leaf's patches, which `patches()` returns (restrictLeaf, on first
  /// use) with the margins `margins`. With the leaf's `model`, the face is first tried for
  /// exclusion by it; `preconditioner()` gives the Krawczyk test's preconditioner of the face's
  /// axes (or null), asked for only when the model's enclosure alone does not exclude the face.
  template <class Patches, class Preconditioner>
  FaceResult<S> solveFace(std::int32_t leaf, const std::array<int, 2>& axes, int side,
                          Patches&& patches, std::span<const S> margins, const LeafModel<S>* model,
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
    if (m_ > 1 && byEvaluation_ &&
        solver.solveByEvaluation(w.point, w.freeAxes, w.faceBox, w.ends, w.roots,
                                 multipliersExclude)) {
      r.certain = r.proven = true;
    } else {
      w.roots.clear();
      faceSlices(patches(), axes, side, w.face, w.cut);
      r.certain = solver.solve(w.point, w.freeAxes, w.face, w.ends, w.roots, margins);
      r.proven = solver.proven();
      r.withinRounding = solver.withinRounding();
    }
    return faceOutcome(std::move(r), w.roots, box, w.freeAxes, w.ends);
  }

  /// The face slices (axes, side) of a leaf's patches into `face` (`cut`: scratch).
  void faceSlices(const std::vector<Bernstein<S>>& patches, const std::array<int, 2>& axes,
                  int side, std::vector<Bernstein<S>>& face, std::vector<Bernstein<S>>& cut) const {
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

  /// The rest of solveFace: the roots' degree and degeneracy.
  FaceResult<S> faceOutcome(FaceResult<S> r, const std::vector<std::vector<S>>& roots,
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

  /// One pass over the minimal m-faces of the active leaves: the polygons of the crossed ones
  /// (excluded base cells around a crossed face become touch leaves, walked in turn) and the
  /// leaves next to a face whose crossings are not proven. Returns the degenerate crossings.
  /// The leaves go in windows: a window's faces are solved in parallel (startWindow), and while
  /// the walk takes one window's answers in leaf order from its slots, the faces it solved are
  /// kept and the next window is solved beside it. The tasks write nothing the walk reads but
  /// the slots of the window walked next, and the walk defers the touch leaves it adds to the
  /// tree until they are done (finishWindow), so nothing depends on the thread count.
  std::int64_t crossFaces() {
    polygons_.clear();
    rootPoints_.clear();
    unprovenFaces_.clear();
    unprovenOf_.clear();
    unprovenOfEmpty_.clear();
    touchLeaves_.clear();
    std::int64_t degenerate = 0;
    TaskBeside beside;  // a local: an exception out of the walk never leaves the task running
    Window* now = &windows_[0];
    Window* next = &windows_[1];
    std::int32_t from = 0;
    bool ready = false;  // whether `now` holds the window at `from`, solved
    while (true) {
      if (!ready) {
        startWindow(beside, from, *now, nullptr);
        finishWindow(beside);
      }
      if (now->from == now->end) return degenerate;  // every leaf walked and its faces kept
      startWindow(beside, now->end, *next, now);
      degenerate += walkWindow(*now);
      finishWindow(beside);
      std::swap(now, next);
      // An empty next window: the tree ended there when it started (touch leaves may follow).
      ready = now->from < now->end;
      from = now->from;
    }
  }

  /// A minimal m-face a leaf owns: its kind (a, side) and the leaves around it (kLeaf; any
  /// other region is looked up again by faceAround).
  struct OwnedFace {
    std::uint8_t a = 0, side = 0;
    std::array<Occupant, 4> around;  ///< as found when the list was made
  };

  /// The faces leaf c owns, in the order crossFaces walks them, into `out`. Touch leaves, which
  /// crossFaces adds at excluded base cells, change neither which faces are minimal (a base-level
  /// leaf where there was none is never finer) nor who owns them (a touch leaf comes after every
  /// leaf already there), so this list stays valid for the whole walk.
  void ownedFaces(std::int32_t c, std::uint64_t facets, std::vector<OwnedFace>& out) const {
    const int level = tree_.level(c);
    // Per-thread scratch (ownedFaces runs in prefetchLeaf's tasks): no allocation per leaf.
    thread_local std::vector<std::int32_t> ci, position;
    ci.assign(tree_.index(c).begin(), tree_.index(c).end());
    position.resize(n_);
    // The region at c's index moved by d0 along axis a0 and by d1 along a1 (a1 < 0: none).
    const auto lookup = [&](int a0, int d0, int a1, int d1) {
      std::copy(ci.begin(), ci.end(), position.begin());
      position[a0] += d0;
      if (a1 >= 0) position[a1] += d1;
      return tree_.find(level, position);
    };
    // The regions next to c across one face (2 per axis), looked up once: every face choice
    // with that axis meets them, so only the diagonal regions are looked up per choice.
    thread_local std::vector<Occupant> across;
    thread_local std::vector<std::uint8_t> looked;
    across.resize(2 * std::size_t(n_));
    looked.assign(2 * std::size_t(n_), 0);
    const auto acrossOf = [&](int axis, int d) -> const Occupant& {
      const std::size_t slot = 2 * std::size_t(axis) + (d > 0 ? 1 : 0);
      if (!looked[slot]) across[slot] = lookup(axis, d, -1, 0), looked[slot] = 1;
      return across[slot];
    };
    // A face of c is not c's when a region around it is finer (the face is not minimal: its
    // parts belong to the finer leaves) or a leaf of c's level before c (the face belongs to
    // the first leaf of its own level).
    const auto rulesOut = [&](const Occupant& o) {
      return o.kind == Occ::kFiner ||
             (o.kind == Occ::kLeaf && tree_.level(o.leaf) == level && o.leaf < c);
    };
    const Occupant self{Occ::kLeaf, c, 0};
    out.clear();
    out.reserve(fixedAxes_.size() << k_);  // every face kind at most once: one allocation
    std::array<Occupant, 4> around;
    for (std::size_t a = 0; a < fixedAxes_.size(); ++a) {
      const auto& axes = fixedAxes_[a];
      for (int side = 0; side < (1 << k_); ++side) {
        // The face's lower corner is c's moved by `side`; around it, on each fixed axis t, lie
        // c's side and the side across (offset d_t: -1 at the lower face, +1 at the upper).
        const int s0 = side & 1, d0 = s0 ? 1 : -1;
        const Occupant& o0 = acrossOf(axes[0], d0);
        if (k_ == 1) {
          if (rulesOut(o0)) continue;
          around[0] = s0 ? self : o0;
          around[1] = s0 ? o0 : self;
        } else {
          // A face in a facet M_c misses is not crossed (and not recorded: no region is
          // looked up for it). The regions across one face next (looked up once), so that a
          // face that is not c's is rejected before its diagonal region is looked up.
          const int s1 = (side >> 1) & 1, d1 = s1 ? 1 : -1;
          if (!facetMet(facets, axes[0], s0) || !facetMet(facets, axes[1], s1)) continue;
          const Occupant& o1 = acrossOf(axes[1], d1);
          if (rulesOut(o1) || rulesOut(o0)) continue;
          const Occupant diagonal = lookup(axes[0], d0, axes[1], d1);
          if (rulesOut(diagonal)) continue;
          // In cyclic order: (-a,-b), (+a,-b), (+a,+b), (-a,+b) around the lower corner; the
          // quadrant on c's side along both axes is c.
          static constexpr int kBits[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
          for (int q = 0; q < 4; ++q) {
            const bool moved0 = kBits[q][0] == s0, moved1 = kBits[q][1] == s1;
            around[q] = moved0 ? (moved1 ? diagonal : o0) : (moved1 ? o1 : self);
          }
        }
        out.push_back({static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(side), around});
      }
    }
  }

  /// The lower corner of an owned face and the regions around it now: as recorded, except
  /// an excluded base cell that a touch leaf has filled since (what CellTree::find says now).
  void faceAround(const std::vector<std::int32_t>& ci, const OwnedFace& f,
                  std::vector<std::int32_t>& corner, std::array<Occupant, 4>& around) const {
    const auto& axes = fixedAxes_[f.a];
    std::copy(ci.begin(), ci.end(), corner.begin());
    for (int t = 0; t < k_; ++t) corner[axes[t]] += (f.side >> t) & 1;
    around = f.around;
    for (int q = 0; q < (1 << k_); ++q) {
      if (around[q].kind != Occ::kEmpty) continue;
      if (const std::int32_t* leaf = touchLeaves_.find(around[q].key))
        around[q] = Occupant{Occ::kLeaf, *leaf, 0};
    }
  }

  /// Which face of its leaf (a, side) is, among the leaf's faces (FaceStore's kind).
  std::uint32_t faceKind(std::size_t a, int side) const {
    return static_cast<std::uint32_t>(a << k_) + static_cast<std::uint32_t>(side);
  }

  /// A leaf's facets as facetsOfModel gives them (entry 2 j + side) in one mask, bit 2 j + side
  /// set where M_c may meet the facet; kAllFacets (every facet may) beyond 32 variables.
  std::uint64_t facetMask(const std::vector<char>& met) const {
    if (n_ > 32 || met.empty()) return kAllFacets;
    std::uint64_t mask = 0;
    for (std::size_t f = 0; f < met.size(); ++f) mask |= std::uint64_t(met[f] != 0) << f;
    return mask;
  }

  /// Whether `mask` (facetMask) lets M_c meet the facet fixing axis a at its lower (side 0) or
  /// upper (1) end.
  bool facetMet(std::uint64_t mask, int a, int side) const {
    return mask == kAllFacets || ((mask >> (2 * a + side)) & 1) != 0;
  }

  /// Whether a face leaves no trace in the walk: not crossed, and addFace flags none of its
  /// leaves (proven, decided, clear of rounding and of the face's boundary).
  template <class Face>
  static bool quiet(const Face& r) {
    return r.degree == 0 && r.roots <= 1 && r.proven && r.certain && !r.withinRounding &&
           r.degenerate == 0;
  }

  /// What prefetchLeaf found for one leaf ahead of crossFaces.
  struct LeafFaces {
    std::int8_t empty = -1;  ///< restrictLeaf's answer (-1: not restricted)
    std::int8_t band = 0;    ///< and its band
    /// The facets the leaf model shows M_c may meet (bit 2 j + side; kAllFacets: unknown).
    std::uint64_t facets = kAllFacets;
    std::vector<std::pair<std::uint32_t, FaceResult<S>>> faces;  ///< new ones, by kind
    std::vector<FaceResult<S>> kept;  ///< copies of the kept faces (earlier rounds) in `visit`
    /// The owned faces that are not quiet, in the order of ownedFaces: (the face, its solution:
    /// i >= 0 in `faces`, else -1 - i in `kept`), so that the walk reads nothing but the slot.
    std::vector<std::pair<OwnedFace, std::int32_t>> visit;

    const FaceResult<S>& face(std::int32_t i) const {
      return i >= 0 ? faces[std::size_t(i)].second : kept[std::size_t(-1 - i)];
    }

    /// Empty again, keeping the storage.
    void clear() {
      empty = -1;
      band = 0;
      facets = kAllFacets;
      faces.clear();
      kept.clear();
      visit.clear();
    }
  };

  /// Whether leaf c is empty by prefetchLeaf's answer, which it gives whenever empty_[c] is
  /// unknown (bandEmpty_[c] is set too; the caller has grown the per-leaf arrays).
  bool emptyOf(std::int32_t c, const LeafFaces& known) {
    bandEmpty_[c] = known.band;
    return known.empty == 1;
  }

  /// A window of kWindowLeaves leaves of crossFaces and what its tasks found.
  struct Window {
    std::int32_t from = 0, end = 0;
    std::vector<std::int32_t> leaves;        ///< the active leaves that may be crossed
    std::vector<std::int8_t> prior;          ///< and their empty_ when the window started
    std::vector<std::uint64_t> priorFacets;  ///< and their facetsMet_
    std::vector<const RootForms*> forms;
    std::vector<LeafFaces> slots;  ///< per leaf from `from` on
    std::size_t used = 0;          ///< the slots holding answers of the window's last use
  };

  /// Starts, as `beside`'s task, keeping the faces that the window `keep` (if any) solved, then
  /// solving the window of leaves from `from` on (up to kWindowLeaves, so that the slots'
  /// memory stays bounded): each active leaf that may be crossed is a task that restricts it
  /// and solves the faces it owns that faces_ does not hold yet, writing only its slot
  /// (prefetchLeaf). Meanwhile the caller may walk `keep`, which reads only its slots.
  void startWindow(TaskBeside& beside, std::int32_t from, Window& w, const Window* keep) {
    grow();
    w.from = from;
    w.end = std::min(static_cast<std::int32_t>(tree_.size()), from + kWindowLeaves);
    w.leaves.clear();
    w.prior.clear();
    w.priorFacets.clear();
    for (std::int32_t c = from; c < w.end; ++c) {
      if (!tree_.active(c) || empty_[c] == 1) continue;
      w.leaves.push_back(c);
      w.prior.push_back(empty_[c]);
      w.priorFacets.push_back(facetsMet_[c]);
    }
    w.forms = rootFormsOf(w.leaves);
    w.slots.resize(kWindowLeaves);
    beside.start([this, &w, keep] {
      if (keep) keepFaces(*keep);
      // The slots' answers from the window's last use first (they hold the faces' roots).
      parallelFor(std::exchange(w.used, std::size_t(w.end - w.from)),
                  [&](std::size_t i) { w.slots[i].clear(); });
      parallelFor(w.leaves.size(), [&](std::size_t i) {
        prefetchLeaf(w.leaves[i], w.prior[i], w.priorFacets[i], *w.forms[i],
                     w.slots[std::size_t(w.leaves[i] - w.from)]);
      });
    });
  }

  /// Waits for the window solved beside the walk and adds the touch leaves the walk deferred.
  void finishWindow(TaskBeside& beside) {
    beside.wait();
    addDeferredLeaves();
  }

  /// Keeps the new faces of a solved window in faces_.
  void keepFaces(const Window& w) {
    faces_.addBlocks(
        w.leaves, [&](std::size_t i) -> const auto& {
          return w.slots[std::size_t(w.leaves[i] - w.from)].faces;
        });
  }

  /// The walk over one solved window's leaves in order: the faces that leave a trace.
  std::int64_t walkWindow(const Window& w) {
    std::int64_t degenerate = 0;
    std::vector<std::int32_t> corner(n_), ci;
    std::array<Occupant, 4> around;
    for (std::int32_t c = w.from; c < w.end; ++c) {
      if (!tree_.active(c)) continue;
      grow();
      const LeafFaces& known = w.slots[std::size_t(c - w.from)];
      if (empty_[c] < 0) empty_[c] = emptyOf(c, known) ? 1 : 0;
      if (empty_[c] == 1) continue;  // no level set between M and M_c meets it
      if (known.facets != kAllFacets) facetsMet_[c] = known.facets;
      const int level = tree_.level(c);
      ci.assign(tree_.index(c).begin(), tree_.index(c).end());
      for (const auto& [f, face] : known.visit) {
        faceAround(ci, f, corner, around);
        degenerate += addFace(known.face(face), around, level, corner, fixedAxes_[f.a]);
      }
    }
    return degenerate;
  }

  /// A task's patches: per thread in double (restrictLeaf then allocates nothing per leaf),
  /// `own` (the caller's, fresh) in MPFR, whose numbers carry a precision.
  static std::vector<Bernstein<S>>& leafScratch(std::vector<Bernstein<S>>& own) {
    if constexpr (std::is_same_v<S, double>) {
      thread_local std::vector<Bernstein<S>> scratch;
      return scratch;
    } else {
      return own;
    }
  }

  /// One task of startWindow: leaf c, whose empty_ was `prior` and facetsMet_ `priorFacets`
  /// when its window started.
  void prefetchLeaf(std::int32_t c, std::int8_t prior, std::uint64_t priorFacets,
                    const RootForms& rf, LeafFaces& out) const {
    std::vector<Bernstein<S>> own;
    std::vector<Bernstein<S>>& patches = leafScratch(own);
    bool restricted = false;
    const auto prepare = [&] {
      if (restricted) return;
      restricted = true;
      bool band = false;
      const bool empty = restrictLeaf(c, rf, patches, band);
      if (out.empty < 0) out.empty = empty ? 1 : 0, out.band = band ? 1 : 0;
    };
    // For m >= 2 (where faces are solved by evaluation) the leaf's affine model, built on the
    // first face not solved yet, or for the emptiness test.
    LeafModel<S> model;
    bool modelled = false;
    const auto buildModel = [&] {
      if (modelled) return;
      buildLeafModel(threadEvaluators(in_.system), leafBox(c), std::span<const S>(level_), model);
      modelled = true;
    };
    if (prior < 0) {
      // A leaf where every F_i - c_i provably takes both signs is not empty by its Bernstein
      // forms either: its patches are restricted only if a face needs them.
      if (m_ > 1 && byEvaluation_) {
        buildModel();
        if (levelsMet(model, leafBox(c))) {
          out.empty = 0, out.band = 0;
        } else if (modelExcludesBand(model)) {
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
      if (out.empty < 0) prepare();
    }
    // A prior emptiness is never 1 (startWindow skips those leaves).
    if (out.empty == 1) return;
    // For a surface, the facets the model shows M_c may meet (docs/crossing.md, "Facets
    // first"), once per leaf: a face in a facet M_c misses is not crossed, and ownedFaces
    // leaves it out.
    out.facets = priorFacets;
    if (k_ == 2 && m_ > 1 && byEvaluation_ && priorFacets == kAllFacets) {
      buildModel();
      thread_local std::vector<char> met;
      std::optional<LinearisedSystem<S>> fresh;
      facetsOfModel(model, threadScratch<S, LinearisedSystem<S>>(fresh), met);
      out.facets = facetMask(met);
    }
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
      if (const FaceRecord* kept = faces_.find(c, kind)) {
        if (quiet(*kept)) continue;
        out.kept.push_back(faces_.result(c, *kept));
        out.visit.emplace_back(f, -static_cast<std::int32_t>(out.kept.size()));
        continue;
      }
      const auto restricted = [&]() -> const std::vector<Bernstein<S>>& {
        prepare();
        return patches;
      };
      if (m_ > 1 && byEvaluation_) buildModel();
      const auto preconditioner = [&]() -> const FacePreconditioner<S>* {
        if (!built[f.a]) {
          buildFacePreconditioner(model, std::span<const int>(fixedAxes_[f.a].data(), k_),
                                  pre[f.a]);
          built[f.a] = 1;
        }
        return &pre[f.a];
      };
      FaceResult<S> r = solveFace(c, fixedAxes_[f.a], f.side, restricted, rf.margins,
                                  modelled ? &model : nullptr, preconditioner);
      if (!quiet(r)) out.visit.emplace_back(f, static_cast<std::int32_t>(out.faces.size()));
      out.faces.emplace_back(kind, std::move(r));
    }
  }

  /// Whether the leaf's affine model proves that no level set F = t c, t in [0, 1], meets it
  /// (bandExcluded: the linearised system's tests on the model; docs/crossing.md, "Empty leaves
  /// by the model"). Then restrictLeaf would find the leaf empty with its band too, or fail to
  /// prove what this proves: the Bernstein forms are not needed.
  bool modelExcludesBand(const LeafModel<S>& model) const {
    std::optional<LinearisedSystem<S>> fresh;
    return bandExcluded(model, std::span<const S>(level_),
                        threadScratch<S, LinearisedSystem<S>>(fresh), kFaceMultiplierSteps);
  }

  /// levelsMet's working storage (threadScratch).
  struct CornerWork {
    std::vector<S> corner, zero;
  };

  /// Whether every F_i - c_i provably takes both signs on the leaf `box` of `model`: its sign
  /// at the centre (the model's value), and the opposite one at the corner where the model's
  /// gradient points away from it (a midpoint-radius run at that corner). Then no Bernstein form
  /// of the leaf clears its level (the coefficients' hull holds the range, within the rounding
  /// margin), so the leaf is not empty, and restricting its forms to find that out is spared.
  bool levelsMet(const LeafModel<S>& model, const Box<S>& box) const {
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

  /// Records a solved face: flags its leaves when the face is not proven, and adds its
  /// polygon (|degree| copies) when it is crossed. Returns its degenerate crossings.
  std::int64_t addFace(const FaceResult<S>& r, std::array<Occupant, 4>& around, int level,
                       const std::vector<std::int32_t>& corner, const std::array<int, 2>& axes) {
    const int quadrants = 1 << k_;
    const bool unproven = !r.proven || r.roots > 1 || std::abs(r.degree) > 1 || r.degenerate;
    const bool singular = !r.certain || std::abs(r.degree) > 1;
    // Roots the face solver could not isolate at its finest face level, or within rounding
    // of the face's boundary: a finer cell has the same trouble (a tangency, or a feature at
    // the scale of the level offset c), so such leaves are not refined.
    const bool stuck = !r.certain || r.withinRounding || r.degenerate;
    for (int q = 0; q < quadrants; ++q) {
      if (around[q].kind != Occ::kLeaf) continue;
      if (stuck) stuck_[around[q].leaf] = 1;
      if (unproven) unproven_[around[q].leaf] = 1;
      if (singular) singular_[around[q].leaf] = 1;
      if (unproven)
        setTrouble(around[q].leaf, r.roots > 0
                                       ? std::span<const S>(r.root)
                                       : std::span<const S>(faceCentre(level, corner, axes)));
    }
    if (r.degree == 0) {
      if (unproven) recordUnproven(around, FaceRef{level, corner, axes});
      return r.degenerate;
    }
    Polygon p;
    for (int q = 0; q < quadrants; ++q) {
      std::int64_t node = 0;
      if (around[q].kind == Occ::kEmpty) {
        // A cell the level set F = c enters where M only touches it: a touch leaf.
        around[q].kind = Occ::kLeaf;
        around[q].leaf = deferTouchLeaf(around[q].key);
        if (unproven) unproven_[around[q].leaf] = 1;
        if (singular) singular_[around[q].leaf] = 1;
      }
      if (around[q].kind == Occ::kLeaf) {
        node = around[q].leaf;
      } else {
        node = -1 - static_cast<std::int64_t>(around[q].key);
        p.outside = true;
      }
      if (p.size > 0 && p.node[p.size - 1] == node) continue;
      p.node[p.size++] = node;
    }
    if (p.size > 1 && p.node[p.size - 1] == p.node[0]) --p.size;
    if (unproven) recordUnproven(around, FaceRef{level, corner, axes});
    p.root = static_cast<std::int32_t>(rootPoints_.size() / n_);
    rootPoints_.insert(rootPoints_.end(), r.root.begin(), r.root.end());
    for (int copy = 0; copy < std::abs(r.degree); ++copy) polygons_.push_back(p);
    return r.degenerate;
  }

  /// A touch leaf at the excluded base cell `key`: its number now, its place in the tree once
  /// the window solved beside the walk is done (addDeferredLeaves), so that the tasks never
  /// see the tree change.
  std::int32_t deferTouchLeaf(CellKey key) {
    const auto leaf = static_cast<std::int32_t>(leafCount());
    deferred_.push_back(key);
    touchLeaves_.insert(key, leaf);
    grow();
    return leaf;
  }

  /// Adds the deferred touch leaves to the tree, in order: they get the numbers they were given.
  void addDeferredLeaves() {
    std::vector<std::int32_t> index(n_);
    for (const CellKey key : deferred_) {
      grid_.unpack(key, index);
      tree_.addLeaf(grid_.depth, index, false);
    }
    deferred_.clear();
  }

  /// The leaves of the tree and the deferred touch leaves.
  std::size_t leafCount() const { return tree_.size() + deferred_.size(); }

  /// The centre of the face of `level` with lower corner `corner` and fixed axes `axes`.
  std::vector<S> faceCentre(int level, const std::vector<std::int32_t>& corner,
                            const std::array<int, 2>& axes) const {
    std::vector<S> centre(n_);
    const Grid& g = tree_.grid(level);
    for (int j = 0; j < n_; ++j) {
      const bool fixed = j == axes[0] || (k_ == 2 && j == axes[1]);
      centre[j] = domain_.lo[j] + S((corner[j] + (fixed ? 0.0 : 0.5)) * g.cellWidth(j));
    }
    return centre;
  }

  /// The leaves around an unproven face (-1 for other regions), for the blocks' test.
  void recordUnproven(const std::array<Occupant, 4>& around, const FaceRef& face) {
    const auto f = static_cast<std::int32_t>(unprovenFaces_.size());
    for (int q = 0; q < (1 << k_); ++q) {
      if (around[q].kind == Occ::kLeaf) {
        unprovenOf_.resize(leafCount());
        unprovenOf_[around[q].leaf].push_back(f);
      } else if (around[q].kind == Occ::kEmpty) {
        unprovenOfEmpty_[around[q].key].push_back(f);
      }
    }
    unprovenFaces_.push_back(face);
  }

  /// When the face lies inside exactly one face of the box of the block (level, lo), on one
  /// of its boundary planes and strictly inside along every other axis: that plane's axis
  /// (`upper`: the block's upper side). Otherwise -1.
  int blockFaceAxis(const FaceRef& face, int level, const std::vector<std::int32_t>& lo,
                    bool& upper) const {
    const std::int64_t scale = std::int64_t{1} << (face.level - level);
    int axis = -1;
    for (int j = 0; j < n_; ++j) {
      const std::int64_t a = lo[j] * scale, b = (lo[j] + 2) * scale, x = face.corner[j];
      const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
      if (fixed && (x == a || x == b)) {
        if (axis >= 0) return -1;  // on an edge of the block's box
        axis = j;
        upper = x == b;
        continue;
      }
      if (fixed ? (x <= a || x >= b) : (x < a || x + 1 > b)) return -1;
    }
    return axis;
  }

  bool onOneBlockFace(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const {
    bool upper = false;
    return blockFaceAxis(face, level, lo, upper) >= 0;
  }

  /// Whether the face lies inside the block of `level` with lower corner `lo` (not on its
  /// boundary).
  bool inside(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const {
    const std::int64_t scale = std::int64_t{1} << (face.level - level);
    for (int j = 0; j < n_; ++j) {
      const std::int64_t a = lo[j] * scale, b = (lo[j] + 2) * scale, x = face.corner[j];
      const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
      if (fixed ? (x <= a || x >= b) : (x < a || x + 1 > b)) return false;
    }
    return true;
  }

  /// Records a point near which the certificate of `leaf` failed (the first one stays): where
  /// a block around the leaf should have its centre.
  void setTrouble(std::int32_t leaf, std::span<const S> point) {
    grow();
    if (hasTrouble_[leaf]) return;
    hasTrouble_[leaf] = 1;
    std::copy(point.begin(), point.end(), trouble_.begin() + std::ptrdiff_t(leaf) * n_);
  }

  /// setTrouble at the centre of face (a, upper) of a leaf.
  void faceTrouble(std::int32_t leaf, int a, bool upper) {
    const Box<S> box = leafBox(leaf);
    std::vector<S> centre(n_);
    for (int j = 0; j < n_; ++j) centre[j] = (box.lo[j] + box.hi[j]) / 2;
    centre[a] = upper ? box.hi[a] : box.lo[a];
    setTrouble(leaf, centre);
  }

  /// Per-leaf arrays follow the tree's growth.
  void grow() {
    const std::size_t size = leafCount();
    if (empty_.size() >= size) return;
    trouble_.resize(size * n_, S(0));
    hasTrouble_.resize(size, 0);
    empty_.resize(size, -1);
    bandEmpty_.resize(size, 0);
    unproven_.resize(size, 0);
    stuck_.resize(size, 0);
    singular_.resize(size, 0);
    graph_.resize(size, -1);
    faceGraph_.resize(size, -1);
    facetsMet_.resize(size, kAllFacets);
    failure_.resize(size, Failure::kNone);
  }

  /// The graph test of a leaf's box (cached): M_c ∩ leaf is proven a graph over k of the
  /// coordinates (J enclosed by the widened derivative hulls of the leaf's patches).
  bool cellGraph(std::int32_t leaf, const RootForms& rf, LeafTests& t) {
    if (graph_[leaf] < 0) {
      // By evaluation first (polynomial in n); the Bernstein hulls where it does not prove it.
      thread_local std::vector<int> all;
      all.resize(n_);
      std::iota(all.begin(), all.end(), 0);
      graph_[leaf] = byEvaluation_ && leafJacobian(leaf, t) &&
                     t.test.graph(std::span<const Interval<S>>(t.whole), all);
      if (!graph_[leaf]) {
        prepare(leaf, rf, t);
        graph_[leaf] = graphOf(t.patches, rf.margins, t.jacobian, t.test);
      }
    }
    return graph_[leaf] == 1;
  }

  /// J over the whole leaf by evaluation into t.whole, once per LeafTests (the cell's graph test
  /// and the face graph tests share it); false when a run failed.
  bool leafJacobian(std::int32_t leaf, LeafTests& t) const {
    if (t.wholeKnown < 0)
      t.wholeKnown = evaluatedJacobian(leafBox(leaf), t.whole, t.wholeExcluded) ? 1 : 0;
    return t.wholeKnown == 1;
  }

  /// The graph test with J(X) from midpoint-radius runs of the programs over the face `box` of
  /// a leaf that fixes axis `fixed`: true when some m columns of the free axes form a regular
  /// block. `excluded`: F - c provably has no zero on the face (that alone passes the face
  /// graph test).
  bool evaluatedGraph(const Box<S>& box, int fixed, bool& excluded, LeafTests& t) const {
    if (!evaluatedJacobian(box, t.jacobian, excluded)) return false;
    return excluded || t.test.graph(t.jacobian, freeAxes(fixed));
  }

  /// J(X) over `box` (m x n, row-major) from midpoint-radius runs of the programs into
  /// `jacobian`; `excluded`: some F_i - c_i provably has no zero on the box. False when a run
  /// fails.
  bool evaluatedJacobian(const Box<S>& box, std::vector<Interval<S>>& jacobian,
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

  /// The graph test of the box of `patches` (jacobian: scratch; test: graphTest_ or a copy).
  bool graphOf(const std::vector<Bernstein<S>>& patches, std::span<const S> margins,
               std::vector<Interval<S>>& jacobian, GraphTest<S>& test) const {
    std::vector<int> axes(n_);
    std::iota(axes.begin(), axes.end(), 0);
    return hullGraph(patches, margins, axes, jacobian, test);
  }

  /// The graph test on the columns `axes` of J enclosed by the derivative hulls of `patches`.
  bool hullGraph(const std::vector<Bernstein<S>>& patches, std::span<const S> margins,
                 const std::vector<int>& axes, std::vector<Interval<S>>& jacobian,
                 GraphTest<S>& test) const {
    jacobian.assign(std::size_t(m_) * n_, Interval<S>());
    for (int i = 0; i < m_; ++i) {
      for (int j = 0; j < n_; ++j)
        jacobian[std::size_t(i) * n_ + j] = derivativeHull(patches[i], j, margins[i]);
    }
    return test.graph(jacobian, axes);
  }

  /// Whether interval evaluation proves that M_c (with `band`: no level set between M and M_c)
  /// does not meet `box`; for m = 1, the sign rule's level set F = -delta: F >= 0 or F < 0 on
  /// the box. Catches what coefficient hulls miss, such as y^2 on a box around y = 0.
  bool intervalEmpty(const Box<S>& box, bool band) const {
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

  /// k = 2: the graph test of every (n-1)-face of a leaf (cached): M_c ∩ face is empty or a
  /// graph over one coordinate, so no closed curve of M_c lies inside a face.
  bool facesGraph(std::int32_t leaf, const RootForms& rf, LeafTests& t) {
    if (faceGraph_[leaf] < 0) {
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
      const auto met = [&](int a, int side) { return facetMet(facetsMet_[leaf], a, side); };
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
          prepare(leaf, rf, t);
          if (!faceGraphOf(t.patches, rf.margins, a, side == 1, freeAxes(a), t.jacobian, t.test))
            failed = 2 * a + side;
        }
      }
      faceGraph_[leaf] = failed < 0;
      if (failed >= 0) faceTrouble(leaf, failed / 2, failed % 2 == 1);
    }
    return faceGraph_[leaf] == 1;
  }

  /// The free axes of a face that fixes axis a.
  std::vector<int> freeAxes(int a) const {
    std::vector<int> axes;
    for (int j = 0; j < n_; ++j) {
      if (j != a) axes.push_back(j);
    }
    return axes;
  }

  /// The faces of the box of `patches` that fail the face graph test, as (fixed axis, upper):
  /// every one, or (`all` false) the first (jacobian: scratch; test: graphTest_ or a copy).
  std::vector<std::pair<int, bool>> failingFacesOf(const std::vector<Bernstein<S>>& patches,
                                                   std::span<const S> margins, bool all,
                                                   std::vector<Interval<S>>& jacobian,
                                                   GraphTest<S>& test) const {
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

  /// The first face (2 a + side) of a failingFacesOf list, or -1.
  static int firstFailing(const std::vector<std::pair<int, bool>>& failing) {
    return failing.empty() ? -1 : 2 * failing.front().first + int(failing.front().second);
  }

  /// Face (a, upper) of the block (level, lo) leaf face by leaf face: no unproven face inside
  /// it (its crossings on the leaf faces' common edges are proven, so the link sees every
  /// piece of M on it) and each leaf face empty or a graph. `rf`: the block's root forms (its
  /// leaves'); w.patches changed.
  bool subFacesGraph(int level, const std::vector<std::int32_t>& lo,
                     const std::vector<std::int32_t>& members, int a, bool upper,
                     const RootForms& rf, BlockWork& w) {
    const std::vector<int> axes = freeAxes(a);
    for (std::int32_t c : members) {
      if (tree_.index(c)[a] != (upper ? lo[a] + 1 : lo[a])) continue;
      for (std::int32_t f : unprovenOf_[c]) {
        bool up = false;
        if (blockFaceAxis(unprovenFaces_[f], level, lo, up) == a && up == upper) return false;
      }
      bool band = false;
      restrictLeaf(c, rf, w.patches, band);
      bandEmpty_[c] = band;  // c is this task's (mergeBlocks)
      if (!faceGraphOf(w.patches, rf.margins, a, upper, axes, w.jacobian, w.test)) return false;
    }
    return true;
  }

  /// faceGraph on the box of `patches` (jacobian: scratch; test: graphTest_ or a copy).
  bool faceGraphOf(const std::vector<Bernstein<S>>& patches, std::span<const S> margins, int a,
                   bool upper, const std::vector<int>& axes, std::vector<Interval<S>>& jacobian,
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

  /// The certificate of every active leaf (docs/certificate.md) into failure_.
  void certify() {
    const Incidence incident(polygons_, tree_.size());
    std::fill(failure_.begin(), failure_.end(), Failure::kNone);
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

  /// The certificate of active leaf c into failure_[c]. It writes only what belongs to c (its
  /// failure, its cached graph tests and its trouble point), so certify runs the leaves in
  /// parallel and the result does not depend on their order.
  void certifyLeaf(std::int32_t c, const RootForms& rf, std::span<const std::int32_t> ps) {
    std::vector<Bernstein<S>> own;
    LeafTests t{leafScratch(own), {}, graphTest_, false, -1, false, {}};
    if (empty_[c] == 1) {
      // M_c misses the leaf; M may not (it lies 1e-8 h away): where it meets the leaf, the
      // isotopy from M to M_c needs the Jacobian's rank there, and on the domain's boundary
      // transversality to its faces.
      // (For m = 1 the sign rule lets F = 0 pass as empty: the boundary's test is strict.)
      const bool missed = bandEmpty_[c] || intervalEmpty(leafBox(c), true);
      if (!missed && !cellGraph(c, rf, t))
        failure_[c] = Failure::kGraph;
      else if ((!missed || m_ == 1) && !boundaryTransverse(c, rf, t, true))
        failure_[c] = Failure::kBoundary;
      return;
    }
    if (unproven_[c]) {
      failure_[c] = Failure::kCrossing;
    } else if (!cellGraph(c, rf, t) && !intervalEmpty(leafBox(c), true)) {
      failure_[c] = Failure::kGraph;
    } else if (k_ == 2 && !facesGraph(c, rf, t)) {
      failure_[c] = Failure::kFaceGraph;
    } else if (!simpleLink(k_, c, polygons_, ps)) {
      failure_[c] = Failure::kLink;
    } else if (!boundaryTransverse(c, rf, t, true)) {
      failure_[c] = Failure::kBoundary;
    }
  }

  /// Whether every level set between M and M_c meets the domain's boundary transversally in
  /// leaf c (docs/certificate.md, "The domain's boundary"): each face of the leaf's box in a
  /// face of the domain of dimension n - j is missed by all of them (interval evaluation of
  /// F - t c, t in [0, 1]), or, for j <= k, J's columns of its free axes have full rank m over
  /// it (the graph test on those columns, whatever the level). A tangency of M with a domain
  /// face, or M through a domain face of dimension below m, fails here. `mark`: a failing leaf
  /// whose face M is tangent to (tangentToFace) is marked stuck: refinement would not help.
  bool boundaryTransverse(std::int32_t c, const RootForms& rf, LeafTests& t, bool mark) {
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
      prepare(c, rf, t);
      if (slicesMiss(t.patches, std::span<const S>(rf.margins), leafBox(c), face,
                     std::span<const S>(level_)))
        continue;
      const auto fail = [&] {
        if (mark && tangentToFace(in_.system, face)) stuck_[c] = 1;
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
      if (!hullGraph(t.patches, rf.margins, face.free, t.jacobian, t.test)) return fail();
    }
    return true;
  }

  /// The leaf's patches into t (once).
  void prepare(std::int32_t leaf, const RootForms& rf, LeafTests& t) const {
    if (t.ready) return;
    bool band = false;
    restrictLeaf(leaf, rf, t.patches, band);
    t.ready = true;
  }

  /// Tangency (docs/certificate.md, "Blocks"): where M touches a grid hyperplane, M_c crosses
  /// it in a small loop or in two crossings closer than any refinement separates, so neither
  /// leaf next to the touching point is simple; the block of 2^n leaves of one level around the
  /// point often is. Certifies such blocks of failing leaves (the first that passes of the
  /// candidates around each leaf); in the mesh a block is one region with one vertex per piece.
  ///
  /// Along a curve of tangency (a circle of M in a grid plane) every block is cut by the curve
  /// where it leaves the block, so an unproven face lies on the block's boundary. Such a
  /// block is kept *tentatively* when the face lies inside one face of the block's box; it
  /// stands when the leaves across that face are in blocks too (then the block face is shared
  /// and the polygons around the unproven face join two block nodes only, which the mesh
  /// drops) and its link, with every block one node, is one cycle. verifyBlocks dissolves the
  /// blocks that do not stand until the rest do.
  ///
  /// The leaves are tried in order, as one sequential loop would, but in parallel by clusters
  /// (blockClusters): a leaf's blocks lie within one leaf of it, so leaves of different clusters
  /// never compete for a leaf, and each cluster's leaves in order give the blocks the loop
  /// would. The blocks are numbered in the order of the leaves that made them.
  /// `leaves`: the active leaves in order, `forms` their root forms.
  void mergeBlocks(const Incidence& incident, const std::vector<std::int32_t>& leaves,
                   const std::vector<const RootForms*>& forms) {
    blocks_.clear(), blockLo_.clear(), blockLevel_.clear(), blockSaved_.clear();
    blockEmpties_.clear();
    block_.assign(tree_.size(), -1);
    unprovenOf_.resize(tree_.size());
    bandEmpty_.resize(tree_.size(), 0);
    // The leaves that try blocks, with their root forms: not a leaf whose own graph test fails
    // (the graph test on a block around it would fail too, on a wider box with wider Jacobian
    // enclosures; only refinement can help), nor one M may touch the domain's boundary in
    // (a block proves nothing there).
    std::vector<std::int32_t> trying;
    std::vector<const RootForms*> tryingForms;
    for (std::size_t i = 0; i < leaves.size(); ++i) {
      const Failure f = failure_[leaves[i]];
      if (f == Failure::kNone || f == Failure::kGraph || f == Failure::kBoundary) continue;
      trying.push_back(leaves[i]);
      tryingForms.push_back(forms[i]);
    }
    const std::vector<std::vector<std::int32_t>> clusters = blockClusters(trying);
    std::vector<BlockWork> work(clusters.size(), BlockWork{{}, {}, graphTest_, {}});
    parallelFor(clusters.size(), [&](std::size_t k) {
      for (const std::int32_t i : clusters[k]) {
        const std::int32_t c = trying[i];
        if (block_[c] >= 0) continue;  // in a block of an earlier leaf of the cluster
        blocksOf(c, *tryingForms[i], incident, work[k]);
      }
    });
    bool tentative = false;
    for (const NewBlock& b : orderedBlocks(work)) {
      for (std::int32_t c : b.members) block_[c] = static_cast<std::int32_t>(blocks_.size());
      blocks_.push_back(b.members);
      blockLo_.push_back(b.lo);
      blockLevel_.push_back(b.level);
      blockEmpties_.push_back(b.empties);
      blockSaved_.push_back(b.saved);
      tentative = tentative || b.tentative;
    }
    if (tentative) verifyBlocks(incident);
  }

  /// The first block that certifies around leaf c (its candidates, then its lattice blocks),
  /// into w.made.
  void blocksOf(std::int32_t c, const RootForms& rf, const Incidence& incident, BlockWork& w) {
    for (const std::vector<std::int32_t>& lo : blockCandidates(c)) {
      if (tryBlock(c, lo, incident, false, rf, w)) return;
    }
    for (const std::vector<std::int32_t>& lo : latticeBlocks(c)) {
      if (tryBlock(c, lo, incident, true, rf, w)) return;
    }
  }

  /// The blocks of mergeBlocks' tasks in the order of the leaves that made them.
  static std::vector<NewBlock> orderedBlocks(std::vector<BlockWork>& work) {
    std::vector<NewBlock> all;
    for (BlockWork& w : work) {
      for (NewBlock& b : w.made) all.push_back(std::move(b));
    }
    std::sort(all.begin(), all.end(),
              [](const NewBlock& a, const NewBlock& b) { return a.leaf < b.leaf; });
    return all;
  }

  /// The axis along which the leaves take the most distinct (level, index) values.
  int spreadAxis(const std::vector<std::int32_t>& leaves) const {
    int best = 0;
    std::size_t most = 0;
    std::vector<std::pair<int, std::int32_t>> at(leaves.size());
    for (int j = 0; j < n_; ++j) {
      for (std::size_t i = 0; i < leaves.size(); ++i)
        at[i] = {tree_.level(leaves[i]), tree_.index(leaves[i])[j]};
      std::sort(at.begin(), at.end());
      const auto distinct =
          static_cast<std::size_t>(std::unique(at.begin(), at.end()) - at.begin());
      if (distinct > most) best = j, most = distinct;
    }
    return best;
  }

  /// The leaves of `trying` (positions in it) grouped into clusters, each in order: two leaves
  /// of one level within two cells of each other along every axis are in one cluster (the
  /// blocks of each lie within one cell of it, so only such leaves can compete for a leaf).
  /// The clusters are in the order of their first leaves.
  std::vector<std::vector<std::int32_t>> blockClusters(
      const std::vector<std::int32_t>& trying) const {
    const auto count = static_cast<std::int32_t>(trying.size());
    // By level, then along the axis where the leaves spread most (a curve of tangency lies in
    // a grid plane): the leaves near one are a run of this order.
    const int axis = spreadAxis(trying);
    std::vector<std::int32_t> order(static_cast<std::size_t>(count));
    std::iota(order.begin(), order.end(), 0);
    const auto key = [&](std::int32_t i) {
      return std::pair{tree_.level(trying[i]), tree_.index(trying[i])[axis]};
    };
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
      return std::pair{key(a), a} < std::pair{key(b), b};
    });
    UnionFind sets{std::vector<int>(static_cast<std::size_t>(count))};
    std::iota(sets.parent.begin(), sets.parent.end(), 0);
    for (std::size_t x = 0; x < order.size(); ++x) {
      const auto a = tree_.index(trying[order[x]]);
      for (std::size_t y = x + 1; y < order.size(); ++y) {
        const auto [level, first] = key(order[y]);
        if (level != key(order[x]).first || first > a[axis] + 2) break;
        const auto b = tree_.index(trying[order[y]]);
        bool near = true;
        for (int j = 0; j < n_ && near; ++j) near = std::abs(a[j] - b[j]) <= 2;
        if (near) sets.unite(order[x], order[y]);
      }
    }
    std::vector<std::vector<std::int32_t>> clusters;
    std::vector<std::int32_t> clusterOf(static_cast<std::size_t>(count), -1);
    for (std::int32_t i = 0; i < count; ++i) {
      std::int32_t& k = clusterOf[sets.find(i)];
      if (k < 0) {
        k = static_cast<std::int32_t>(clusters.size());
        clusters.emplace_back();
      }
      clusters[k].push_back(i);
    }
    return clusters;
  }

  /// The blocks for leaf c on a curve of tangency: for each grid plane next to c that holds
  /// every unproven face next to c, the block that straddles the plane and has even lower
  /// corners along the other axes (so that the blocks along the curve tile it face to face).
  std::vector<std::vector<std::int32_t>> latticeBlocks(std::int32_t c) const {
    const int level = tree_.level(c);
    const auto ci = tree_.index(c);
    // (axis, plane index at this level) pairs common to every unproven face.
    std::vector<std::pair<int, std::int64_t>> common;
    bool first = true;
    for (std::int32_t f : unprovenOf_[c]) {
      const FaceRef& face = unprovenFaces_[f];
      const int shift = face.level - level;
      if (shift < 0) return {};
      std::vector<std::pair<int, std::int64_t>> planes;
      for (int t = 0; t < k_; ++t) {
        const int j = face.axes[t];
        const std::int64_t x = face.corner[j];
        if ((x & ((std::int64_t{1} << shift) - 1)) != 0) continue;
        const std::int64_t p = x >> shift;
        if (p == ci[j] || p == ci[j] + 1) planes.emplace_back(j, p);
      }
      if (first)
        common = planes;
      else
        std::erase_if(common, [&](const auto& q) {
          return std::find(planes.begin(), planes.end(), q) == planes.end();
        });
      first = false;
    }
    std::vector<std::vector<std::int32_t>> blocks;
    for (const auto& [axis, plane] : common) {
      std::vector<std::int32_t> lo(n_);
      for (int j = 0; j < n_; ++j) lo[j] = ci[j] & ~std::int32_t{1};
      lo[axis] = static_cast<std::int32_t>(plane - 1);
      blocks.push_back(std::move(lo));
    }
    return blocks;
  }

  /// Dissolves the blocks that do not stand (mergeBlocks) until every remaining one does.
  void verifyBlocks(const Incidence& incident) {
    for (bool changed = true; changed;) {
      changed = false;
      for (std::size_t b = 0; b < blocks_.size(); ++b) {
        if (blocks_[b].empty() || blockStands(b, incident)) continue;
        for (std::size_t i = 0; i < blocks_[b].size(); ++i) {
          block_[blocks_[b][i]] = -1;
          failure_[blocks_[b][i]] = blockSaved_[b][i];
        }
        blocks_[b].clear();
        changed = true;
      }
    }
  }

  /// Whether block b stands among the others: every unproven face next to it inside it, or
  /// inside one face of its box with block leaves across, and its link (every block one node)
  /// one cycle.
  bool blockStands(std::size_t b, const Incidence& incident) const {
    const int level = blockLevel_[b];
    const std::vector<std::int32_t>& lo = blockLo_[b];
    const auto stands = [&](const std::vector<std::int32_t>& faces) {
      return std::all_of(faces.begin(), faces.end(), [&](std::int32_t f) {
        return inside(unprovenFaces_[f], level, lo) ||
               sharedBlockFace(unprovenFaces_[f], level, lo);
      });
    };
    for (std::int32_t c : blocks_[b]) {
      if (!stands(unprovenOf_[c])) return false;
    }
    for (CellKey key : blockEmpties_[b]) {
      auto it = unprovenOfEmpty_.find(key);
      if (it != unprovenOfEmpty_.end() && !stands(it->second)) return false;
    }
    std::vector<Polygon> link;
    std::vector<std::int32_t> ps;
    const std::int64_t front = blocks_[b].front();
    for (std::int32_t p : blockPolygons(blocks_[b], incident)) {
      const Polygon q = collapsed(polygons_[p], [&](std::int64_t node) { return blockNode(node); });
      if (q.size < (k_ == 1 ? 2 : 3)) continue;  // inside the block, or between two blocks
      if (std::count(q.node.begin(), q.node.begin() + q.size, front) != 1) return false;
      ps.push_back(static_cast<std::int32_t>(link.size()));
      link.push_back(q);
    }
    return simpleLink(k_, front, link, ps);
  }

  /// The polygons incident to any of the leaves, once each.
  static std::vector<std::int32_t> blockPolygons(const std::vector<std::int32_t>& members,
                                                 const Incidence& incident) {
    std::vector<std::int32_t> around;
    for (std::int32_t c : members)
      around.insert(around.end(), incident[c].begin(), incident[c].end());
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    return around;
  }

  /// Whether the face lies inside exactly one face of the block's box (level, lo) and every
  /// leaf across that face next to it is a leaf of `level` in a block.
  bool sharedBlockFace(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const {
    const int shift = face.level - level;
    const std::int64_t scale = std::int64_t{1} << shift;
    bool upper = false;
    const int axis = blockFaceAxis(face, level, lo, upper);
    if (axis < 0) return false;
    // The leaves across: one index along the axis, one or two along the other fixed axis.
    std::vector<std::int32_t> across(n_);
    int other = -1;
    for (int j = 0; j < n_; ++j) {
      const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
      across[j] = static_cast<std::int32_t>(face.corner[j] >> shift);
      if (j == axis)
        across[j] = upper ? lo[j] + 2 : lo[j] - 1;
      else if (fixed && (face.corner[j] & (scale - 1)) == 0)
        other = j;  // on a leaf plane
    }
    for (int s = 0; s < (other >= 0 ? 2 : 1); ++s) {
      std::vector<std::int32_t> index = across;
      if (other >= 0) index[other] -= s;
      const Occupant o = tree_.find(level, index);
      if (o.kind != Occupant::Kind::kLeaf || tree_.level(o.leaf) != level || block_[o.leaf] < 0)
        return false;
    }
    return true;
  }

  /// The lower corners of the blocks of 2^n leaves that hold leaf c, the one centred nearest
  /// its trouble point first, then those that differ from it along more and more axes (at
  /// most kBlockTries).
  std::vector<std::vector<std::int32_t>> blockCandidates(std::int32_t c) const {
    constexpr std::size_t kBlockTries = 16;
    const auto ci = tree_.index(c);
    const Box<S> box = leafBox(c);
    std::uint32_t below = 0;  // bit j: the preferred block extends below the leaf along j
    for (int j = 0; j < n_; ++j) {
      const S t = hasTrouble_[c] ? trouble_[std::size_t(c) * n_ + j] : box.lo[j];
      if (t < (box.lo[j] + box.hi[j]) / 2) below |= 1u << j;
    }
    std::vector<std::uint32_t> flips(std::size_t{1} << n_);
    std::iota(flips.begin(), flips.end(), 0u);
    std::stable_sort(flips.begin(), flips.end(), [](std::uint32_t a, std::uint32_t b) {
      return std::popcount(a) < std::popcount(b);
    });
    std::vector<std::vector<std::int32_t>> out;
    for (std::size_t t = 0; t < std::min(kBlockTries, flips.size()); ++t) {
      std::vector<std::int32_t> lo(ci.begin(), ci.end());
      for (int j = 0; j < n_; ++j)
        lo[j] -= static_cast<std::int32_t>(((below ^ flips[t]) >> j) & 1);
      out.push_back(std::move(lo));
    }
    return out;
  }

  /// The certificate of the block of 2^n leaves of `level` with lower corner `lo`: its leaves
  /// free, one polynomial piece, every unproven face inside it, the crossings on its boundary
  /// one simple piece, and the graph and face graph tests on its box.
  /// Leaf c's try (mergeBlocks' task w): `rf` its root forms, which are the block's; a block
  /// that certifies takes its members (block_ and failure_) and goes to w.made.
  bool tryBlock(std::int32_t c, const std::vector<std::int32_t>& lo, const Incidence& incident,
                bool tentative, const RootForms& rf, BlockWork& w) {
    const int level = tree_.level(c);
    std::vector<std::int32_t> members;
    std::vector<CellKey> empties;
    if (!blockMembers(level, lo, members, empties)) return false;
    // Every unproven face next to the block's regions lies inside it (tentative: or inside
    // one face of its box, for verifyBlocks to check the leaves across).
    const auto within = [&](const std::vector<std::int32_t>& faces, bool relaxed) {
      return std::all_of(faces.begin(), faces.end(), [&](std::int32_t f) {
        return inside(unprovenFaces_[f], level, lo) ||
               (relaxed && onOneBlockFace(unprovenFaces_[f], level, lo));
      });
    };
    for (std::int32_t c : members) {
      if (!within(unprovenOf_[c], tentative)) return false;
    }
    for (CellKey key : empties) {
      auto it = unprovenOfEmpty_.find(key);
      if (it != unprovenOfEmpty_.end() && !within(it->second, tentative)) return false;
    }
    // The link: now, or (tentative) once the neighbour blocks exist, in verifyBlocks.
    std::vector<Polygon> link;
    std::vector<std::int32_t> ps;
    if (!tentative &&
        (!blockLink(members, incident, link, ps) || !simpleLink(k_, members.front(), link, ps)))
      return false;
    // The graph tests on the block's box.
    std::vector<std::int32_t> hi(lo);
    for (std::int32_t& i : hi) ++i;
    Box<S> box = cellBox(tree_.grid(level), domain_, lo);
    box.hi = cellBox(tree_.grid(level), domain_, hi).hi;
    w.patches.resize(m_);
    for (int i = 0; i < m_; ++i) (*rf.forms)[i].restrictInto(box, w.patches[i]);
    if (!graphOf(w.patches, rf.margins, w.jacobian, w.test) && !intervalEmpty(box, true))
      return false;
    if (k_ == 2) {
      // A face of the block's box that fails as a whole: a tentative block may prove it leaf
      // face by leaf face (subFacesGraph).
      const auto failing = failingFacesOf(w.patches, rf.margins, tentative, w.jacobian, w.test);
      for (const auto& [a, upper] : failing) {
        if (!tentative || !subFacesGraph(level, lo, members, a, upper, rf, w)) return false;
      }
    }
    // A block proves nothing about the domain's boundary: its members must each.
    for (std::int32_t d : members) {
      std::vector<Bernstein<S>> own;
      LeafTests t{leafScratch(own), {}, graphTest_, false, -1, false, {}};
      if (!boundaryTransverse(d, rf, t, false)) return false;
    }
    // The members are taken (block_ >= 0 until mergeBlocks numbers the block).
    NewBlock b{c, level, tentative, lo, std::move(members), std::move(empties), {}};
    for (std::int32_t d : b.members) {
      block_[d] = 0;
      b.saved.push_back(failure_[d]);
      failure_[d] = Failure::kNone;
    }
    w.made.push_back(std::move(b));
    return true;
  }

  /// The leaves of a block: every region of it an active leaf of `level` in no other block,
  /// inside one polynomial piece of the input.
  bool blockMembers(int level, const std::vector<std::int32_t>& lo,
                    std::vector<std::int32_t>& members, std::vector<CellKey>& empties) const {
    const std::int64_t top = tree_.grid(level).cellsPerAxis();
    const int patchLevel = in_.problem.roots.empty() ? 0 : in_.problem.rootLevel;
    for (int j = 0; j < n_; ++j) {
      if (lo[j] < 0 || lo[j] + 2 > top) return false;
      if ((lo[j] >> (level - patchLevel)) != ((lo[j] + 1) >> (level - patchLevel))) return false;
    }
    std::vector<std::int32_t> position(n_);
    for (std::uint32_t corner = 0; corner < (1u << n_); ++corner) {
      for (int j = 0; j < n_; ++j)
        position[j] = lo[j] + static_cast<std::int32_t>((corner >> j) & 1);
      const Occupant o = tree_.find(level, position);
      // A base cell the bounding excluded: M_c does not enter it (it would be a touch leaf).
      if (o.kind == Occ::kEmpty) {
        if (std::find(empties.begin(), empties.end(), o.key) == empties.end())
          empties.push_back(o.key);
        continue;
      }
      if (o.kind != Occ::kLeaf || tree_.level(o.leaf) != level || !tree_.active(o.leaf) ||
          block_[o.leaf] >= 0)
        return false;
      members.push_back(o.leaf);
    }
    return !members.empty();
  }

  /// The polygons of the block's boundary with its leaves as one node (members.front());
  /// those inside it drop out. False when a polygon meets the block twice (not a box).
  bool blockLink(const std::vector<std::int32_t>& members, const Incidence& incident,
                 std::vector<Polygon>& link, std::vector<std::int32_t>& ps) const {
    for (std::int32_t p : blockPolygons(members, incident)) {
      const Polygon q = collapsed(polygons_[p], [&](std::int64_t node) {
        return std::find(members.begin(), members.end(), node) != members.end() ? members.front()
                                                                                : node;
      });
      if (q.size < (k_ == 1 ? 2 : 3)) continue;  // inside the block
      if (std::count(q.node.begin(), q.node.begin() + q.size, members.front()) != 1) return false;
      ps.push_back(static_cast<std::int32_t>(link.size()));
      link.push_back(q);
    }
    return true;
  }

  /// A polygon node as the mesh sees it: a leaf in a block is the block's first leaf.
  std::int64_t blockNode(std::int64_t node) const {
    const bool inBlock = node >= 0 && std::size_t(node) < block_.size() && block_[node] >= 0;
    return inBlock ? std::int64_t{blocks_[block_[node]].front()} : node;
  }

  /// A polygon with its nodes mapped by `map`, equal neighbours merged (cyclically).
  template <class Map>
  static Polygon collapsed(const Polygon& poly, const Map& map) {
    Polygon q = poly;
    q.size = 0;
    for (int i = 0; i < poly.size; ++i) {
      const std::int64_t node = map(poly.node[i]);
      if (q.size > 0 && q.node[q.size - 1] == node) continue;
      q.node[q.size++] = node;
    }
    if (q.size > 1 && q.node[q.size - 1] == q.node[0]) --q.size;
    return q;
  }

  /// The mesh's polygons with every certified block as one node (its first leaf), when every
  /// leaf is certified: then the mesh is the dual of the certified decomposition. Otherwise
  /// the blocks stay apart: merging a block's vertices is an edge contraction, and next to an
  /// uncertified leaf nothing proves its link condition.
  void collapseBlocks(bool certified) {
    if (blocks_.empty() || !certified) return;
    std::vector<Polygon> kept;
    for (const Polygon& p : polygons_) {
      const Polygon q = collapsed(p, [&](std::int64_t node) { return blockNode(node); });
      if (q.size >= (k_ == 1 ? 2 : 3)) kept.push_back(q);
    }
    polygons_ = std::move(kept);
  }

  /// Crossings, certificates and refinement until every leaf is certified or at the maximum
  /// level (or the leaf budget is spent). Returns the degenerate crossings of the last pass.
  std::int64_t refineAndCertify() {
    tree_ = CellTree(grid_, tree_.maxLevel());
    tree_.addBaseCells(in_.cells);
    faces_.clear();
    empty_.clear(), bandEmpty_.clear(), unproven_.clear(), stuck_.clear(), singular_.clear(),
        graph_.clear(), faceGraph_.clear(), facetsMet_.clear();
    failure_.clear();
    trouble_.clear(), hasTrouble_.clear();
    refined_ = 0;
    solutionChildren_ = 0;
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
            !((failure_[c] == Failure::kCrossing || failure_[c] == Failure::kBoundary) &&
              stuck_[c]))
          refine.push_back(c);
      }
      // Certified (or as far as it goes): then the leaves the chord error asks for.
      if (refine.empty() && in_.tolerance > 0 && refining_) refine = chordLeaves();
      if (refine.empty() || !in_.refine || !refining_) return degenerate;
      if (!withinBudget(refine.size())) {
        budgetSpent_ = true;
        return degenerate;
      }
      // The children's bounding tests in parallel, the tree's growth in order.
      std::vector<std::vector<std::uint8_t>> children(refine.size());
      parallelFor(refine.size(), [&](std::size_t i) {
        const std::int32_t c = refine[i];
        children[i] = in_.refine(cellBox(tree_.grid(tree_.level(c)), grid_.domain, tree_.index(c)));
      });
      for (std::size_t i = 0; i < refine.size(); ++i) {
        solutionChildren_ += static_cast<std::size_t>(std::count_if(
            children[i].begin(), children[i].end(), [](std::uint8_t f) { return f != 0; }));
        tree_.refine(refine[i], children[i]);
        ++refined_;
      }
      grow();
    }
  }

  /// `--tolerance`: the leaves below the maximum level that are nodes of a mesh polygon inside
  /// the domain whose simplices have a barycentre farther than the tolerance from its Newton
  /// projection onto M (the analysis's chord error; the polygons at the domain's boundary, whose
  /// boundary vertices are not placed here, are not tested). Each leaf's vertex is taken as the
  /// projection of the mean of its crossings, as the dual complex places it (a block's: of the
  /// block's crossings).
  std::vector<std::int32_t> chordLeaves() const {
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

  /// Whether a simplex of the polygon (its edge, or its triangles split along the shorter
  /// diagonal as addSimplices does) has its barycentre farther than `tolerance` from M.
  bool chordAbove(const Polygon& poly, const std::vector<S>& vertex, const S& tolerance) const {
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

  /// The topology record from the final tree.
  void record(TopologyRecord& t, std::int64_t degenerate) const {
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
      if (failure_[c] == Failure::kNone) {
        ++t.certifiedCells;
        continue;
      }
      ++t.uncertifiedCells;
      ++reasons[failureName(failure_[c])];
      stuck += failure_[c] == Failure::kCrossing && stuck_[c];
      tangent += failure_[c] == Failure::kBoundary && stuck_[c];
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
      if (reasons.count(failureName(Failure::kBoundary))) {
        why << "; M may touch the domain's boundary (tangent to a face of the domain, or through "
            << "a face of it of dimension below n - k = " << m_ << ")";
        if (tangent > 0)
          why << ", " << tangent << " next to a point of M where refinement cannot prove it (M "
              << "tangent to the domain's boundary there, or through a corner of it)";
      }
      if (budgetSpent_) {
        why << "; refinement stopped at its budget of " << maxSolutionLeaves_
            << " solution leaves and " << maxLeaves_ << " leaves";
      }
    } else if (degenerate > 0) {
      why << degenerate << " crossings within rounding of a face boundary";
    }
    t.reason = why.str();
    t.certified = t.reason.empty();
  }

  /// The dual complex of the final tree (docs/crossing.md, steps 3 and 4, and "The domain's
  /// boundary"), blocks merged where every leaf is certified.
  void buildComplex(ConnectionOutput<S>& out) {
    collapseBlocks(out.topology.certified);
    buildDualComplex(
        DualInput<S>{in_, tree_, domain_, polygons_, rootPoints_, singular_, position_.slack}, out);
  }

  const ConnectionInput<S>& in_;
  const Grid& grid_;
  int n_, k_, m_, maxFaceDepth_;
  Box<S> domain_;
  CellForms<S> cellForms_;  ///< the Bernstein forms of every leaf
  const GeneralPosition<S> position_;
  GraphTest<S> graphTest_;
  CellTree tree_;
  std::vector<std::array<int, 2>> fixedAxes_;  ///< the k fixed axes of each kind of m-face
  std::vector<S> level_;                       ///< c of the current attempt
  bool byEvaluation_ = true;  ///< faces and graph tests by evaluation first (no patch leaves)
  std::unordered_map<const std::vector<Bernstein<S>>*, RootForms> rootForms_;
  FaceStore<S> faces_;  ///< every solved face
  std::vector<Polygon> polygons_;
  std::vector<S> rootPoints_;
  // Per leaf: proven empty (-1 unknown), next to an unproven face, next to an undecided face,
  // graph tests (-1 unknown), and the certificate's failure.
  std::vector<std::int8_t> empty_, bandEmpty_;
  std::vector<std::uint8_t> unproven_, stuck_, singular_;
  std::vector<std::int8_t> graph_, faceGraph_;
  /// Per leaf, the facets the leaf model shows M_c may meet (facetMask; kAllFacets: unknown).
  std::vector<std::uint64_t> facetsMet_;
  FlatMap<CellKey, std::int32_t> touchLeaves_;  ///< the touch leaves of one crossFaces, by base key
  std::array<Window, 2> windows_;  ///< crossFaces's: the one walked, the one solved beside
  std::vector<CellKey> deferred_;  ///< deferTouchLeaf's, until addDeferredLeaves
  /// Leaves per window of crossFaces: enough tasks for many threads, a few MB of slots.
  static constexpr std::int32_t kWindowLeaves = 2048;
  std::vector<Failure> failure_;
  std::vector<S> trouble_;  ///< n per leaf: where its certificate failed (setTrouble)
  std::vector<std::uint8_t> hasTrouble_;
  std::vector<FaceRef> unprovenFaces_;                  ///< recordUnproven
  std::vector<std::vector<std::int32_t>> unprovenOf_;   ///< per leaf: its unproven faces
  CellMap<std::vector<std::int32_t>> unprovenOfEmpty_;  ///< per empty cell
  std::vector<std::vector<std::int32_t>> blocks_;       ///< the leaves of certified blocks
  std::vector<std::int32_t> block_;                     ///< per leaf: its block, or -1
  /// Per block: its lower corner and level, and its leaves' failures before it (to dissolve
  /// it); a dissolved block has no leaves.
  std::vector<std::vector<std::int32_t>> blockLo_;
  std::vector<int> blockLevel_;
  std::vector<std::vector<CellKey>> blockEmpties_;  ///< its base cells the bounding excluded
  std::vector<std::vector<Failure>> blockSaved_;
  std::int64_t refined_ = 0;
  static constexpr std::size_t kMaxLeaves = std::size_t{1} << 22;
  std::size_t maxLeaves_ = 0, maxSolutionLeaves_ = 0;
  std::size_t solutionChildren_ = 0;  ///< solution children of the leaves refined so far
  bool refining_ = true;              ///< false: certify the base grid only (run's fallback)
  bool budgetSpent_ = false;
};

}  // namespace

template <class S>
ConnectionOutput<S> CrossingConnection::connect(const ConnectionInput<S>& in) const {
  if (in.k != 1 && in.k != 2) {
    throw InputError("connection 'crossing' supports k = 1 and k = 2, not k = " +
                     std::to_string(in.k));
  }
  return AdaptiveCrossing<S>(in, maxFaceDepth).run();
}

template ConnectionOutput<double> CrossingConnection::connect(const ConnectionInput<double>&) const;
template ConnectionOutput<Mpfr> CrossingConnection::connect(const ConnectionInput<Mpfr>&) const;

}  // namespace ndc
