/// \file crossing_detail.hpp
/// Internal to the crossing connection (docs/crossing.md): the state of AdaptiveCrossing and the
/// types its phases share. The phases are defined in crossing_faces.cpp (crossings on the
/// minimal m-faces), crossing_certify.cpp (the certificate of a leaf), crossing_blocks.cpp
/// (blocks of leaves around a tangency), crossing_refine.cpp (the refinement loop) and
/// crossing.cpp (the dual complex and the entry point); each instantiates its definitions for
/// double and ndc::Mpfr.
#pragma once

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <unordered_map>
#include <vector>

#include "framework/core/bernstein.hpp"
#include "framework/core/interval.hpp"
#include "strategies/connection/cell_tree.hpp"
#include "strategies/connection/certificate.hpp"
#include "strategies/connection/crossing.hpp"

namespace ndc::crossing_detail {

template <class S>
using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// Which ends of a face's free axes lie on the domain boundary. There the face has no
/// neighbour to share a crossing with, so it is closed, and it keeps crossings up to `slack`
/// outside (the perturbed level set F = c leaves the domain by that much where M touches it).
struct FaceEnds {
  std::vector<bool> lower, upper;
};

/// Singular values of the Jacobian at x, largest first.
template <class S>
Vector<S> singularValuesAt(const System<S>& system, std::span<const S> x);

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

  /// Gradient scale, slack and tolerance from the projected points of the solution cells.
  GeneralPosition(const ConnectionInput<S>& in, const Grid& grid);

  /// The level of attempt a: c_i = theta_{a,i} * scale_i with theta in [0.5, 1) from the
  /// golden-ratio sequence (no two attempts or equations share a ratio).
  std::vector<S> level(int attempt) const;

  /// How many of a face's roots lie within the tolerance of one of its grid (not domain)
  /// boundaries: there the face and its neighbour could disagree about the root.
  std::int64_t nearBoundary(const std::vector<std::vector<S>>& roots, const Box<S>& box,
                            const std::vector<int>& freeAxes, const FaceEnds& ends) const;

  std::vector<S> scale;  ///< kRelative * cell width * gradient scale, per equation
  S slack;               ///< crossings kept this far outside the domain
  S tolerance;           ///< a root this close to a face boundary is degenerate
};

