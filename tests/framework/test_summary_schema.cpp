// The summary.json schema table (framework/io/summary_schema.hpp): the writer's bytes, the
// writer follows the table, and docs/contracts.md shows exactly the table's fields.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/runner/columns.hpp"
#include "framework/io/summary_schema.hpp"
#include "framework/problem/summary.hpp"
#include "framework/util/json.hpp"

namespace {

/// A summary with every field set and every optional part present; `comparable`: whether the
/// second `[expect]` key could be compared.
ndc::Summary fullSummary(bool comparable) {
  ndc::Summary s;
  s.problem = "full \"quoted\" problem";
  s.n = 4;
  s.k = 2;
  s.variables = {"x", "y", "z", "w"};
  s.settings.depth = 7;
  s.settings.bounding = "bernstein";
  s.settings.subdivision = "uniform";
  s.settings.scalar = "mpfr";
  s.settings.precisionBits = 128;
  s.settings.projection = "newton";
  s.settings.classification = "paper";
  s.settings.connection = "paper";
  s.settings.jitter = 18446744073709551615ull;
  s.settings.timeoutSeconds = 12.5;
  s.settings.tolerance = 1e-3;
  s.settings.threads = 3;
  s.parameters = {{"bounding", "{}"}, {"connection", "{\"max_face_depth\": 20}"}};
  s.visited = 101, s.solution = 55, s.normal = 40, s.abnormal = 10, s.failed = 5;
  s.mesh.vertices = 12, s.mesh.edges = 30, s.mesh.triangles = 20, s.mesh.components = 2;
  s.mesh.boundaryEdges = 3, s.mesh.nonmanifoldEdges = 4, s.mesh.eulerCharacteristic = -2;
  s.mesh.openEnds = 5, s.mesh.branchVertices = 6, s.mesh.boundaryComponents = 7;
  s.mesh.maxResidual = 1.25e-15, s.mesh.maxChordError = 0.1, s.mesh.chordFailures = 8;
  s.mesh.orientable = false;
  s.mesh.betti = {2, 1, 0}, s.mesh.bettiZ2 = {2, 2, 1};
  s.mesh.boundaryFacets = 3, s.mesh.nonmanifoldFacets = 4;
  s.ambiguousCells = 9, s.singularCells = 10, s.offManifoldVertices = 11;
  s.perturbation = {{1e-7, -2e-7}, 3, 4};
  s.topology.certified = false;
  s.topology.reason = "crossing";
  s.topology.certifiedCells = 13, s.topology.refinedCells = 14, s.topology.uncertifiedCells = 15;
  s.topology.blockCells = 16, s.topology.facesSolved = 17, s.topology.baseLevel = 7,
  s.topology.maxLevel = 9;
  s.topology.maxDepth = 16;
  s.singularPoints = {{{0.5, -0.25, 0, 1}, 1e-9}, {{1, 2, 3, 4}, 0.125}};
  ndc::ExpectCheck a;
  a.key = "components", a.wanted = 2, a.got = 2, a.ok = true;
  ndc::ExpectCheck b;
  b.key = "genus", b.wanted = 1, b.got = 0, b.ok = false;
  if (!comparable) b.notComparable = "not one closed surface";
  s.expect = {a, b};
  s.application = "bisector";
  s.singularName = "the bisector's determinant";
  s.imageSingularVertices = 17;
  s.tSubdivision = 0.5, s.tProjection = 0.25, s.tConnection = 1.0 / 3, s.tAnalysis = 0;
  s.tTotal = std::nan("");
  s.memoryBudget = 1073741824, s.estimatedMemory = 123456.5, s.estimatedSeconds = 2.75;
  return s;
}

/// Whether a field holds a value of its own (not an object, list or map of others).
bool isLeaf(const ndc::SummaryField& f) {
  return f.type != ndc::SummaryType::object && f.type != ndc::SummaryType::list &&
         f.type != ndc::SummaryType::map;
}

/// The JSON example of section `heading` of docs/contracts.md (its first ```json block).
std::string contractsExample(const std::string& heading) {
  std::ifstream in(std::string(NDC_SOURCE_DIR) + "/docs/contracts.md");
  std::ostringstream read;
  read << in.rdbuf();
  const std::string text = read.str();
  const std::size_t section = text.find("\n" + heading + "\n");
  REQUIRE(section != std::string::npos);
  const std::size_t open = text.find("```json\n", section);
  REQUIRE(open != std::string::npos);
  const std::size_t close = text.find("```", open + 8);
  REQUIRE(close != std::string::npos);
  return text.substr(open + 8, close - open - 8);
}

}  // namespace

