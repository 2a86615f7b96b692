/// \file summary_schema.hpp
/// The one table of the summary.json fields (docs/contracts.md 4.3 and 4.5): each field's path,
/// JSON type, one line of documentation, where it sits in the experiment CSV, and how its value is
/// taken from a Summary. Everything that names the fields reads them from here: the writer
/// (ndc::toJson walks the table in order), the experiment runner (its summary columns,
/// kExperimentSummaryColumns), the report (the columns it reads are checked against it when it is
/// compiled) and a test that compares the table with the examples of docs/contracts.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "framework/problem/summary.hpp"

namespace ndc {

/// The JSON type of a summary field.
enum class SummaryType {
  object,         ///< an object; its fields are the rows `PATH.NAME` that follow
  list,           ///< an array of objects, one per element; the element is the row `PATH[]`
  map,            ///< an object whose keys come from the run; the value of each is the row `PATH.*`
  string,         ///< a string
  integer,        ///< an integer
  number,         ///< a number (`%.17g`; null when not finite)
  boolean,        ///< true or false
  numberList,     ///< an array of numbers
  integerList,    ///< an array of integers
  integerOrList,  ///< an integer, or an array of integers (the list keys of `expect`)
  stringList,     ///< an array of strings
  json            ///< JSON text written as it is (a strategy's parameters)
};

/// The field is left out of the summary (an empty `expect`, `application` without an application
/// problem, `not_comparable` of a compared key).
struct SummaryAbsent {};

/// JSON text written as it is.
struct SummaryJson {
  std::string text;  ///< the JSON text
};

/// The keys of a list's (empty strings, one per element) or a map's elements.
struct SummaryKeys {
  std::vector<std::string> keys;  ///< one per element, in order
};

/// The value of one field in one run, as the writer writes it: null, absent, a boolean, an
/// integer, a number, a string, a list of numbers or of strings, JSON text, or the elements of a
/// container.
using SummaryValue =
    std::variant<std::nullptr_t, SummaryAbsent, bool, std::int64_t, std::uint64_t, double,
                 std::string, std::vector<double>, std::vector<std::string>, SummaryJson,
                 SummaryKeys, std::vector<std::int64_t>>;

/// Where a field starts in the text of summary.json.
enum class SummaryLayout {
  inline_,  ///< after its predecessor on the same line (top-level fields: each on its own line)
  newLine   ///< on a line of its own, indented two spaces per level
};

/// One field of summary.json.
struct SummaryField {
  /// Dotted path from the top, e.g. `mesh.vertices`; `[]` is an element of a list, `*` any key of
  /// a map (`expect.*.wanted`).
  std::string_view path;
  SummaryType type;      ///< its JSON type
  bool nullable;         ///< whether it may be null
  bool extension;        ///< false: docs/contracts.md 4.3; true: an extension of 4.5
  std::string_view doc;  ///< what it holds, one line
  int csvColumn;         ///< its place (1, 2, ...) among the experiment CSV's summary columns;
                         ///< 0: not one of them
  SummaryLayout layout;  ///< where it starts in the text
  /// Its value in a run; `element` is the index of the enclosing list's or map's element.
  /// nullptr for an object that is always present, and for a mesh statistic (meshStat).
  SummaryValue (*value)(const Summary& s, std::size_t element);
  /// A mesh statistic's member of MeshStats (its value is `s.mesh.*meshStat`; the runner reads
  /// these back to compare a run with the problem's `[expect]`); nullptr for other fields.
  std::int64_t MeshStats::*meshStat = nullptr;
};

/// Short names for the table below.
namespace summary_schema {

using T = SummaryType;                                      ///< a field's type
constexpr SummaryLayout kInline = SummaryLayout::inline_;   ///< after its predecessor
constexpr SummaryLayout kNewLine = SummaryLayout::newLine;  ///< on a line of its own
using Value = SummaryValue;                                 ///< a field's value
using S = const Summary&;                                   ///< the summary a value is taken from
using I = std::size_t;                                      ///< the element of a list or map

/// The value of a string field that is null when empty.
inline Value orNull(const std::string& s) { return s.empty() ? Value(nullptr) : Value(s); }

/// The value of an `expect` key's `wanted` or `got`: an integer, or a list for a list key.
inline Value expectValue(const ExpectCheck& c, long value, const std::vector<long>& list) {
  if (!c.isList) return std::int64_t{value};
  return std::vector<std::int64_t>(list.begin(), list.end());
}

// clang-format off
/// Every field of summary.json in the order the writer writes them (docs/contracts.md 4.3, 4.5).
inline constexpr SummaryField kSummaryFields[] = {
    {"schema", T::string, false, false, "the schema of the file, `ndcontour.summary/1`", 0, kInline,
     [](S, I) -> Value { return std::string("ndcontour.summary/1"); }},
    {"problem", T::string, false, false, "the problem's name", 0, kInline,
     [](S s, I) -> Value { return s.problem; }},
    {"n", T::integer, false, false, "the number of variables (the dimension of the ambient space)",
     0, kInline, [](S s, I) -> Value { return std::int64_t{s.n}; }},
    {"k", T::integer, false, false, "the dimension of M: 1 curve, 2 surface", 0, kInline,
     [](S s, I) -> Value { return std::int64_t{s.k}; }},
    {"variables", T::stringList, false, true,
     "the problem's variable names, one per coordinate; absent where the run has none", 0,
     kInline, [](S s, I) -> Value {
       return s.variables.empty() ? Value(SummaryAbsent{}) : Value(s.variables); }},
    // settings
    {"settings", T::object, false, false, "the strategies and parameters of the run", 0, kInline,
     nullptr},
    {"settings.depth", T::integer, false, false, "the subdivision depth (`--depth`)", 0, kInline,
     [](S s, I) -> Value { return std::int64_t{s.settings.depth}; }},
    {"settings.bounding", T::string, false, false, "the bounding model's name", 0, kInline,
     [](S s, I) -> Value { return s.settings.bounding; }},
    {"settings.subdivision", T::string, false, false, "the subdivision model's name", 0, kInline,
     [](S s, I) -> Value { return s.settings.subdivision; }},
    {"settings.scalar", T::string, false, false, "the scalar type: `double` or `mpfr`", 0, kInline,
     [](S s, I) -> Value { return s.settings.scalar; }},
    {"settings.precision_bits", T::integer, false, false, "the scalar's precision in bits", 0,
     kInline, [](S s, I) -> Value { return std::int64_t{s.settings.precisionBits}; }},
    {"settings.projection", T::string, false, false, "the projection model's name", 0, kInline,
     [](S s, I) -> Value { return s.settings.projection; }},
    {"settings.classification", T::string, false, false, "the classification model's name", 0,
     kInline, [](S s, I) -> Value { return s.settings.classification; }},
    {"settings.connection", T::string, false, false, "the connection model's name", 0, kInline,
     [](S s, I) -> Value { return s.settings.connection; }},
    {"settings.jitter", T::integer, true, false,
     "the seed of the domain's jitter (`--jitter`); null: none", 0, kInline, [](S s, I) -> Value {
       return s.settings.jitter ? Value(*s.settings.jitter) : Value(nullptr); }},
    {"settings.max_depth", T::integer, false, true, "the refinement limit (`--max-depth`)", 0,
     kInline, [](S s, I) -> Value { return std::int64_t{s.topology.maxDepth}; }},
    {"settings.tolerance", T::number, true, true,
     "the chord error asked for with `--tolerance`; null without it", 0, kInline,
     [](S s, I) -> Value {
       return s.settings.tolerance > 0 ? Value(s.settings.tolerance) : Value(nullptr); }},
    {"settings.threads", T::integer, false, true, "the worker threads the run used", 0, kInline,
     [](S s, I) -> Value { return std::int64_t{s.settings.threads}; }},
    {"settings.parameters", T::map, false, true,
     "per strategy family, every parameter value the run used", 0, kInline,
     [](S s, I) -> Value {
       SummaryKeys k;
       for (const auto& p : s.parameters) k.keys.push_back(p.first);
       return k; }},
    {"settings.parameters.*", T::json, false, true, "a family's parameters as a JSON object", 0,
     kInline, [](S s, I i) -> Value { return SummaryJson{s.parameters[i].second}; }},
    // cells
    {"cells", T::object, false, false, "the cells of the subdivision", 0, kInline, nullptr},
    {"cells.visited", T::integer, false, false, "boxes the subdivision bounded", 1, kInline,
     [](S s, I) -> Value { return s.visited; }},
    {"cells.solution", T::integer, false, false, "final-depth boxes kept", 2, kInline,
     [](S s, I) -> Value { return s.solution; }},
    {"cells.normal", T::integer, false, false, "solution cells classified normal", 3, kInline,
     [](S s, I) -> Value { return s.normal; }},
    {"cells.abnormal", T::integer, false, false, "solution cells classified abnormal", 4, kInline,
     [](S s, I) -> Value { return s.abnormal; }},
    {"cells.failed", T::integer, false, false, "solution cells whose projection failed", 5,
     kInline, [](S s, I) -> Value { return s.failed; }},
    // mesh
    {"mesh", T::object, false, false, "mesh statistics after welding identical vertices", 0,
     kInline, nullptr},
    {"mesh.vertices", T::integer, false, false, "vertices", 6, kInline,
     nullptr, &MeshStats::vertices},
    {"mesh.edges", T::integer, false, false,
     "segments (k = 1) or distinct triangle edges (k = 2)", 7, kInline,
     nullptr, &MeshStats::edges},
    {"mesh.triangles", T::integer, false, false, "triangles (k = 2)", 8, kInline,
     nullptr, &MeshStats::triangles},
    {"mesh.components", T::integer, false, false, "connected components", 9, kInline,
     nullptr, &MeshStats::components},
    {"mesh.boundary_edges", T::integer, false, false, "edges of exactly one triangle", 10, kInline,
     nullptr, &MeshStats::boundaryEdges},
    {"mesh.boundary_components", T::integer, false, true,
     "k = 2: the closed loops of boundary edges", 28, kInline,
     nullptr, &MeshStats::boundaryComponents},
    {"mesh.nonmanifold_edges", T::integer, false, false, "edges of three or more triangles", 11,
     kInline, nullptr, &MeshStats::nonmanifoldEdges},
    {"mesh.euler_characteristic", T::integer, false, false, "V - E + T (k = 2), V - E (k = 1)", 12,
     kInline, nullptr, &MeshStats::eulerCharacteristic},
    {"mesh.open_ends", T::integer, false, false, "vertices of degree 1 (k = 1)", 13, kInline,
     nullptr, &MeshStats::openEnds},
    {"mesh.branch_vertices", T::integer, false, false, "vertices of degree 3 or more (k = 1)", 14,
     kInline, nullptr, &MeshStats::branchVertices},
    {"mesh.orientable", T::boolean, false, true,
     "whether every component could be oriented consistently", 0, kInline,
     [](S s, I) -> Value { return s.mesh.orientable; }},
    {"mesh.betti", T::integerList, false, true,
     "Betti numbers b_0 .. b_k over Q (ranks modulo 2^31 - 1)", 0, kInline,
     [](S s, I) -> Value { return s.mesh.betti; }},
    {"mesh.betti_z2", T::integerList, false, true, "Betti numbers b_0 .. b_k over Z/2", 0,
     kInline, [](S s, I) -> Value { return s.mesh.bettiZ2; }},
    {"mesh.boundary_facets", T::integer, false, true,
     "(k-1)-faces of exactly one k-simplex (every k)", 42, kInline,
     nullptr, &MeshStats::boundaryFacets},
    {"mesh.nonmanifold_facets", T::integer, false, true,
     "(k-1)-faces of three or more k-simplices (every k)", 43, kInline,
     nullptr, &MeshStats::nonmanifoldFacets},
    // accuracy
    {"accuracy", T::object, false, false, "how close the mesh is to M", 0, kInline, nullptr},
    {"accuracy.max_residual", T::number, false, false,
     "max over vertices and equations of |F_i(v)|", 15, kInline,
     [](S s, I) -> Value { return s.mesh.maxResidual; }},
    {"accuracy.max_chord_error", T::number, false, false,
     "max distance of segment midpoints / triangle centroids to M", 16, kInline,
     [](S s, I) -> Value { return s.mesh.maxChordError; }},
    // diagnostics
    {"diagnostics", T::object, false, false, "what the run noticed on the way", 0, kInline,
     nullptr},
    {"diagnostics.ambiguous_cells", T::integer, false, false,
     "cells the connection found ambiguous", 17, kInline,
     [](S s, I) -> Value { return s.ambiguousCells; }},
    {"diagnostics.singular_cells", T::integer, false, false,
     "cells where the Jacobian may lose rank", 18, kInline,
     [](S s, I) -> Value { return s.singularCells; }},
    {"diagnostics.chord_failures", T::integer, false, true,
     "simplices whose centre did not project onto M", 19, kInline,
     [](S s, I) -> Value { return s.mesh.chordFailures; }},
    {"diagnostics.off_manifold_vertices", T::integer, false, true,
     "dual vertices whose projection failed", 25, kInline,
     [](S s, I) -> Value { return s.offManifoldVertices; }},
    {"diagnostics.empty_zero_set", T::boolean, false, true,
     "true when the run proved that M does not meet the domain", 0, kInline,
     [](S s, I) -> Value { return emptyZeroSet(s); }},
    {"diagnostics.singular_points", T::list, false, true,
     "where the Jacobian loses rank on M, located to the cell size", 0, kNewLine,
     [](S s, I) -> Value {
       return SummaryKeys{std::vector<std::string>(s.singularPoints.size())}; }},
    {"diagnostics.singular_points[]", T::object, false, true, "one singular point", 0, kInline,
     nullptr},
    {"diagnostics.singular_points[].point", T::numberList, false, true, "its n coordinates", 0,
     kInline, [](S s, I i) -> Value { return s.singularPoints[i].point; }},
    {"diagnostics.singular_points[].sigma_min", T::number, false, true,
     "the smallest singular value of the Jacobian there", 0, kInline,
     [](S s, I i) -> Value { return s.singularPoints[i].sigmaMin; }},
    {"diagnostics.perturbation", T::object, false, true,
     "the level offset of the crossing connection (docs/crossing.md)", 0, kNewLine, nullptr},
    {"diagnostics.perturbation.level", T::numberList, false, true,
     "the level c of the perturbed system F = c, one per equation", 0, kInline,
     [](S s, I) -> Value { return s.perturbation.level; }},
    {"diagnostics.perturbation.attempts", T::integer, false, true, "levels tried", 26, kInline,
     [](S s, I) -> Value { return std::int64_t{s.perturbation.attempts}; }},
    {"diagnostics.perturbation.degenerate_crossings", T::integer, false, true,
     "crossings still within rounding of their face's boundary", 27, kInline,
     [](S s, I) -> Value { return s.perturbation.degenerateCrossings; }},
    // topology
    {"topology", T::object, false, true, "the topology certificate (docs/certificate.md)", 0,
     kInline, nullptr},
    {"topology.certified", T::boolean, false, true,
     "true only when every cell is certified and every crossing proven", 0, kInline,
     [](S s, I) -> Value { return s.topology.certified; }},
    {"topology.reason", T::string, true, true, "why not (null when certified)", 36, kInline,
     [](S s, I) -> Value { return orNull(s.topology.reason); }},
    {"topology.certified_cells", T::integer, false, true,
     "leaves that hold a certified piece of M or are proven empty", 33, kInline,
     [](S s, I) -> Value { return s.topology.certifiedCells; }},
    {"topology.refined_cells", T::integer, false, true, "leaves refined on the way", 37, kInline,
     [](S s, I) -> Value { return s.topology.refinedCells; }},
    {"topology.uncertified_cells", T::integer, false, true,
     "leaves uncertified at the maximum depth", 38, kInline,
     [](S s, I) -> Value { return s.topology.uncertifiedCells; }},
    {"topology.block_cells", T::integer, false, true,
     "certified leaves certified together in blocks of 2^n", 39, kInline,
     [](S s, I) -> Value { return s.topology.blockCells; }},
    {"topology.faces_solved", T::integer, false, true,
     "minimal m-faces solved for crossings, over every round of refinement", 41, kInline,
     [](S s, I) -> Value { return s.topology.facesSolved; }},
    {"topology.base_level", T::integer, false, true, "`--depth`", 32, kInline,
     [](S s, I) -> Value { return std::int64_t{s.topology.baseLevel}; }},
    {"topology.max_level", T::integer, false, true, "the deepest level a leaf reached", 35,
     kInline, [](S s, I) -> Value { return std::int64_t{s.topology.maxLevel}; }},
    {"topology.max_depth", T::integer, false, true, "the limit of refinement (`--max-depth`)", 34,
     kInline, [](S s, I) -> Value { return std::int64_t{s.topology.maxDepth}; }},
    // timing_s
    {"timing_s", T::object, false, false, "wall-clock seconds per stage", 0, kInline, nullptr},
    {"timing_s.subdivision", T::number, false, false, "the subdivision", 20, kInline,
     [](S s, I) -> Value { return s.tSubdivision; }},
    {"timing_s.projection", T::number, false, false, "the projection", 21, kInline,
     [](S s, I) -> Value { return s.tProjection; }},
    {"timing_s.connection", T::number, false, false, "the connection", 22, kInline,
     [](S s, I) -> Value { return s.tConnection; }},
    {"timing_s.analysis", T::number, false, false, "the analysis of the mesh", 23, kInline,
     [](S s, I) -> Value { return s.tAnalysis; }},
    {"timing_s.total", T::number, false, false, "the whole run", 24, kInline,
     [](S s, I) -> Value { return s.tTotal; }},
    // budget
    {"budget", T::object, false, true, "the run's budgets (docs/input-limits.md)", 0, kInline,
     nullptr},
    {"budget.max_memory_bytes", T::number, false, true, "the memory budget", 29, kInline,
     [](S s, I) -> Value { return s.memoryBudget; }},
    {"budget.estimated_memory_bytes", T::number, false, true,
     "the memory the run was estimated to need", 30, kInline,
     [](S s, I) -> Value { return s.estimatedMemory; }},
    {"budget.timeout_s", T::number, true, true, "the timeout (`--timeout`); null: none", 31,
     kInline, [](S s, I) -> Value {
       return s.settings.timeoutSeconds ? Value(*s.settings.timeoutSeconds) : Value(nullptr); }},
    {"budget.estimated_time_s", T::number, false, true,
     "the time the run was estimated to take once its cells were counted", 40, kInline,
     [](S s, I) -> Value { return s.estimatedSeconds; }},
    // expect
    {"expect", T::map, false, true,
     "the problem's `[expect]` compared with the mesh; absent without one", 0, kInline,
     [](S s, I) -> Value {
       if (s.expect.empty()) return SummaryAbsent{};
       SummaryKeys k;
       for (const ExpectCheck& c : s.expect) k.keys.push_back(c.key);
       return k; }},
    {"expect.*", T::object, false, true, "one key of `[expect]`", 0, kInline, nullptr},
    {"expect.*.wanted", T::integerOrList, false, true,
     "the value the problem file expects (a list for `betti`, `betti_z2`)", 0, kInline,
     [](S s, I i) -> Value {
       const ExpectCheck& c = s.expect[i];
       return expectValue(c, c.wanted, c.wantedList); }},
    {"expect.*.got", T::integerOrList, true, true, "the mesh's value; null when not comparable",
     0, kInline, [](S s, I i) -> Value {
       const ExpectCheck& c = s.expect[i];
       return c.notComparable.empty() ? expectValue(c, c.got, c.gotList) : Value(nullptr); }},
    {"expect.*.ok", T::boolean, true, true, "whether they agree; null when not comparable", 0,
     kInline, [](S s, I i) -> Value {
       const ExpectCheck& c = s.expect[i];
       return c.notComparable.empty() ? Value(c.ok) : Value(nullptr); }},
    {"expect.*.not_comparable", T::string, false, true,
     "why the key could not be compared; absent when it was", 0, kInline,
     [](S s, I i) -> Value {
       const ExpectCheck& c = s.expect[i];
       return c.notComparable.empty() ? Value(SummaryAbsent{}) : Value(c.notComparable); }},
    // application
    {"application", T::object, false, true, "application problems only: the application", 0,
     kInline, [](S s, I) -> Value {
       return s.application.empty() ? Value(SummaryAbsent{}) : Value(nullptr); }},
    {"application.name", T::string, false, true, "the application's name", 0, kInline,
     [](S s, I) -> Value { return s.application; }},
    {"application.image_singular_vertices", T::integer, false, true,
     "mesh vertices whose image denominator is too close to 0", 0, kInline,
     [](S s, I) -> Value { return s.imageSingularVertices; }},
    {"application.singular_meaning", T::string, false, true,
     "what such a vertex means for the application", 0, kInline,
     [](S s, I) -> Value { return s.singularName; }},
};
// clang-format on

}  // namespace summary_schema

using summary_schema::kSummaryFields;

/// The field of a concrete dotted path of a summary (`diagnostics.singular_points.0.sigma_min`,
/// `expect.components.ok`, `settings.parameters.connection.max_face_depth`): list indices match
/// `[]`, map keys `*`, and anything below a list of numbers or strings or JSON text is that field.
/// nullptr when no field matches.
const SummaryField* summaryFieldOf(std::string_view path);

}  // namespace ndc
