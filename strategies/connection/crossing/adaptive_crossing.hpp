/// \file adaptive_crossing.hpp
/// The crossing connection's engine, AdaptiveCrossing, as a table of contents: its methods are
/// grouped by the file of this folder that defines them, a .inl per role, which only
/// adaptive_crossing_double.cpp and adaptive_crossing_mpfr.cpp include, to instantiate the class
/// once per scalar (docs/crossing.md, "Source files").
/// Internal to the crossing connection (strategies/connection/crossing.hpp is its interface).
///
/// Notation (docs/crossing.md, docs/certificate.md):
///  - n the ambient dimension, k the manifold's (1 or 2), m = n - k the equations of F.
///  - M = {F = 0}; M_c = {F = c}, the level set of the general-position offset c (level_,
///    GeneralPosition), whose crossings with the grid's faces make the mesh.
///  - A leaf is a cell of the adaptive 2^n-tree (tree_, CellTree), numbered in order of
///    creation; a minimal m-face is a face of k fixed axes (fixedAxes_) of the finest leaf
///    around it, owned by one leaf (ownedFaces) and solved once per level c (faces_).
///  - A touch leaf is an excluded base cell that M_c enters (addFace, deferTouchLeaf); a block
///    is 2^n leaves of one level certified together (mergeBlocks).
///
/// Invariants:
///  - perLeaf_ has a row for every leaf numbered so far (grow, before any row is written).
///  - The parallel tasks (prefetchLeaf, certifyLeaf, tryBlock) write only their own leaf's rows
///    and slots, so every output is independent of the thread count and the task order.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/cell_forms.hpp"
#include "framework/strategy/strategy.hpp"
#include "framework/util/flat_map.hpp"
#include "strategies/connection/crossing/cell_tree.hpp"
#include "strategies/connection/crossing/certificate.hpp"
#include "strategies/connection/crossing/dual_polygon.hpp"
#include "strategies/connection/crossing/face_solver.hpp"
#include "strategies/connection/crossing/face_store.hpp"
#include "strategies/connection/crossing/general_position.hpp"
#include "strategies/connection/crossing/leaf_model.hpp"

namespace ndc::crossing_detail {

/// Why a leaf is not certified (docs/certificate.md); the names go to uncertified.csv.
enum class Failure : std::uint8_t { kNone, kCrossing, kGraph, kFaceGraph, kLink, kBoundary };

/// A cell the bounding excluded (Occupant::Kind::kEmpty): a base cell the subdivision
/// excluded, or a child of a refined leaf that refinement excluded; its level and its key there.
struct EmptyCell {
  int level = 0;
  CellKey key = 0;
  bool operator==(const EmptyCell&) const = default;
};

/// A map keyed by excluded cells: one hash map per level of the tree (keys of different levels
/// may coincide).
template <class V>
class EmptyCellMap {
 public:
  /// Empty, for the levels base .. maxLevel.
  void reset(int base, int maxLevel) {
    base_ = base;
    levels_.assign(std::size_t(maxLevel - base + 1), {});
  }
  void clear() {
    for (CellMap<V>& level : levels_) level.clear();
  }
  V& operator[](const EmptyCell& e) { return levels_[std::size_t(e.level - base_)][e.key]; }
  const V* find(const EmptyCell& e) const {
    const CellMap<V>& level = levels_[std::size_t(e.level - base_)];
    const auto it = level.find(e.key);
    return it == level.end() ? nullptr : &it->second;
  }

 private:
  int base_ = 0;
  std::vector<CellMap<V>> levels_;
};

/// The excluded cell an occupant of kind kEmpty stands for.
inline EmptyCell emptyCellOf(const Occupant& o) { return EmptyCell{o.level, o.key}; }

/// Where a minimal m-face lies: its level, the index of its lower corner there and its k fixed
/// axes.
struct FaceRef {
  int level = 0;
  std::vector<std::int32_t> corner;
  std::array<int, 2> axes{};
};

/// The per-leaf state of AdaptiveCrossing, a column per field, indexed by leaf number (touch
/// leaves included from when they are numbered). The columns grow together (grow) and are
/// cleared together (clear).
template <class S>
struct LeafTable {
  /// A leaf's facet mask when nothing is known: every facet may meet M_c.
  static constexpr std::uint64_t kAllFacets = ~std::uint64_t{0};

  std::vector<std::int8_t> empty;      ///< M_c proven to miss the leaf: 1, or not: 0 (-1 unknown)
  std::vector<std::int8_t> bandEmpty;  ///< no level set between M and M_c meets it either
  std::vector<std::uint8_t> unproven;  ///< next to a face whose crossings are not proven
  std::vector<std::uint8_t> stuck;     ///< next to crossings no refinement separates
  std::vector<std::uint8_t> singular;  ///< next to an undecided face or one of degree > 1
  std::vector<std::int8_t> graph;      ///< cellGraph's answer (-1 unknown)
  std::vector<std::int8_t> faceGraph;  ///< facesGraph's answer (-1 unknown)
  /// The facets the leaf model shows M_c may meet (facetMask; kAllFacets: unknown).
  std::vector<std::uint64_t> facetsMet;
  std::vector<Failure> failure;  ///< the certificate's verdict
  std::vector<S> trouble;        ///< n per leaf: where its certificate failed (setTrouble)
  std::vector<std::uint8_t> hasTrouble;
  std::vector<std::vector<std::int32_t>> unprovenOf;  ///< its unproven faces (recordUnproven)
  std::vector<std::int32_t> block;                    ///< its block (mergeBlocks), or -1

