// One solve cut into pieces (split.hpp): the plan, the pieces' outputs read back, and the merge.
#include "pipeline/split.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "framework/io/io.hpp"
#include "framework/mesh/analysis.hpp"
#include "framework/mesh/orientation.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/budget.hpp"
#include "framework/problem/system.hpp"
#include "framework/util/errors.hpp"
#include "framework/util/json.hpp"
#include "pipeline/pipeline.hpp"
#include "strategies/projection/projection.hpp"

namespace ndc {

namespace {

/// The glue tolerance: a millionth of the smallest cell width of the pieces' base grid. Both sides
/// of a shared face put their boundary vertices on M ∩ face from level sets about 1e-8 cell widths
/// apart (docs/crossing.md, "General position"); distinct vertices are at least a cell width of
/// the deepest refinement apart.
double glueTolerance(const SplitPlan& plan) {
  double width = std::numeric_limits<double>::infinity();
  for (const Box<double>& box : plan.boxes)
    for (int j = 0; j < box.dim(); ++j)
      width = std::min(width, std::ldexp(box.width(j), -plan.pieceDepth));
  return 1e-6 * width;
}

/// A piece's summary.json by path.
class PieceSummary {
 public:
  PieceSummary(const std::string& json, const std::string& file) : file_(file) {
    try {
      for (JsonLeaf& leaf : jsonLeaves(json)) leaves_.emplace(leaf.path, std::move(leaf));
    } catch (const std::exception& e) {
      throw InputError(file + ": " + e.what());
    }
  }
  const JsonLeaf& at(const std::string& path) const {
    const auto it = leaves_.find(path);
    if (it == leaves_.end()) throw InputError(file_ + ": no field '" + path + "'");
    return it->second;
  }
  bool has(const std::string& path) const { return leaves_.count(path) > 0; }
  double number(const std::string& path) const {
    const JsonLeaf& leaf = at(path);
    return leaf.kind == JsonKind::number ? std::strtod(leaf.text.c_str(), nullptr) : 0.0;
  }
  std::int64_t integer(const std::string& path) const {
    return static_cast<std::int64_t>(std::llround(number(path)));
  }
  bool boolean(const std::string& path) const { return at(path).text == "true"; }
  std::string text(const std::string& path) const { return at(path).text; }
  /// The numbers of a list field (`path.0`, `path.1`, ..).
  std::vector<double> list(const std::string& path) const {
    std::vector<double> out;
    while (has(path + "." + std::to_string(out.size())))
      out.push_back(number(path + "." + std::to_string(out.size())));
    return out;
  }

 private:
  std::string file_;
  std::unordered_map<std::string, JsonLeaf> leaves_;
};

/// The uncertified leaves of a piece's uncertified.csv (`cell` rows), their levels counted in
/// the whole grid.
void readUncertified(const std::string& csv, int n, int levels, std::vector<UncertifiedCell>& out) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) {
    std::vector<std::string> field;
    std::stringstream row(line);
    for (std::string f; std::getline(row, f, ',');) field.push_back(f);
    // The contract's columns first; the variables' names may follow (aliases of lo and hi).
    if (field.size() < static_cast<std::size_t>(3 + 2 * n) || field[0] != "cell") continue;
    UncertifiedCell cell;
    cell.level = std::atoi(field[1].c_str()) + levels;
    cell.reason = field[2];
    for (int j = 0; j < n; ++j) {
      cell.lo.push_back(std::strtod(field[3 + 2 * j].c_str(), nullptr));
      cell.hi.push_back(std::strtod(field[4 + 2 * j].c_str(), nullptr));
    }
    out.push_back(std::move(cell));
  }
}

