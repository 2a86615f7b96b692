/// \file summary.hpp
/// Run settings and the run summary: the `summary.json` contract (docs/contracts.md 4.3).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ndc {

/// The strategies and parameters of one run (`settings` in summary.json).
struct Settings {
  int depth = 6;
  std::string bounding = "linearized";
  std::string subdivision = "binary";
  std::string scalar = "double";
  unsigned precisionBits = 53;
  std::string projection = "newton";
  std::string classification = "paper";
  std::string connection = "crossing";
  std::optional<std::uint64_t> jitter;
  /// Memory the run may use, in bytes (`--max-memory`); 0: ndc::defaultMemoryBudget().
  std::uint64_t maxMemoryBytes = 0;
  /// Wall-clock limit of the whole solve in seconds (`--timeout`; the CLI enforces it); unset:
  /// none.
  std::optional<double> timeoutSeconds;
  /// The deepest level adaptive refinement may reach (`--max-depth`); 0: the default,
  /// ndc::defaultMaxDepth (docs/certificate.md).
  int maxDepth = 0;
  /// Chord error the mesh should stay below (`--tolerance`): the crossing connection refines
  /// the leaves whose mesh pieces are farther from M (docs/certificate.md); 0: none.
  double tolerance = 0;
  /// Worker threads of the run (`--threads`); 0: every hardware thread. The outputs do not
  /// depend on it (docs/performance.md, "Threads"); summary.json records the count used.
  int threads = 0;
};

/// Mesh statistics after welding identical vertices (`mesh` in summary.json).
struct MeshStats {
  std::int64_t vertices = 0, edges = 0, triangles = 0, components = 0;
  std::int64_t boundaryEdges = 0, nonmanifoldEdges = 0, eulerCharacteristic = 0;
  std::int64_t openEnds = 0, branchVertices = 0;
  /// k = 2: connected components of the boundary edges (each a closed loop on a manifold mesh
  /// with boundary, e.g. 2 for a cylinder cut by the domain); 0 for other k.
  std::int64_t boundaryComponents = 0;
  double maxResidual = 0;    ///< max over vertices and equations of |F_i(v)|
  double maxChordError = 0;  ///< max distance of segment midpoints / triangle centroids to M
  /// Midpoints / centroids whose projection did not converge (left out of maxChordError).
  std::int64_t chordFailures = 0;
  /// Whether every connected component could be oriented consistently; the simplices of the
  /// output are oriented so (framework/mesh/orientation.hpp).
  bool orientable = true;
  /// Betti numbers b_0 .. b_k over Q (ranks modulo 2^31 - 1) and over Z/2
  /// (framework/mesh/homology.hpp); empty until the analysis fills them.
  std::vector<std::int64_t> betti, bettiZ2;
  /// (k-1)-faces of exactly one k-simplex (k = 1: open ends, k = 2: boundary edges) and of
  /// three or more (k = 1: branch vertices, k = 2: non-manifold edges), for every k.
  std::int64_t boundaryFacets = 0, nonmanifoldFacets = 0;
};

/// A point of M where the Jacobian of the constraints loses rank (`diagnostics.singular_points`).
struct SingularPoint {
  std::vector<double> point;  ///< n coordinates
  double sigmaMin = 0;        ///< smallest singular value of the m x n Jacobian there
};

/// One key of the problem's `[expect]` compared with the mesh (`expect` in summary.json).
struct ExpectCheck {
  std::string key;  ///< e.g. "components", "euler_characteristic", "boundary_edges"
  long wanted = 0;
  long got = 0;
  bool ok = false;
  /// Why the key could not be compared (not a mesh statistic, or genus of a mesh that is not
  /// one closed surface); empty when it was. A key not compared has `ok` false and no `got`.
  std::string notComparable;
  /// A key whose value is a list (`betti`, `betti_z2`): `wanted` and `got` are unused and the
  /// lists are these.
  bool isList = false;
  std::vector<long> wantedList, gotList;
};

/// How the crossing connection put M in general position with respect to the grid
/// (`diagnostics.perturbation` in summary.json; see docs/crossing.md).
struct PerturbationRecord {
  /// The level c of the perturbed system F = c whose crossings decide the dual cells (one
  /// value per equation); empty when the connection does not perturb (k = n - 1, or another
  /// connection).
  std::vector<double> level;
  int attempts = 0;  ///< levels tried until no crossing was within rounding of a grid face
  /// Crossings still within rounding of the boundary of their face after the last attempt
  /// (0 when general position was verified).
  std::int64_t degenerateCrossings = 0;
};