  /// The leaves with a row.
  std::size_t size() const { return empty.size(); }

  /// Rows for `leaves` leaves in R^n: the new ones at their defaults (nothing known).
  void grow(std::size_t leaves, int n) {
    if (size() >= leaves) return;
    empty.resize(leaves, -1);
    bandEmpty.resize(leaves, 0);
    unproven.resize(leaves, 0);
    stuck.resize(leaves, 0);
    singular.resize(leaves, 0);
    graph.resize(leaves, -1);
    faceGraph.resize(leaves, -1);
    facetsMet.resize(leaves, kAllFacets);
    failure.resize(leaves, Failure::kNone);
    trouble.resize(leaves * n, S(0));
    hasTrouble.resize(leaves, 0);
    unprovenOf.resize(leaves);
    block.resize(leaves, -1);
  }

  /// The flags a pass over the faces sets (unproven, stuck, singular) cleared, before the pass.
  void clearFaceFlags() {
    std::fill(unproven.begin(), unproven.end(), 0);
    std::fill(stuck.begin(), stuck.end(), 0);
    std::fill(singular.begin(), singular.end(), 0);
  }

  /// No rows.
  void clear() {
    empty.clear(), bandEmpty.clear(), unproven.clear(), stuck.clear(), singular.clear();
    graph.clear(), faceGraph.clear(), facetsMet.clear(), failure.clear();
    trouble.clear(), hasTrouble.clear(), unprovenOf.clear(), block.clear();
  }
};

/// The crossing connection on an adaptive 2^n-tree: crossings on the minimal m-faces, the
/// certificate of every leaf, refinement of the leaves that fail it, and the dual complex.
template <class S>
class AdaptiveCrossing {
 public:
  /// Reweighted least-squares steps of a face's multiplier test (faceMultipliersExclude), as in
  /// the linearized bounding.
  static constexpr int kFaceMultiplierSteps = 8;
  /// The most Bernstein coefficients (all m equations' slices of one face) a face that
  /// evaluation does not decide is solved on; beyond, the face stays unproven (solveFace), so
  /// that no face costs (d + 1)^m per box for large m (docs/performance.md,
  /// "Without dense forms").
  static constexpr double kMaxFaceCoefficients = 32768;
  /// Faces whose slices have at most this many coefficients are solved on them at every level;
  /// larger ones only at the maximum level, or where refinement is off (solveFace).
  static constexpr double kCheapFaceCoefficients = 1024;
  /// The most Bernstein coefficients (all m equations' dense forms on a leaf) the certificate's
  /// tests restrict to a leaf where evaluation does not decide: beyond (a quadric in R^12 has
  /// 3^12 = 531441), such a test fails, and the leaf is refined or left uncertified, so that no
  /// leaf costs (d + 1)^n. Only programs without patch leaves go without (byEvaluation_).
  static constexpr double kMaxLeafCoefficients = 262144;
  /// The dense forms' coefficients per leaf up to which refineGraphFailures restricts them
  /// where evaluation does not prove a graph test; beyond, a coarse leaf that evaluation
  /// does not prove is refined at once.
  static constexpr double kCheapLeafCoefficients = 4096;
  /// Blocks (2^n leaves certified together, each region looked up) are tried up to this n
  /// only, so that no step costs 2^n past it (4,096 regions in R^12).
  static constexpr int kMaxBlockDimension = 12;
  /// A leaf's facet mask (facetMask) when nothing is known: every facet may meet M_c.
  static constexpr std::uint64_t kAllFacets = ~std::uint64_t{0};

  // ---- adaptive_crossing.inl: the run
  AdaptiveCrossing(const ConnectionInput<S>& in, int maxFaceDepth);
  /// The certified mesh, refining where the certificate fails. When refinement does not reach a
  /// certificate and its mesh has more non-manifold defects than the base grid's (crossings at
  /// the scale of the level offset c, docs/certificate.md "Status"), the base grid's is kept.
  ConnectionOutput<S> run();

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
    /// By evaluation only (refineGraphFailures): no Bernstein hulls, and a failure not cached.
    bool evaluationOnly = false;
  };

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

  /// A minimal m-face a leaf owns: its kind (a, side) and the leaves around it (kLeaf; any
  /// other region is looked up again by faceAround).
  struct OwnedFace {
    std::uint8_t a = 0, side = 0;
    std::array<Occupant, 4> around;  ///< as found when the list was made
  };

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