/// Union-find over small integer sets (the link of one vertex).
struct UnionFind {
  std::vector<int> parent;
  int find(int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

/// A crossed minimal m-face of the tree (docs/certificate.md): the leaves around it in cyclic
/// order (k = 2; a coarser leaf that fills two of the four quadrants appears once, so the
/// polygon is a triangle), or the two leaves across it (k = 1). A node is a leaf number, or
/// -1 - tag for a region beyond the domain (such a polygon only enters the certificate).
struct Polygon {
  std::array<std::int64_t, 4> node{-1, -1, -1, -1};
  int size = 0;
  std::int32_t root = -1;  ///< its crossing, in the root list
  bool outside = false;    ///< a node lies beyond the domain: not a cell of the mesh
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

/// Why a leaf is not certified (docs/certificate.md); the names go to uncertified.csv.
enum class Failure : std::uint8_t { kNone, kCrossing, kGraph, kFaceGraph, kLink };

/// The crossing connection on an adaptive 2^n-tree: crossings on the minimal m-faces, the
/// certificate of every leaf, refinement of the leaves that fail it, and the dual complex.
/// Its phases are defined in crossing_faces.cpp, crossing_certify.cpp, crossing_blocks.cpp,
/// crossing_refine.cpp and crossing.cpp, over the state held in its members.
template <class S>
class AdaptiveCrossing {
 public:
  AdaptiveCrossing(const ConnectionInput<S>& in, int maxFaceDepth);

  /// The certified mesh, refining where the certificate fails. When refinement does not reach a
  /// certificate and its mesh has more non-manifold defects than the base grid's (crossings at
  /// the scale of the level offset c, docs/certificate.md "Status"), the base grid's is kept.
  ConnectionOutput<S> run();

  /// Edges of more than two triangles (k = 2) or vertices of more than two edges (k = 1).
  static std::int64_t nonmanifold(const Complex<S>& complex);

  /// Level offsets until no crossing is within rounding of a face boundary, each with its
  /// refinement and certificate; the complex of the last.
  ConnectionOutput<S> attempts();

 private:
  using Occ = Occupant::Kind;
  /// The root forms a leaf's patches are restricted from (the domain's, or the B-spline
  /// patch's), with the rounding margin of each equation.
  struct RootForms {
    std::vector<Bernstein<S>> forms;
    std::vector<S> margins;
  };

  // Phase 1, crossing_faces.cpp: the leaves' patches and the crossings on their minimal m-faces.
  const RootForms& rootForms(std::span<const std::int32_t> index, int level);

  Box<S> leafBox(std::int32_t leaf) const;

  /// The leaf's Bernstein patches (into patches_) and whether they prove that M_c does not
  /// meet the closed leaf (then no face of it is crossed); bandEmpty_ records whether no level
  /// set F = t c, t in [0, 1], meets it either (M itself, and the isotopy from M to M_c).
  bool restrictTo(std::int32_t leaf);

  /// Solves face (axes, side) of `leaf` (patches_ hold the leaf's patches).
  FaceResult<S> solveFace(std::int32_t leaf, const std::array<int, 2>& axes, int side);

  /// One pass over the minimal m-faces of the active leaves: the polygons of the crossed ones
  /// (excluded base cells around a crossed face become touch leaves, walked in turn) and the
  /// leaves next to a face whose crossings are not proven. Returns the degenerate crossings.
  std::int64_t crossFaces();

  /// Records a solved face: flags its leaves when the face is not proven, and adds its
  /// polygon (|degree| copies) when it is crossed. Returns its degenerate crossings.
  std::int64_t addFace(const FaceResult<S>& r, std::array<Occupant, 4>& around,
                       const FaceRef& face);

  /// The leaves around an unproven face (-1 for other regions), for the blocks' test.
  void recordUnproven(const std::array<Occupant, 4>& around, const FaceRef& face);

  // Phase 2, crossing_certify.cpp: the certificate of each leaf (graph tests, link).
  /// Records a point near which the certificate of `leaf` failed (the first one stays): where
  /// a block around the leaf should have its centre.
  void setTrouble(std::int32_t leaf, std::span<const S> point);

  /// setTrouble at the centre of face (a, upper) of a leaf.
  void faceTrouble(std::int32_t leaf, int a, bool upper);

  /// The graph test of a leaf's box (cached): M_c ∩ leaf is proven a graph over k of the
  /// coordinates (J enclosed by the widened derivative hulls of the leaf's patches).
  bool cellGraph(std::int32_t leaf);

  /// The graph test of the box of patches_.
  bool patchesGraph();

  /// Whether interval evaluation proves that M_c (with `band`: no level set between M and M_c)
  /// does not meet `box`; for m = 1, the sign rule's level set F = -delta: F >= 0 or F < 0 on
  /// the box. Catches what coefficient hulls miss, such as y^2 on a box around y = 0.
  bool intervalEmpty(const Box<S>& box, bool band);

  /// k = 2: the graph test of every (n-1)-face of a leaf (cached): M_c ∩ face is empty or a
  /// graph over one coordinate, so no closed curve of M_c lies inside a face.
  bool facesGraph(std::int32_t leaf);

  /// The free axes of a face that fixes axis a.
  std::vector<int> freeAxes(int a) const;

  /// The faces of the box of patches_ that fail the face graph test, as (fixed axis, upper):
  /// every one, or (`all` false) the first.
  std::vector<std::pair<int, bool>> failingFaces(bool all = true);

  /// The first face (2 a + side) of the box of patches_ that fails the face graph test, or -1.
  int failingFace();

  /// The graph test of one face of the leaf in patches_ (fixed axis a at its lower or upper
  /// end): empty, or a graph over one of the free axes.
  bool faceGraph(int a, bool upper, const std::vector<int>& axes);

  /// The certificate of every active leaf (docs/certificate.md) into failure_.
  void certify();

  /// The link of leaf c (k = 2): one edge per polygon, between the polygon's two nodes next to
  /// c; `nodes` receives the distinct neighbour nodes the edges number.
  static std::vector<std::array<int, 2>> linkEdges(std::int64_t c,
                                                   const std::vector<Polygon>& polygons,
                                                   const std::vector<std::int32_t>& ps,
                                                   std::vector<std::int64_t>& nodes);

  /// Whether the crossings on the boundary of leaf c form one simple piece: none, or two
  /// (k = 1), or one cycle through every neighbour region exactly twice (k = 2; the regions
  /// beyond the domain are nodes too, so a surface with boundary closes its loop there).
  bool simpleLink(std::int64_t c, const std::vector<Polygon>& polygons,
                  const std::vector<std::int32_t>& ps) const;

  // Phase 3, crossing_blocks.cpp: blocks of 2^n leaves around a tangency.
  /// When the face lies inside exactly one face of the box of the block (level, lo), on one
  /// of its boundary planes and strictly inside along every other axis: that plane's axis
  /// (`upper`: the block's upper side). Otherwise -1.
  int blockFaceAxis(const FaceRef& face, int level, const std::vector<std::int32_t>& lo,
                    bool& upper) const;

  bool onOneBlockFace(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const;

  /// Whether the face lies inside the block of `level` with lower corner `lo` (not on its
  /// boundary).
  bool inside(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const;

  /// Face (a, upper) of the block (level, lo) leaf face by leaf face: no unproven face inside
  /// it (its crossings on the leaf faces' common edges are proven, so the link sees every
  /// piece of M on it) and each leaf face empty or a graph. Leaves patches_ changed.
  bool subFacesGraph(int level, const std::vector<std::int32_t>& lo,
                     const std::vector<std::int32_t>& members, int a, bool upper);

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
  void mergeBlocks(const std::vector<std::vector<std::int32_t>>& incident);

  /// The blocks for leaf c on a curve of tangency: for each grid plane next to c that holds
  /// every unproven face next to c, the block that straddles the plane and has even lower
  /// corners along the other axes (so that the blocks along the curve tile it face to face).
  std::vector<std::vector<std::int32_t>> latticeBlocks(std::int32_t c) const;

  /// Dissolves the blocks that do not stand (mergeBlocks) until every remaining one does.
  void verifyBlocks(const std::vector<std::vector<std::int32_t>>& incident);

  /// Whether block b stands among the others: every unproven face next to it inside it, or
  /// inside one face of its box with block leaves across, and its link (every block one node)
  /// one cycle.
  bool blockStands(std::size_t b, const std::vector<std::vector<std::int32_t>>& incident) const;

  /// The polygons incident to any of the leaves, once each.
  static std::vector<std::int32_t> blockPolygons(
      const std::vector<std::int32_t>& members,
      const std::vector<std::vector<std::int32_t>>& incident);

  /// Whether the face lies inside exactly one face of the block's box (level, lo) and every
  /// leaf across that face next to it is a leaf of `level` in a block.
  bool sharedBlockFace(const FaceRef& face, int level, const std::vector<std::int32_t>& lo) const;

  /// The lower corners of the blocks of 2^n leaves that hold leaf c, the one centred nearest
  /// its trouble point first, then those that differ from it along more and more axes (at
  /// most kBlockTries).
  std::vector<std::vector<std::int32_t>> blockCandidates(std::int32_t c) const;

  /// The certificate of the block of 2^n leaves of `level` with lower corner `lo`: its leaves
  /// free, one polynomial piece, every unproven face inside it, the crossings on its boundary
  /// one simple piece, and the graph and face graph tests on its box.
  bool tryBlock(int level, const std::vector<std::int32_t>& lo,
                const std::vector<std::vector<std::int32_t>>& incident, bool tentative);

  /// The leaves of a block: every region of it an active leaf of `level` in no other block,
  /// inside one polynomial piece of the input.
  bool blockMembers(int level, const std::vector<std::int32_t>& lo,
                    std::vector<std::int32_t>& members, std::vector<CellKey>& empties) const;

  /// The polygons of the block's boundary with its leaves as one node (members.front());
  /// those inside it drop out. False when a polygon meets the block twice (not a box).
  bool blockLink(const std::vector<std::int32_t>& members,
                 const std::vector<std::vector<std::int32_t>>& incident, std::vector<Polygon>& link,
                 std::vector<std::int32_t>& ps) const;

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

  // Phase 4, crossing_refine.cpp: the refinement loop and the chord error.
  /// Crossings, certificates and refinement until every leaf is certified or at the maximum
  /// level (or the leaf budget is spent). Returns the degenerate crossings of the last pass.
  std::int64_t refineAndCertify();

  /// `--tolerance`: the leaves below the maximum level that are nodes of a mesh polygon whose
  /// simplices have a barycentre farther than the tolerance from its Newton projection onto M
  /// (the analysis's chord error). Each leaf's vertex is taken as the projection of the mean of
  /// its crossings, as the dual complex places it (a block's: of the block's crossings).
  std::vector<std::int32_t> chordLeaves() const;

  /// Whether a simplex of the polygon (its edge, or its triangles split along the shorter
  /// diagonal as addSimplices does) has its barycentre farther than `tolerance` from M.
  bool chordAbove(const Polygon& poly, const std::vector<S>& vertex, const S& tolerance) const;

  /// The topology record from the final tree.
  void record(TopologyRecord& t, std::int64_t degenerate) const;

  // Phase 5, crossing.cpp: the per-leaf state and the dual complex.
  /// Per-leaf arrays follow the tree's growth.
  void grow();

  /// The dual complex of the final tree (docs/crossing.md, steps 3 and 4), on the polygons
  /// that lie inside the domain.
  void buildComplex(ConnectionOutput<S>& out);

  /// The pieces of M in leaf c: for k = 2 the components of the link of its vertex (one edge
  /// per incident polygon, between the polygon's two nodes next to c), one per sheet of M in
  /// the leaf; for k = 1 one. Counts the leaves whose piece is not simple.
  template <class SlotOf>
  std::int32_t pieces(std::size_t c, const std::vector<std::int32_t>& ps,
                      std::vector<std::int32_t>& piece, const SlotOf& slotOf,
                      ConnectionOutput<S>& out) const;

  /// Whether leaf c (or a leaf of its block) touches the domain boundary.
  bool onDomainBoundary(std::int32_t c) const;

  /// The simplices of one mesh polygon: an edge (k = 1), a triangle, or a quad split along its
  /// shorter diagonal.
  void addSimplices(const Polygon& poly, std::int32_t p, const std::vector<std::int32_t>& first,
                    const std::vector<std::int32_t>& piece, ConnectionOutput<S>& out) const;

  // The state of the phases.
  const ConnectionInput<S>& in_;
  const Grid& grid_;
  int n_, k_, m_, maxFaceDepth_;
  Box<S> domain_;
  const GeneralPosition<S> position_;
  GraphTest<S> graphTest_;
  std::vector<Interval<S>> jacobian_;  ///< m x n enclosure for the graph tests
  CellTree tree_;
  std::vector<std::array<int, 2>> fixedAxes_;  ///< the k fixed axes of each kind of m-face
  std::vector<S> level_;                       ///< c of the current attempt
  std::map<CellKey, RootForms> rootForms_;
  std::vector<Bernstein<S>> patches_;  ///< the current leaf's patches
  std::vector<S> margins_;
  std::unordered_map<std::uint64_t, FaceResult<S>> faces_;
  std::vector<Polygon> polygons_;
  std::vector<S> rootPoints_;
  // Per leaf: proven empty (-1 unknown), next to an unproven face, next to an undecided face,
  // graph tests (-1 unknown), and the certificate's failure.
  std::vector<std::int8_t> empty_, bandEmpty_;
  std::vector<std::uint8_t> unproven_, stuck_, singular_;
  std::vector<std::int8_t> graph_, faceGraph_;
  std::vector<Failure> failure_;
  std::vector<S> trouble_;  ///< n per leaf: where its certificate failed (setTrouble)
  std::vector<std::uint8_t> hasTrouble_;
  std::vector<FaceRef> unprovenFaces_;                 ///< recordUnproven
  std::vector<std::vector<std::int32_t>> unprovenOf_;  ///< per leaf: its unproven faces
  std::unordered_map<CellKey, std::vector<std::int32_t>> unprovenOfEmpty_;  ///< per empty cell
  std::vector<std::vector<std::int32_t>> blocks_;  ///< the leaves of certified blocks
  std::vector<std::int32_t> block_;                ///< per leaf: its block, or -1
  /// Per block: its lower corner and level, and its leaves' failures before it (to dissolve
  /// it); a dissolved block has no leaves.
  std::vector<std::vector<std::int32_t>> blockLo_;
  std::vector<int> blockLevel_;
  std::vector<std::vector<CellKey>> blockEmpties_;  ///< its base cells the bounding excluded
  std::vector<std::vector<Failure>> blockSaved_;
  std::int64_t refined_ = 0;
  std::size_t maxLeaves_ = 0;
  bool refining_ = true;  ///< false: certify the base grid only (run's fallback)
  bool budgetSpent_ = false;
};

extern template struct GeneralPosition<double>;
extern template struct GeneralPosition<Mpfr>;

}  // namespace ndc::crossing_detail