/// A cell left uncertified at the maximum depth (`uncertified.csv`).
struct UncertifiedCell {
  std::vector<double> lo, hi;  ///< its closed box
  int level = 0;               ///< its level in the 2^n-tree
  std::string reason;          ///< which part of the certificate failed (docs/certificate.md)
};

/// The topology certificate of a run (`topology` in summary.json; docs/certificate.md).
struct TopologyRecord {
  /// True only when every cell of the final 2^n-tree is certified and every crossing proven:
  /// then the mesh is a closed (or bounded) manifold with the topology of M.
  bool certified = false;
  std::string reason;  ///< why not (empty when certified)
  /// Leaves of the final tree that hold a certified piece of M (or are proven empty), that
  /// were refined on the way, and that stay uncertified at the maximum depth.
  std::int64_t certifiedCells = 0, refinedCells = 0, uncertifiedCells = 0;
  /// Certified leaves that are certified together, in blocks of 2^n leaves around a point
  /// where M touches a grid plane (docs/certificate.md, "Blocks"); counted in certifiedCells.
  std::int64_t blockCells = 0;
  /// Minimal m-faces solved for crossings, over every round of refinement and every attempt
  /// (a measure of the connection's work that does not depend on the machine).
  std::int64_t facesSolved = 0;
  int baseLevel = 0;  ///< `--depth`
  int maxLevel = 0;   ///< the deepest level a leaf reached
  int maxDepth = 0;   ///< the limit of refinement (`--max-depth`)
  std::vector<UncertifiedCell> uncertified;
};

/// Everything summary.json holds.
struct Summary {
  std::string problem;
  int n = 0, k = 0;
  /// The problem's variable names, one per coordinate (an application's parameter names);
  /// empty where a run has none, and then the outputs name the coordinates `u0 ..`
  /// (`variables` in summary.json, docs/contracts.md 4.5).
  std::vector<std::string> variables;
  Settings settings;
  /// Per strategy family, in pipeline order: the parameter values the run used, as a JSON
  /// object (`settings.parameters` in summary.json; `{}` for a model without parameters).
  std::vector<std::pair<std::string, std::string>> parameters;
  std::int64_t visited = 0, solution = 0, normal = 0, abnormal = 0, failed = 0;
  MeshStats mesh;
  std::int64_t ambiguousCells = 0, singularCells = 0;
  /// Dual vertices that Newton could not bring onto M (written at their crossing mean).
  std::int64_t offManifoldVertices = 0;
  PerturbationRecord perturbation;
  /// The topology certificate and the adaptive refinement behind it.
  TopologyRecord topology;
  /// Located singular points of M (`diagnostics.singular_points`, `singular.csv`).
  std::vector<SingularPoint> singularPoints;
  /// The comparison with `[expect]`; empty when the problem has none.
  std::vector<ExpectCheck> expect;
  /// Application problems only (empty name otherwise): the application, and how many mesh
  /// vertices have an image denominator too close to 0 (e.g. the bisector determinant).
  std::string application;
  std::string singularName;
  std::int64_t imageSingularVertices = 0;
  double tSubdivision = 0, tProjection = 0, tConnection = 0, tAnalysis = 0, tTotal = 0;
  /// The memory budget of the run in bytes (`budget.max_memory_bytes`), and the memory the run
  /// was estimated to need before the projection (`budget.estimated_memory_bytes`).
  double memoryBudget = 0, estimatedMemory = 0;
  /// The time the run was estimated to take after the subdivision (`budget.estimated_time_s`;
  /// docs/input-limits.md, "Time").
  double estimatedSeconds = 0;
};

/// Whether the run proved that M does not meet the domain: the subdivision excluded every cell
/// by its bounds, so no solution cell is left (`diagnostics.empty_zero_set`).
inline bool emptyZeroSet(const Summary& s) { return s.solution == 0; }

/// summary.json text (schema "ndcontour.summary/1"), field names exactly as docs/contracts.md 4.3.
std::string toJson(const Summary& summary);

}  // namespace ndc