  /// A window of kWindowLeaves leaves of crossFaces and what its tasks found.
  struct Window {
    std::int32_t from = 0, end = 0;
    std::vector<std::int32_t> leaves;        ///< the active leaves that may be crossed
    std::vector<std::int8_t> prior;          ///< and their perLeaf_.empty when the window started
    std::vector<std::uint64_t> priorFacets;  ///< and their perLeaf_.facetsMet
    std::vector<const RootForms*> forms;
    std::vector<LeafFaces> slots;  ///< per leaf from `from` on
    std::size_t used = 0;          ///< the slots holding answers of the window's last use
  };

  /// levelsMet's working storage (threadScratch).
  struct CornerWork {
    std::vector<S> corner, zero;
  };

  /// A block certified by a task of mergeBlocks, before it is numbered.
  struct NewBlock {
    std::int32_t leaf = -1;  ///< the leaf that made it
    int level = 0;
    bool tentative = false;
    std::vector<std::int32_t> lo, members;
    std::vector<EmptyCell> empties;
    std::vector<Failure> saved;  ///< the members' failures before
  };

  /// A task of mergeBlocks: the scratch of a block's graph tests and the blocks it made.
  struct BlockWork {
    std::vector<Bernstein<S>> patches;
    std::vector<Interval<S>> jacobian;
    GraphTest<S> test;
    std::vector<NewBlock> made;
  };

  /// A leaf in prefetchLeaf's steps: its patches, restricted on first use (restrictOnce), and
  /// its affine model, built on first use (modelOnce), with the slot its answers go to.
  struct PrefetchedLeaf {
    PrefetchedLeaf(std::int32_t c, const RootForms& rf, LeafFaces& out)
        : c(c), rf(rf), out(out), patches(leafScratch(own)) {}
    std::int32_t c;
    const RootForms& rf;
    LeafFaces& out;
    std::vector<Bernstein<S>> own;       ///< leafScratch's, in MPFR
    std::vector<Bernstein<S>>& patches;  ///< leafScratch's
    bool restricted = false;             ///< whether `patches` hold the leaf's
    LeafModel<S> model;
    bool modelled = false;  ///< whether `model` is the leaf's
  };

  // ---- adaptive_crossing.inl: the run (continued)
  /// Level offsets until no crossing is within rounding of a face boundary, each with its
  /// refinement and certificate; the complex of the last.
  ConnectionOutput<S> attempts();
  /// Edges of more than two triangles (k = 2) or vertices of more than two edges (k = 1).
  static std::int64_t nonmanifold(const Complex<S>& complex);
  /// The topology record from the final tree.
  void record(TopologyRecord& t, std::int64_t degenerate) const;
  /// The dual complex of the final tree (docs/crossing.md, steps 3 and 4, and "The domain's
  /// boundary"), blocks merged where every leaf is certified.
  void buildComplex(ConnectionOutput<S>& out);

  // ---- refinement.inl: the refinement loop and its budget
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
  void setBudget(std::size_t baseCells, bool tolerance, double refineSeconds);
  /// Whether refining `refine` leaves stays within the budget: the leaves it adds at most, and
  /// the solution leaves it adds, predicted from the solution children per refined leaf so far
  /// (2^k before the first refinement: a k-manifold through a cell meets about 2^k children).
  bool withinBudget(std::size_t refine) const;
  /// Crossings, certificates and refinement until every leaf is certified or at the maximum
  /// level (or the leaf budget is spent). Returns the degenerate crossings of the last pass.
  std::int64_t refineAndCertify();
  /// Refines `refine` (leaves of the tree): their children by the run's bounding test.
  void refineLeaves(const std::vector<std::int32_t>& refine);
  /// Refines the leaves within kEagerLevels of the base grid whose graph test fails, before
  /// their faces are solved (refinement would follow their certificate's failure anyway).
  void refineGraphFailures();
  /// Whether leaf c fails refineGraphFailures's tests: not proven empty by intervals, and its
  /// graph test, or for k = 2 a face graph test where M is not tangent to the facet's plane,
  /// fails (by evaluation only unless cheapForms_).
  bool failsGraphTests(std::int32_t c, const RootForms& rf);
  /// How many levels below the base grid refineGraphFailures reaches.
  static constexpr int kEagerLevels = 3;
  /// Whether refinement will still try leaf c if it fails: refinement is on, c is above the
  /// maximum level and not next to crossings no refinement separates.
  bool refinable(std::int32_t c) const;
  /// Whether M is tangent to the plane of one of leaf c's unproven faces, or (a face graph
  /// failure) of one of its facets: tangentToFace (domain_boundary.hpp) on each. There no
  /// refinement proves the leaf, and it tries blocks at once (a heuristic: it proves nothing).
  /// faceMemo (one entry per unproven face, -1 before its probe) keeps the faces' answers.
  bool tangentToGridPlane(std::int32_t c, std::vector<signed char>& faceMemo) const;
  /// Whether M is tangent to the hyperplane of one of leaf c's facets (tangentToFace on each).
  bool tangentToFacetPlane(std::int32_t c) const;