TEST_CASE("summary schema: the bytes of summary.json", "[summary][experiment]") {
  // Captured from the writer before the table drove it.
  CHECK(ndc::toJson(fullSummary(true)) == R"json({
  "schema": "ndcontour.summary/1",
  "problem": "full \"quoted\" problem",
  "n": 4,
  "k": 2,
  "variables": ["x", "y", "z", "w"],
  "settings": {"depth": 7, "bounding": "bernstein", "subdivision": "uniform", "scalar": "mpfr", "precision_bits": 128, "projection": "newton", "classification": "paper", "connection": "paper", "jitter": 18446744073709551615, "max_depth": 16, "tolerance": 0.001, "threads": 3, "parameters": {"bounding": {}, "connection": {"max_face_depth": 20}}},
  "cells": {"visited": 101, "solution": 55, "normal": 40, "abnormal": 10, "failed": 5},
  "mesh": {"vertices": 12, "edges": 30, "triangles": 20, "components": 2, "boundary_edges": 3, "boundary_components": 7, "nonmanifold_edges": 4, "euler_characteristic": -2, "open_ends": 5, "branch_vertices": 6, "orientable": false, "betti": [2, 1, 0], "betti_z2": [2, 2, 1], "boundary_facets": 3, "nonmanifold_facets": 4},
  "accuracy": {"max_residual": 1.25e-15, "max_chord_error": 0.10000000000000001},
  "diagnostics": {"ambiguous_cells": 9, "singular_cells": 10, "chord_failures": 8, "off_manifold_vertices": 11, "empty_zero_set": false,
    "singular_points": [
      {"point": [0.5, -0.25, 0, 1], "sigma_min": 1.0000000000000001e-09},
      {"point": [1, 2, 3, 4], "sigma_min": 0.125}
    ],
    "perturbation": {"level": [9.9999999999999995e-08, -1.9999999999999999e-07], "attempts": 3, "degenerate_crossings": 4}},
  "topology": {"certified": false, "reason": "crossing", "certified_cells": 13, "refined_cells": 14, "uncertified_cells": 15, "block_cells": 16, "faces_solved": 17, "base_level": 7, "max_level": 9, "max_depth": 16},
  "timing_s": {"subdivision": 0.5, "projection": 0.25, "connection": 0.33333333333333331, "analysis": 0, "total": null},
  "budget": {"max_memory_bytes": 1073741824, "estimated_memory_bytes": 123456.5, "timeout_s": 12.5, "estimated_time_s": 2.75},
  "expect": {"components": {"wanted": 2, "got": 2, "ok": true}, "genus": {"wanted": 1, "got": 0, "ok": false}},
  "application": {"name": "bisector", "image_singular_vertices": 17, "singular_meaning": "the bisector's determinant"}
}
)json");
  CHECK(ndc::toJson(fullSummary(false)) == R"json({
  "schema": "ndcontour.summary/1",
  "problem": "full \"quoted\" problem",
  "n": 4,
  "k": 2,
  "variables": ["x", "y", "z", "w"],
  "settings": {"depth": 7, "bounding": "bernstein", "subdivision": "uniform", "scalar": "mpfr", "precision_bits": 128, "projection": "newton", "classification": "paper", "connection": "paper", "jitter": 18446744073709551615, "max_depth": 16, "tolerance": 0.001, "threads": 3, "parameters": {"bounding": {}, "connection": {"max_face_depth": 20}}},
  "cells": {"visited": 101, "solution": 55, "normal": 40, "abnormal": 10, "failed": 5},
  "mesh": {"vertices": 12, "edges": 30, "triangles": 20, "components": 2, "boundary_edges": 3, "boundary_components": 7, "nonmanifold_edges": 4, "euler_characteristic": -2, "open_ends": 5, "branch_vertices": 6, "orientable": false, "betti": [2, 1, 0], "betti_z2": [2, 2, 1], "boundary_facets": 3, "nonmanifold_facets": 4},
  "accuracy": {"max_residual": 1.25e-15, "max_chord_error": 0.10000000000000001},
  "diagnostics": {"ambiguous_cells": 9, "singular_cells": 10, "chord_failures": 8, "off_manifold_vertices": 11, "empty_zero_set": false,
    "singular_points": [
      {"point": [0.5, -0.25, 0, 1], "sigma_min": 1.0000000000000001e-09},
      {"point": [1, 2, 3, 4], "sigma_min": 0.125}
    ],
    "perturbation": {"level": [9.9999999999999995e-08, -1.9999999999999999e-07], "attempts": 3, "degenerate_crossings": 4}},
  "topology": {"certified": false, "reason": "crossing", "certified_cells": 13, "refined_cells": 14, "uncertified_cells": 15, "block_cells": 16, "faces_solved": 17, "base_level": 7, "max_level": 9, "max_depth": 16},
  "timing_s": {"subdivision": 0.5, "projection": 0.25, "connection": 0.33333333333333331, "analysis": 0, "total": null},
  "budget": {"max_memory_bytes": 1073741824, "estimated_memory_bytes": 123456.5, "timeout_s": 12.5, "estimated_time_s": 2.75},
  "expect": {"components": {"wanted": 2, "got": 2, "ok": true}, "genus": {"wanted": 1, "got": null, "ok": null, "not_comparable": "not one closed surface"}},
  "application": {"name": "bisector", "image_singular_vertices": 17, "singular_meaning": "the bisector's determinant"}
}
)json");
  CHECK(ndc::toJson(ndc::Summary{}) == R"json({
  "schema": "ndcontour.summary/1",
  "problem": "",
  "n": 0,
  "k": 0,
  "settings": {"depth": 6, "bounding": "linearized", "subdivision": "binary", "scalar": "double", "precision_bits": 53, "projection": "newton", "classification": "paper", "connection": "crossing", "jitter": null, "max_depth": 0, "tolerance": null, "threads": 0, "parameters": {}},
  "cells": {"visited": 0, "solution": 0, "normal": 0, "abnormal": 0, "failed": 0},
  "mesh": {"vertices": 0, "edges": 0, "triangles": 0, "components": 0, "boundary_edges": 0, "boundary_components": 0, "nonmanifold_edges": 0, "euler_characteristic": 0, "open_ends": 0, "branch_vertices": 0, "orientable": true, "betti": [], "betti_z2": [], "boundary_facets": 0, "nonmanifold_facets": 0},
  "accuracy": {"max_residual": 0, "max_chord_error": 0},
  "diagnostics": {"ambiguous_cells": 0, "singular_cells": 0, "chord_failures": 0, "off_manifold_vertices": 0, "empty_zero_set": true,
    "singular_points": [],
    "perturbation": {"level": [], "attempts": 0, "degenerate_crossings": 0}},
  "topology": {"certified": false, "reason": null, "certified_cells": 0, "refined_cells": 0, "uncertified_cells": 0, "block_cells": 0, "faces_solved": 0, "base_level": 0, "max_level": 0, "max_depth": 0},
  "timing_s": {"subdivision": 0, "projection": 0, "connection": 0, "analysis": 0, "total": 0},
  "budget": {"max_memory_bytes": 0, "estimated_memory_bytes": 0, "timeout_s": null, "estimated_time_s": 0}
}
)json");
}