/// The counts, times, certificates and diagnostics of the pieces, summed or joined.
void mergeRecords(Summary& s, const SplitPlan& plan, const std::vector<PieceOutput>& pieces) {
  TopologyRecord& t = s.topology;
  t.certified = true;
  t.baseLevel = s.settings.depth;
  t.maxLevel = s.settings.depth;
  t.maxDepth = plan.pieceMaxDepth + plan.levels;
  std::vector<std::string> reasons;
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const PieceSummary j(pieces[p].summaryJson, "piece " + std::to_string(p) + " summary.json");
    s.visited += j.integer("cells.visited");
    s.solution += j.integer("cells.solution");
    s.normal += j.integer("cells.normal");
    s.abnormal += j.integer("cells.abnormal");
    s.failed += j.integer("cells.failed");
    s.ambiguousCells += j.integer("diagnostics.ambiguous_cells");
    s.singularCells += j.integer("diagnostics.singular_cells");
    s.offManifoldVertices += j.integer("diagnostics.off_manifold_vertices");
    PerturbationRecord& q = s.perturbation;
    if (q.level.empty()) q.level = j.list("diagnostics.perturbation.level");
    q.attempts =
        std::max(q.attempts, static_cast<int>(j.integer("diagnostics.perturbation.attempts")));
    q.degenerateCrossings += j.integer("diagnostics.perturbation.degenerate_crossings");
    for (int i = 0; j.has("diagnostics.singular_points." + std::to_string(i) + ".sigma_min"); ++i) {
      const std::string at = "diagnostics.singular_points." + std::to_string(i);
      s.singularPoints.push_back({j.list(at + ".point"), j.number(at + ".sigma_min")});
    }
    if (!j.boolean("topology.certified")) {
      t.certified = false;
      reasons.push_back("piece " + std::to_string(p) + ": " + j.text("topology.reason"));
    }
    t.certifiedCells += j.integer("topology.certified_cells");
    t.refinedCells += j.integer("topology.refined_cells");
    t.uncertifiedCells += j.integer("topology.uncertified_cells");
    t.blockCells += j.integer("topology.block_cells");
    t.facesSolved += j.integer("topology.faces_solved");
    t.maxLevel =
        std::max(t.maxLevel, static_cast<int>(j.integer("topology.max_level")) + plan.levels);
    readUncertified(pieces[p].uncertifiedCsv, s.n, plan.levels, t.uncertified);
    s.tSubdivision += j.number("timing_s.subdivision");
    s.tProjection += j.number("timing_s.projection");
    s.tConnection += j.number("timing_s.connection");
    s.tAnalysis += j.number("timing_s.analysis");
    s.estimatedMemory = std::max(s.estimatedMemory, j.number("budget.estimated_memory_bytes"));
    s.estimatedSeconds += j.number("budget.estimated_time_s");
  }
  // A singular point on a face two pieces share is found by both: keep one.
  std::vector<SingularPoint> points;
  const double tolerance = glueTolerance(plan);
  for (SingularPoint& p : s.singularPoints) {
    const auto same = [&](const SingularPoint& q) {
      for (std::size_t j = 0; j < p.point.size(); ++j)
        if (!(std::abs(p.point[j] - q.point[j]) <= tolerance)) return false;
      return q.point.size() == p.point.size();
    };
    if (std::none_of(points.begin(), points.end(), same)) points.push_back(std::move(p));
  }
  s.singularPoints = std::move(points);
  if (!reasons.empty()) {
    t.reason = std::to_string(reasons.size()) + " of " + std::to_string(pieces.size()) +
               " pieces not certified; " + reasons.front();
  }
}

/// The glued mesh analysed in scalar S as a run's welded mesh is (framework/mesh/analysis.hpp).
template <class S>
MeshStats analyseGlued(const Problem& problem, const StrategyChoices& choices,
                       const GlueResult& glued) {
  Complex<S> complex;
  complex.n = problem.n();
  complex.k = problem.k();
  for (const double x : glued.vertices) complex.vertices.push_back(S(x));
  complex.simplices = glued.simplices;
  complex.vertexCell.assign(complex.vertexCount(), -1);
  const System<S> system(problem);
  const Projection<S> projection = createProjection<S>(choices.projection, system);
  return analyse<S>(complex, system, makeProjector<S>(projection));
}

}  // namespace

SplitPlan planSplit(const Problem& problem, const Settings& settings, int pieces) {
  if (pieces < 1 || pieces > kMaxSplitPieces || !std::has_single_bit(static_cast<unsigned>(pieces)))
    throw UsageError("--split " + std::to_string(pieces) +
                     ": the number of pieces must be a power of two from 1 to " +
                     std::to_string(kMaxSplitPieces));
  if (settings.jitter)
    throw InputError(problem.path +
                     ": --split cannot be used with --jitter: the pieces' grids would not meet");
  if (problem.application || !problem.roots.empty())
    throw InputError(problem.path +
                     ": --split does not take B-spline or application input yet (a piece's "
                     "knot spans and parameters would have to be cut with it)");
  const int n = problem.n();
  SplitPlan plan;
  plan.halvings = std::countr_zero(static_cast<unsigned>(pieces));
  plan.levels = plan.halvings / n;
  const int extra = plan.halvings % n;
  plan.pieceDepth = settings.depth - plan.levels;
  if (plan.pieceDepth < kMinDepth)
    throw UsageError("--split " + std::to_string(pieces) + " needs --depth " +
                     std::to_string(plan.levels + kMinDepth) + " or more for " + std::to_string(n) +
                     " variables (each piece is a box of the depth-" + std::to_string(plan.levels) +
                     " grid)");
  plan.pieceMaxDepth = maxDepthOf(problem, settings) - plan.levels;
  // The boxes: axis j cut into 2^(t + 1) parts for j < e and 2^t otherwise, axis 0 fastest;
  // neighbours compute their shared end by one formula, so it is the same double.
  std::vector<int> parts(n), index(n, 0);
  for (int j = 0; j < n; ++j) parts[j] = 1 << (plan.levels + (j < extra ? 1 : 0));
  const Box<double>& d = problem.domain;
  const auto end = [&](int j, int i) {
    return i == parts[j] ? d.hi[j] : d.lo[j] + (d.hi[j] - d.lo[j]) / parts[j] * i;
  };
  for (int p = 0; p < pieces; ++p) {
    Box<double> box;
    for (int j = 0; j < n; ++j) {
      box.lo.push_back(end(j, index[j]));
      box.hi.push_back(end(j, index[j] + 1));
    }
    plan.boxes.push_back(std::move(box));
    for (int j = 0; j < n && ++index[j] == parts[j]; ++j) index[j] = 0;
  }
  return plan;
}