  // ---- chord_refinement.inl: --tolerance, the leaves whose mesh is beyond the chord error
  /// `--tolerance`: the leaves below the maximum level that are nodes of a mesh polygon inside
  /// the domain whose simplices have a barycentre farther than the tolerance from its Newton
  /// projection onto M (the analysis's chord error; the polygons at the domain's boundary, whose
  /// boundary vertices are not placed here, are not tested). Each leaf's vertex is taken as the
  /// projection of the mean of its crossings, as the dual complex places it (a block's: of the
  /// block's crossings).
  std::vector<std::int32_t> chordLeaves() const;
  /// Whether a simplex of the polygon (its edge, or its triangles split along the shorter
  /// diagonal as addSimplices does) has its barycentre farther than `tolerance` from M.
  bool chordAbove(const Polygon& poly, const std::vector<S>& vertex, const S& tolerance) const;

  // ---- leaf_patches.inl: a leaf's Bernstein patches
  /// The root forms of the leaf at `index` of `level`, with their margins (cached).
  const RootForms& rootForms(std::span<const std::int32_t> index, int level);
  /// The root forms of every leaf in `leaves` (rootForms, which fills its cache: call it
  /// before a parallel loop reads them).
  std::vector<const RootForms*> rootFormsOf(const std::vector<std::int32_t>& leaves);
  /// The box of `leaf`.
  Box<S> leafBox(std::int32_t leaf) const;
  /// The leaf's Bernstein patches into `patches`, whether they prove that M_c misses the
  /// closed leaf (returned; then no face of it is crossed) and whether no level set
  /// F = t c, t in [0, 1], meets it either (`band`: M itself, and the isotopy from M to M_c).
  /// Reads only: safe in parallel tasks.
  bool restrictLeaf(std::int32_t leaf, const RootForms& rf, std::vector<Bernstein<S>>& patches,
                    bool& band) const;
  /// A task's patches: per thread in double (restrictLeaf then allocates nothing per leaf),
  /// `own` (the caller's, fresh) in MPFR, whose numbers carry a precision.
  static std::vector<Bernstein<S>>& leafScratch(std::vector<Bernstein<S>>& own);
  /// The leaf's patches into t (once).
  void prepare(std::int32_t leaf, const RootForms& rf, LeafTests& t) const;

  // ---- face_walk.inl: the pass over the minimal m-faces, window by window, and what it records
  /// One pass over the minimal m-faces of the active leaves: the polygons of the crossed ones
  /// (excluded base cells around a crossed face become touch leaves, walked in turn) and the
  /// leaves next to a face whose crossings are not proven. Returns the degenerate crossings.
  /// The leaves go in windows: a window's faces are solved in parallel (startWindow), and while
  /// the walk takes one window's answers in leaf order from its slots, the faces it solved are
  /// kept and the next window is solved beside it. The tasks write nothing the walk reads but
  /// the slots of the window walked next, and the walk defers the touch leaves it adds to the
  /// tree until they are done (finishWindow), so nothing depends on the thread count.
  std::int64_t crossFaces();
  /// Starts, as `beside`'s task, keeping the faces that the window `keep` (if any) solved, then
  /// solving the window of leaves from `from` on (up to kWindowLeaves, so that the slots'
  /// memory stays bounded): each active leaf that may be crossed is a task that restricts it
  /// and solves the faces it owns that faces_ does not hold yet, writing only its slot
  /// (prefetchLeaf). Meanwhile the caller may walk `keep`, which reads only its slots.
  void startWindow(TaskBeside& beside, std::int32_t from, Window& w, const Window* keep);
  /// Waits for the window solved beside the walk and adds the touch leaves the walk deferred.
  void finishWindow(TaskBeside& beside);
  /// Keeps the new faces of a solved window in faces_.
  void keepFaces(const Window& w);
  /// The walk over one solved window's leaves in order: the faces that leave a trace.
  std::int64_t walkWindow(const Window& w);
  /// Records a solved face: flags its leaves when the face is not proven, and adds its
  /// polygon (|degree| copies) when it is crossed. Returns its degenerate crossings.
  std::int64_t addFace(const FaceResult<S>& r, std::array<Occupant, 4>& around, int level,
                       const std::vector<std::int32_t>& corner, const std::array<int, 2>& axes);
  /// A touch leaf at the excluded base cell `key`: its number now, its place in the tree once
  /// the window solved beside the walk is done (addDeferredLeaves), so that the tasks never
  /// see the tree change.
  std::int32_t deferTouchLeaf(const EmptyCell& cell);
  /// Adds the deferred touch leaves to the tree, in order: they get the numbers they were given.
  void addDeferredLeaves();
  /// The leaves of the tree and the deferred touch leaves.
  std::size_t leafCount() const;
  /// The centre of the face of `level` with lower corner `corner` and fixed axes `axes`.
  std::vector<S> faceCentre(int level, const std::vector<std::int32_t>& corner,
                            const std::array<int, 2>& axes) const;
  /// The leaves around an unproven face (-1 for other regions), for the blocks' test.
  void recordUnproven(const std::array<Occupant, 4>& around, const FaceRef& face);
  /// Records a point near which the certificate of `leaf` failed (the first one stays): where
  /// a block around the leaf should have its centre.
  void setTrouble(std::int32_t leaf, std::span<const S> point);
  /// setTrouble at the centre of face (a, upper) of a leaf.
  void faceTrouble(std::int32_t leaf, int a, bool upper);
  /// The per-leaf table follows the tree's growth (and the deferred touch leaves).
  void grow();