TEST_CASE("summary schema: the writer writes every field in the table's order",
          "[summary][experiment]") {
  // Every leaf of a full summary is a field of the table, met in the table's order.
  std::vector<const ndc::SummaryField*> met;
  for (const std::string& path : ndc::jsonLeafPaths(ndc::toJson(fullSummary(false)))) {
    INFO(path);
    const ndc::SummaryField* f = ndc::summaryFieldOf(path);
    REQUIRE(f);
    if (met.empty() || met.back() != f) met.push_back(f);
  }
  std::vector<const ndc::SummaryField*> leaves;
  for (const ndc::SummaryField& f : ndc::kSummaryFields)
    if (isLeaf(f)) leaves.push_back(&f);
  // Elements repeat their fields: compare the order of first appearance.
  std::vector<const ndc::SummaryField*> first;
  for (const ndc::SummaryField* f : met)
    if (std::find(first.begin(), first.end(), f) == first.end()) first.push_back(f);
  CHECK(first == leaves);
  // Each field has a value unless it is an object; the CSV columns are numbers.
  for (const ndc::SummaryField& f : ndc::kSummaryFields) {
    INFO(f.path);
    CHECK((f.value || f.meshStat || f.type == ndc::SummaryType::object));
    CHECK(!f.doc.empty());
  }
  CHECK(ndc::summaryFieldOf("settings.parameters.connection.max_face_depth")->path ==
        "settings.parameters.*");
  CHECK(ndc::summaryFieldOf("diagnostics.singular_points.3.point.1")->path ==
        "diagnostics.singular_points[].point");
  CHECK(ndc::summaryFieldOf("mesh.genus") == nullptr);
  CHECK(ndc::kExperimentSummaryColumns.front() == "cells.visited");
  CHECK(ndc::kExperimentSummaryColumns.back() == "mesh.nonmanifold_facets");
}