std::string domainText(const Box<double>& box) {
  std::string text;
  char buffer[64];
  for (int j = 0; j < box.dim(); ++j) {
    std::snprintf(buffer, sizeof buffer, "%s%.17g:%.17g", j ? "," : "", box.lo[j], box.hi[j]);
    text += buffer;
  }
  return text;
}

Box<double> parseDomainText(const std::string& text, int n) {
  const auto fail = [&](const std::string& why) -> Box<double> {
    throw UsageError("--domain '" + text + "': " + why);
  };
  Box<double> box;
  std::stringstream in(text);
  for (std::string pair; std::getline(in, pair, ',');) {
    const std::size_t colon = pair.find(':');
    if (colon == std::string::npos) return fail("expected lo:hi for each variable");
    const std::string lo = pair.substr(0, colon), hi = pair.substr(colon + 1);
    char *endLo = nullptr, *endHi = nullptr;
    const double a = std::strtod(lo.c_str(), &endLo), b = std::strtod(hi.c_str(), &endHi);
    if (lo.empty() || hi.empty() || *endLo || *endHi || !std::isfinite(a) || !std::isfinite(b))
      return fail("'" + pair + "' is not two finite numbers lo:hi");
    if (!(a < b)) return fail("'" + pair + "' is empty (lo must be below hi)");
    box.lo.push_back(a);
    box.hi.push_back(b);
  }
  if (box.dim() != n)
    return fail("expected " + std::to_string(n) + " intervals lo:hi (one per variable), got " +
                std::to_string(box.dim()));
  return box;
}

PieceOutput readPiece(const std::filesystem::path& dir, const Box<double>& box) {
  PieceOutput out;
  const PlyMesh ply = readPly(dir / "mesh.ply");
  out.mesh.box = box;
  for (const std::vector<double>& u : ply.u)
    out.mesh.vertices.insert(out.mesh.vertices.end(), u.begin(), u.end());
  for (const std::vector<int>& s : ply.simplices)
    out.mesh.simplices.insert(out.mesh.simplices.end(), s.begin(), s.end());
  const auto read = [](const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  };
  if (!std::filesystem::exists(dir / "summary.json"))
    throw InputError((dir / "summary.json").string() + ": missing");
  out.summaryJson = read(dir / "summary.json");
  if (std::filesystem::exists(dir / "uncertified.csv"))
    out.uncertifiedCsv = read(dir / "uncertified.csv");
  return out;
}

RunResult mergePieces(const Problem& problem, const Settings& settings, const SplitPlan& plan,
                      const std::vector<PieceOutput>& pieces, double wallSeconds) {
  RunResult result;
  result.n = problem.n();
  result.k = problem.k();
  Summary& s = result.summary;
  const StrategyChoices choices = parseStrategies(settings);
  describeRun(s, problem, settings, choices,
              settings.scalar == "double" ? 53u : settings.precisionBits);
  mergeRecords(s, plan, pieces);
  s.memoryBudget = static_cast<double>(settings.maxMemoryBytes ? settings.maxMemoryBytes
                                                               : defaultMemoryBudget());
  // Glue, then analyse the glued mesh as a run analyses its welded mesh.
  const auto start = std::chrono::steady_clock::now();
  std::vector<MeshPiece> meshes;
  for (const PieceOutput& piece : pieces) meshes.push_back(piece.mesh);
  const GlueResult glued = gluePieces(result.n, result.k, meshes, glueTolerance(plan));
  s.mesh = settings.scalar == "double" ? analyseGlued<double>(problem, choices, glued) : [&] {
    const unsigned bits = mpfrPrecision();
    setMpfrPrecision(settings.precisionBits);
    MeshStats m = analyseGlued<Mpfr>(problem, choices, glued);
    setMpfrPrecision(bits);
    return m;
  }();
  result.vertices = glued.vertices;
  result.simplices = glued.simplices;
  s.mesh.orientable = orientSimplices(result.k, result.simplices);
  s.tAnalysis += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (glued.unmatched > 0 && s.topology.certified) {
    s.topology.certified = false;
    s.topology.reason = "the pieces do not meet on their shared faces: " + glued.reason;
  } else if (glued.unmatched > 0) {
    s.topology.reason += "; the pieces do not meet on their shared faces: " + glued.reason;
  }
  checkCertificate(s);
  s.tTotal =
      wallSeconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace ndc