  // ---- owned_faces.inl: the minimal m-faces a leaf owns and the regions around them
  /// The faces leaf c owns, in the order crossFaces walks them, into `out`. Touch leaves, which
  /// crossFaces adds at excluded base cells, change neither which faces are minimal (a base-level
  /// leaf where there was none is never finer) nor who owns them (a touch leaf comes after every
  /// leaf already there), so this list stays valid for the whole walk.
  void ownedFaces(std::int32_t c, std::uint64_t facets, std::vector<OwnedFace>& out) const;
  /// The lower corner of an owned face and the regions around it now: as recorded, except
  /// an excluded base cell that a touch leaf has filled since (what CellTree::find says now).
  void faceAround(const std::vector<std::int32_t>& ci, const OwnedFace& f,
                  std::vector<std::int32_t>& corner, std::array<Occupant, 4>& around) const;
  /// Which face of its leaf (a, side) is, among the leaf's faces (FaceStore's kind).
  std::uint32_t faceKind(std::size_t a, int side) const;
  /// A leaf's facets as facetsOfModel gives them (entry 2 j + side) in one mask, bit 2 j + side
  /// set where M_c may meet the facet; kAllFacets (every facet may) beyond 32 variables.
  std::uint64_t facetMask(const std::vector<char>& met) const;
  /// Whether `mask` (facetMask) lets M_c meet the facet fixing axis a at its lower (side 0) or
  /// upper (1) end.
  bool facetMet(std::uint64_t mask, int a, int side) const;