TEST_CASE("summary schema: docs/contracts.md 4.3 and 4.5 show exactly the table's fields",
          "[summary][experiment]") {
  // Each leaf of the examples is a field: of the contract (4.3) or an extension (4.5).
  std::set<const ndc::SummaryField*> shown;
  for (const bool extension : {false, true}) {
    const std::string example = contractsExample(extension ? "## 4.5 Extensions of the summary "
                                                             "(added fields; nothing above is "
                                                             "renamed)"
                                                           : "## 4.3 summary.json");
    for (const std::string& path : ndc::jsonLeafPaths(example)) {
      INFO((extension ? "4.5: " : "4.3: ") + path);
      const ndc::SummaryField* f = ndc::summaryFieldOf(path);
      REQUIRE(f);
      CHECK(f->extension == extension);
      shown.insert(f);
    }
  }
  // Each field of the table is shown.
  for (const ndc::SummaryField& f : ndc::kSummaryFields) {
    INFO(f.path);
    if (isLeaf(f)) CHECK(shown.count(&f) == 1);
  }
}

TEST_CASE("summary schema: docs/experiments.md names every column of the combined CSV",
          "[summary][experiment]") {
  std::ifstream in(std::string(NDC_SOURCE_DIR) + "/docs/experiments.md");
  std::ostringstream read;
  read << in.rdbuf();
  const std::string text = read.str();
  const std::size_t from = text.find("### The combined CSV");
  const std::size_t to = text.find("### The comparison with `[expect]`");
  REQUIRE(from != std::string::npos);
  REQUIRE(to != std::string::npos);
  const std::string section = text.substr(from, to - from);
  for (const std::string_view column : ndc::kExperimentRunColumns) {
    INFO(column);
    CHECK(section.find("`" + std::string(column) + "`") != std::string::npos);
  }
  for (const std::string_view column : ndc::kExperimentSummaryColumns) {
    INFO(column);
    CHECK(section.find("`" + std::string(column) + "`") != std::string::npos);
  }
}