  // ---- prefetch.inl: a window's task per leaf: its emptiness, its facets and its faces solved
  /// One task of startWindow: leaf c, whose perLeaf_.empty was `prior` and perLeaf_.facetsMet
  /// `priorFacets` when its window started, into its slot `out`.
  void prefetchLeaf(std::int32_t c, std::int8_t prior, std::uint64_t priorFacets,
                    const RootForms& rf, LeafFaces& out) const;
  /// prefetchLeaf's first step, for a leaf whose emptiness is unknown: whether M_c misses it, by
  /// its affine model where that decides, else by its Bernstein forms (restrictOnce).
  void prefetchEmptiness(PrefetchedLeaf& leaf) const;
  /// For a surface, the facets the model shows M_c may meet (docs/crossing.md, "Facets
  /// first"), once per leaf: a face in a facet M_c misses is not crossed, and ownedFaces leaves
  /// it out.
  void prefetchFacets(PrefetchedLeaf& leaf, std::uint64_t priorFacets) const;
  /// The faces the leaf owns: those of earlier rounds copied from faces_, the others solved
  /// (solveFace); the slot keeps those the walk visits.
  void prefetchFaces(PrefetchedLeaf& leaf) const;
  /// The leaf's patches restricted into leaf.patches, once (restrictLeaf), with the emptiness
  /// they prove if it is not known yet.
  void restrictOnce(PrefetchedLeaf& leaf) const;
  /// The leaf's affine model built into leaf.model, once (buildLeafModel).
  void modelOnce(PrefetchedLeaf& leaf) const;
  /// Whether leaf c is empty by prefetchLeaf's answer, which it gives whenever perLeaf_.empty[c]
  /// is unknown (perLeaf_.bandEmpty[c] is set too; the caller has grown the per-leaf table).
  bool emptyOf(std::int32_t c, const LeafFaces& known);
  /// Whether the leaf's affine model proves that no level set F = t c, t in [0, 1], meets it
  /// (bandExcluded: the linearized system's tests on the model; docs/crossing.md, "Empty leaves
  /// by the model"). Then restrictLeaf would find the leaf empty with its band too, or fail to
  /// prove what this proves: the Bernstein forms are not needed.
  bool modelExcludesBand(const LeafModel<S>& model) const;
  /// Whether every F_i - c_i provably takes both signs on the leaf `box` of `model`: its sign
  /// at the centre (the model's value), and the opposite one at the corner where the model's
  /// gradient points away from it (a midpoint-radius run at that corner). Then no Bernstein form
  /// of the leaf clears its level (the coefficients' hull holds the range, within the rounding
  /// margin), so the leaf is not empty, and restricting its forms to find that out is spared.
  bool levelsMet(const LeafModel<S>& model, const Box<S>& box) const;
  /// Whether a face leaves no trace in the walk: not crossed, and addFace flags none of its
  /// leaves (proven, decided, clear of rounding and of the face's boundary).
  template <class Face>
  static bool quiet(const Face& r);
  /// The Bernstein coefficients of the slices of the m equations on a face with fixed `axes`:
  /// what one box of the face's Bernstein solve costs (FaceSolver::setBernsteinCost).
  double faceCoefficients(const std::array<int, 2>& axes) const;
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
                          Preconditioner&& preconditioner) const;
  /// The face slices (axes, side) of a leaf's patches into `face` (`cut`: scratch).
  void faceSlices(const std::vector<Bernstein<S>>& patches, const std::array<int, 2>& axes,
                  int side, std::vector<Bernstein<S>>& face, std::vector<Bernstein<S>>& cut) const;
  /// The rest of solveFace: the roots' degree and degeneracy.
  FaceResult<S> faceOutcome(FaceResult<S> r, const std::vector<std::vector<S>>& roots,
                            const Box<S>& box, const std::vector<int>& freeAxes,
                            const FaceEnds& ends) const;

  // ---- leaf_certificate.inl: each leaf's certificate (graphs, face graphs, link, boundary)
  /// The certificate of every active leaf (docs/certificate.md) into perLeaf_.failure.
  void certify();
  /// The certificate of active leaf c into perLeaf_.failure[c]. It writes only what belongs to c
  /// (its failure, its cached graph tests and its trouble point), so certify runs the leaves in
  /// parallel and the result does not depend on their order.
  void certifyLeaf(std::int32_t c, const RootForms& rf, std::span<const std::int32_t> ps);
  /// The graph test of a leaf's box (cached): M_c ∩ leaf is proven a graph over k of the
  /// coordinates (J enclosed by the widened derivative hulls of the leaf's patches).
  bool cellGraph(std::int32_t leaf, const RootForms& rf, LeafTests& t);
  /// J over the whole leaf by evaluation into t.whole, once per LeafTests (the cell's graph test
  /// and the face graph tests share it); false when a run failed.
  bool leafJacobian(std::int32_t leaf, LeafTests& t) const;
  /// The graph test with J(X) from midpoint-radius runs of the programs over the face `box` of
  /// a leaf that fixes axis `fixed`: true when some m columns of the free axes form a regular
  /// block. `excluded`: F - c provably has no zero on the face (that alone passes the face
  /// graph test).
  bool evaluatedGraph(const Box<S>& box, int fixed, bool& excluded, LeafTests& t) const;
  /// J(X) over `box` (m x n, row-major) from midpoint-radius runs of the programs into
  /// `jacobian`; `excluded`: some F_i - c_i provably has no zero on the box. False when a run
  /// fails.
  bool evaluatedJacobian(const Box<S>& box, std::vector<Interval<S>>& jacobian,
                         bool& excluded) const;
  /// The graph test of the box of `patches` (jacobian: scratch; test: graphTest_ or a copy).
  bool graphOf(const std::vector<Bernstein<S>>& patches, std::span<const S> margins,
               std::vector<Interval<S>>& jacobian, GraphTest<S>& test) const;
  /// The graph test on the columns `axes` of J enclosed by the derivative hulls of `patches`.
  bool hullGraph(const std::vector<Bernstein<S>>& patches, std::span<const S> margins,
                 const std::vector<int>& axes, std::vector<Interval<S>>& jacobian,
                 GraphTest<S>& test) const;
  /// Whether interval evaluation proves that M_c (with `band`: no level set between M and M_c)
  /// does not meet `box`; for m = 1, the sign rule's level set F = -delta: F >= 0 or F < 0 on
  /// the box. Catches what coefficient hulls miss, such as y^2 on a box around y = 0.
  bool intervalEmpty(const Box<S>& box, bool band) const;
  /// k = 2: the graph test of every (n-1)-face of a leaf (cached): M_c ∩ face is empty or a
  /// graph over one coordinate, so no closed curve of M_c lies inside a face.
  bool facesGraph(std::int32_t leaf, const RootForms& rf, LeafTests& t);
  /// The free axes of a face that fixes axis a.
  std::vector<int> freeAxes(int a) const;
  /// The faces of the box of `patches` that fail the face graph test, as (fixed axis, upper):
  /// every one, or (`all` false) the first (jacobian: scratch; test: graphTest_ or a copy).
  std::vector<std::pair<int, bool>> failingFacesOf(const std::vector<Bernstein<S>>& patches,
                                                   std::span<const S> margins, bool all,
                                                   std::vector<Interval<S>>& jacobian,
                                                   GraphTest<S>& test) const;
  /// faceGraph on the box of `patches` (jacobian: scratch; test: graphTest_ or a copy).
  bool faceGraphOf(const std::vector<Bernstein<S>>& patches, std::span<const S> margins, int a,
                   bool upper, const std::vector<int>& axes, std::vector<Interval<S>>& jacobian,
                   GraphTest<S>& test) const;
  /// Whether every level set between M and M_c meets the domain's boundary transversally in
  /// leaf c (docs/certificate.md, "The domain's boundary"): each face of the leaf's box in a
  /// face of the domain of dimension n - j is missed by all of them (interval evaluation of
  /// F - t c, t in [0, 1]), or, for j <= k, J's columns of its free axes have full rank m over
  /// it (the graph test on those columns, whatever the level). A tangency of M with a domain
  /// face, or M through a domain face of dimension below m, fails here. `mark`: a failing leaf
  /// whose face M is tangent to (tangentToFace) is marked stuck: refinement would not help.
  bool boundaryTransverse(std::int32_t c, const RootForms& rf, LeafTests& t, bool mark);

  // ---- blocks.inl: blocks of 2^n leaves certified together, and the mesh seen through them
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
                   const std::vector<const RootForms*>& forms);
  /// The first block that certifies around leaf c (its candidates, then its lattice blocks),
  /// into w.made.
  void blocksOf(std::int32_t c, const RootForms& rf, const Incidence& incident, BlockWork& w);
  /// The blocks of mergeBlocks' tasks in the order of the leaves that made them.
  static std::vector<NewBlock> orderedBlocks(std::vector<BlockWork>& work);
  /// The leaves of `trying` (positions in it) grouped into clusters, each in order: two leaves
  /// of one level within two cells of each other along every axis are in one cluster (the
  /// blocks of each lie within one cell of it, so only such leaves can compete for a leaf).
  /// The clusters are in the order of their first leaves.
  std::vector<std::vector<std::int32_t>> blockClusters(
      const std::vector<std::int32_t>& trying) const;
  /// The axis along which the leaves take the most distinct (level, index) values.
  int spreadAxis(const std::vector<std::int32_t>& leaves) const;
  /// The lower corners of the blocks of 2^n leaves that hold leaf c, the one centred nearest
  /// its trouble point first, then those that differ from it along more and more axes (at
  /// most kBlockTries).
  std::vector<std::vector<std::int32_t>> blockCandidates(std::int32_t c) const;
  /// The blocks for leaf c on a curve of tangency: for each grid plane next to c that holds
  /// every unproven face next to c, the block that straddles the plane and has even lower
  /// corners along the other axes (so that the blocks along the curve tile it face to face).
  std::vector<std::vector<std::int32_t>> latticeBlocks(std::int32_t c) const;
  /// The certificate of the block of 2^n leaves of `level` with lower corner `lo`: its leaves
  /// free, one polynomial piece, every unproven face inside it, the crossings on its boundary
  /// one simple piece, and the graph and face graph tests on its box.
  /// Leaf c's try (mergeBlocks' task w): `rf` its root forms, which are the block's; a block
  /// that certifies takes its members (perLeaf_.block and perLeaf_.failure) and goes to w.made.
  bool tryBlock(std::int32_t c, const std::vector<std::int32_t>& lo, const Incidence& incident,
                bool tentative, const RootForms& rf, BlockWork& w);
  /// The graph tests of a block's box (the box's, and for k = 2 each facet's) on J enclosed
  /// over the whole box by evaluation: true when that proves them all (no Bernstein form).
  bool evaluatedBlockGraphs(const Box<S>& box, BlockWork& w) const;
  /// The leaves of a block: every region of it an active leaf of `level` in no other block,
  /// inside one polynomial piece of the input.
  bool blockMembers(int level, const std::vector<std::int32_t>& lo,
                    std::vector<std::int32_t>& members, std::vector<EmptyCell>& empties) const;
  /// The polygons of the block's boundary with its leaves as one node (members.front());
  /// those inside it drop out. False when a polygon meets the block twice (not a box).
  bool blockLink(const std::vector<std::int32_t>& members, const Incidence& incident,
                 std::vector<Polygon>& link, std::vector<std::int32_t>& ps) const;
  /// Face (a, upper) of the block (level, lo) leaf face by leaf face: no unproven face inside
  /// it (its crossings on the leaf faces' common edges are proven, so the link sees every
  /// piece of M on it) and each leaf face empty or a graph. `rf`: the block's root forms (its
  /// leaves'); w.patches changed.
  bool subFacesGraph(int level, const std::vector<std::int32_t>& lo,
                     const std::vector<std::int32_t>& members, int a, bool upper,
                     const RootForms& rf, BlockWork& w);
  /// When the face lies inside exactly one face of the box of the block (level, lo), on one
  /// of its boundary planes and strictly inside along every other axis: that plane's axis
  /// (`upper`: the block's upper side). Otherwise -1.
  int blockFaceAxis(const FaceRef& face, int level, const std::vector<std::int32_t>& lo,
                    bool& upper) const;
  bool onOneBlockFace(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const;
  /// Whether the face lies inside the block of `level` with lower corner `lo` (not on its
  /// boundary).
  bool inside(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const;
  /// Dissolves the blocks that do not stand (mergeBlocks) until every remaining one does.
  void verifyBlocks(const Incidence& incident);
  /// Whether block b stands among the others: every unproven face next to it inside it, or
  /// inside one face of its box with block leaves across, and its link (every block one node)
  /// one cycle.
  bool blockStands(std::size_t b, const Incidence& incident) const;
  /// The polygons incident to any of the leaves, once each.
  static std::vector<std::int32_t> blockPolygons(const std::vector<std::int32_t>& members,
                                                 const Incidence& incident);
  /// Whether the face lies inside exactly one face of the block's box (level, lo) and every
  /// leaf across that face next to it is a leaf of `level` in a block.
  bool sharedBlockFace(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const;
  /// A polygon node as the mesh sees it: a leaf in a block is the block's first leaf.
  std::int64_t blockNode(std::int64_t node) const;
  /// A polygon with its nodes mapped by `map`, equal neighbours merged (cyclically).
  template <class Map>
  static Polygon collapsed(const Polygon& poly, const Map& map);
  /// The mesh's polygons with every certified block as one node (its first leaf), when every
  /// leaf is certified: then the mesh is the dual of the certified decomposition. Otherwise
  /// the blocks stay apart: merging a block's vertices is an edge contraction, and next to an
  /// uncertified leaf nothing proves its link condition.
  void collapseBlocks(bool certified);

  const ConnectionInput<S>& in_;
  const Grid& grid_;
  int n_, k_, m_, maxFaceDepth_;
  Box<S> domain_;
  CellForms<S> cellForms_;  ///< the Bernstein forms of every leaf
  const GeneralPosition<S> position_;
  GraphTest<S> graphTest_;
  CellTree tree_;
  std::vector<std::array<int, 2>> fixedAxes_;  ///< the k fixed axes of each kind of m-face
  std::vector<std::vector<int>> degrees_;      ///< each equation's degree in each variable
  /// Whether the leaves' dense Bernstein forms are used where evaluation decides nothing
  /// (kMaxLeafCoefficients); without them such a test fails (docs/performance.md, "Without
  /// dense forms").
  bool dense_ = true;
  /// Whether the dense forms are at most kCheapLeafCoefficients per leaf, or the only way.
  bool cheapForms_ = true;
  /// The progress stage of the round (refineAndCertify): its number, leaves and refined leaves.
  std::string progressLabel_ = "connection";
  std::size_t progressLeaves_ = 0;  ///< the leaves when the round started
  /// Reports the round's progress (in_.progress): `walked` of its leaves walked.
  void reportProgress(std::int32_t walked);
  /// Faces solved so far (prefetchFaces; TopologyRecord::facesSolved).
  mutable std::atomic<std::int64_t> facesSolved_{0};
  RootForms noForms_;         ///< rootForms' answer without dense forms: no forms, zero margins
  std::vector<S> level_;      ///< c of the current attempt
  bool byEvaluation_ = true;  ///< faces and graph tests by evaluation first (no patch leaves)
  std::unordered_map<const std::vector<Bernstein<S>>*, RootForms> rootForms_;
  FaceStore<S> faces_;  ///< every solved face
  std::vector<Polygon> polygons_;
  std::vector<S> rootPoints_;
  LeafTable<S> perLeaf_;                    ///< what is known of each leaf
  EmptyCellMap<std::int32_t> touchLeaves_;  ///< the touch leaves of one crossFaces, by their cell
  std::array<Window, 2> windows_;           ///< crossFaces's: the one walked, the one solved beside
  std::vector<EmptyCell> deferred_;         ///< deferTouchLeaf's, until addDeferredLeaves
  /// Leaves per window of crossFaces: enough tasks for many threads, a few MB of slots.
  static constexpr std::int32_t kWindowLeaves = 2048;
  std::vector<FaceRef> unprovenFaces_;                       ///< recordUnproven
  EmptyCellMap<std::vector<std::int32_t>> unprovenOfEmpty_;  ///< per excluded cell
  std::vector<std::vector<std::int32_t>> blocks_;            ///< the leaves of certified blocks
  /// Per block: its lower corner and level, and its leaves' failures before it (to dissolve
  /// it); a dissolved block has no leaves.
  std::vector<std::vector<std::int32_t>> blockLo_;
  std::vector<int> blockLevel_;
  std::vector<std::vector<EmptyCell>> blockEmpties_;  ///< its cells the bounding excluded
  std::vector<std::vector<Failure>> blockSaved_;
  std::int64_t refined_ = 0;
  /// The most leaves of the tree, for memory: every leaf is a solution or a touch leaf
  /// (refinement makes no leaf of an excluded child), so the solution-leaf budget binds first.
  static constexpr std::size_t kMaxLeaves = std::size_t{1} << 22;
  std::size_t maxSolutionLeaves_ = 0;
  std::size_t solutionChildren_ = 0;  ///< solution children of the leaves refined so far
  bool refining_ = true;              ///< false: certify the base grid only (run's fallback)
  bool budgetSpent_ = false;
  /// Blocks for every failing leaf, also those refinement could still prove (mergeBlocks):
  /// set for the last certify of a run whose refinement stopped at its budget.
  bool blocksEverywhere_ = false;
};

// The one explicit instantiation definition of each (a program may hold only one) is in
// adaptive_crossing_double.cpp and adaptive_crossing_mpfr.cpp.
extern template class AdaptiveCrossing<double>;
extern template class AdaptiveCrossing<Mpfr>;

}  // namespace ndc::crossing_detail
