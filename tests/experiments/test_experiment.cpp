// The experiment runner (docs/experiments.md) as a process: config validation, the combined
// CSV, resume, failure recording and provenance; the problem generators in-process.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "applications/load.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/generate.hpp"
#include "framework/io/io.hpp"
#include "framework/problem/problem.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("experiment");
  return dir.path();
}

using ndc::test::quoted;

using ndc::test::slurp;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

struct Run {
  int status = -1;
  std::string out, err;
};

/// Runs `ndcontour ARGS` (ARGS already shell-quoted) and captures status, stdout and stderr.
Run ndcontour(const std::string& args) {
  const fs::path out = scratch() / "stdout.txt", err = scratch() / "stderr.txt";
  const std::string command = quoted(ndc::test::binaryPath()) + " " + args + " >" +
                              quoted(out.string()) + " 2>" + quoted(err.string()) + " </dev/null";
  const int raw = std::system(command.c_str());
  Run run;
  run.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  run.out = slurp(out);
  run.err = slurp(err);
  return run;
}

/// Writes a config `<dir>/<id>.toml` and returns its path.
fs::path writeConfig(const std::string& id, const std::string& text,
                     const std::string& dir = "configs") {
  fs::create_directories(scratch() / dir);
  const fs::path file = scratch() / dir / (id + ".toml");
  std::ofstream(file) << text;
  return file;
}

std::string example(const std::string& name) {
  return (fs::path(ndc::test::sourceDir()) / "experiments" / "problems" / (name + ".toml"))
      .string();
}

/// `ndcontour experiment CONFIG --out OUT ARGS`.
Run experiment(const fs::path& config, const fs::path& out, const std::string& args = "") {
  return ndcontour("experiment " + quoted(config.string()) + " --out " + quoted(out.string()) +
                   " " + args);
}

/// A CSV file as rows of fields (RFC 4180 quoting).
std::vector<std::vector<std::string>> readCsv(const fs::path& file) {
  const std::string text = slurp(file);
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string field;
  bool inQuotes = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (inQuotes) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        inQuotes = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      inQuotes = true;
    } else if (c == ',') {
      row.push_back(field);
      field.clear();
    } else if (c == '\n') {
      row.push_back(field);
      field.clear();
      rows.push_back(row);
      row.clear();
    } else {
      field += c;
    }
  }
  return rows;
}

/// Rows of a CSV as maps from column name to value.
std::vector<std::map<std::string, std::string>> csvRecords(const fs::path& file) {
  const auto rows = readCsv(file);
  std::vector<std::map<std::string, std::string>> records;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    REQUIRE(rows[r].size() == rows[0].size());
    std::map<std::string, std::string> record;
    for (std::size_t c = 0; c < rows[0].size(); ++c) record[rows[0][c]] = rows[r][c];
    records.push_back(record);
  }
  return records;
}

/// Status 2, nothing on stdout, exactly one line on stderr holding every part.
void checkBadConfig(const Run& run, std::initializer_list<std::string> parts) {
  INFO("stderr: " << run.err << "stdout: " << run.out);
  CHECK(run.status == 2);
  CHECK(run.out.empty());
  CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
  for (const auto& part : parts) CHECK(contains(run.err, part));
}

/// The exact header of the combined CSV: other tools read it by these names.
const std::string kHeader =
    "experiment,run,problem,problem_file,n,k,depth,seed,scalar,precision_bits,bounding,"
    "subdivision,projection,classification,connection,status,exit_code,error,expect_components,"
    "expect_euler_characteristic,expect_ok,expect_notes,cells.visited,cells.solution,"
    "cells.normal,cells.abnormal,"
    "cells.failed,mesh.vertices,mesh.edges,mesh.triangles,mesh.components,mesh.boundary_edges,"
    "mesh.nonmanifold_edges,mesh.euler_characteristic,mesh.open_ends,mesh.branch_vertices,"
    "accuracy.max_residual,accuracy.max_chord_error,diagnostics.ambiguous_cells,"
    "diagnostics.singular_cells,diagnostics.chord_failures,timing_s.subdivision,"
    "timing_s.projection,timing_s.connection,timing_s.analysis,timing_s.total,"
    "diagnostics.off_manifold_vertices,diagnostics.perturbation.attempts,"
    "diagnostics.perturbation.degenerate_crossings,mesh.boundary_components,"
    "budget.max_memory_bytes,budget.estimated_memory_bytes,budget.timeout_s,"
    "topology.base_level,topology.certified_cells,topology.max_depth,topology.max_level,"
    "topology.reason,topology.refined_cells,topology.uncertified_cells,topology.block_cells,"
    "budget.estimated_time_s,topology.faces_solved,mesh.boundary_facets,mesh.nonmanifold_facets";

const std::string kTiny =
    "id = \"tiny\"\nartefact = \"table\"\ndescription = \"a tiny grid\"\n"
    "problems = [\"" +
    example("circle") +
    "\"]\n"
    "connection = [\"paper\", \"crossing\"]\ndepths = [3, 4]\n"
    "timeout_s = 60\n[quick]\ndepths = [2]\n";

}  // namespace

TEST_CASE("experiment: bad configs exit 2 with one line naming file, line and column",
          "[experiment]") {
  struct Case {
    std::string id;
    std::string text;
    std::string position;  // right after "FILE:" (line and column where the text fixes them)
    std::string message;
  };
  const std::string head = "artefact = \"table\"\ndescription = \"d\"\n";
  const std::string circle = "problems = [\"" + example("circle") + "\"]\n";
  const std::vector<Case> cases = {
      {"syntax", "id = \"syntax\"\nartefact = \"table\n", "2:", "TOML syntax error"},
      {"stem", "id = \"other\"\n" + head + circle + "depths = [3]\n",
       "1:6:", "id 'other' must equal the file name"},
      {"unknown-key", "id = \"unknown-key\"\n" + head + circle + "depths = [3]\ncolour = 1\n",
       "6:1:", "unknown key 'colour'"},
      {"missing-depths", "id = \"missing-depths\"\n" + head + circle, " missing",
       "required key 'depths'"},
      {"wrong-type", "id = \"wrong-type\"\n" + head + circle + "depths = \"3\"\n",
       "5:10:", "depths must be an integer, not a string"},
      {"depth-range", "id = \"depth-range\"\n" + head + circle + "depths = [3, 31]\n",
       "5:14:", "depths = 31 is out of range"},
      {"strategy",
       "id = \"strategy\"\n" + head + circle + "depths = [3]\nbounding = [\"taylor\"]\n", "6:13:",
       "bounding: unknown bounding strategy 'taylor' (known: bernstein, interval, "
       "linearized)"},
      {"connection",
       "id = \"connection\"\n" + head + circle + "depths = [3]\nconnection = \"mc\"\n",
       "6:14:", "unknown connection strategy 'mc'"},
      {"parameter",
       "id = \"parameter\"\n" + head + circle + "depths = [3]\nconnection = \"paper:layers=2\"\n",
       "6:14:",
       "connection strategy 'paper:layers=2': unknown parameter 'layers' (known: extra_layers, "
       "thin_thick_normal)"},
      {"artefact",
       "id = \"artefact\"\nartefact = \"movie\"\ndescription = \"d\"\n" + circle + "depths = [3]\n",
       "2:12:", "unknown artefact 'movie'"},
      {"missing-file",
       "id = \"missing-file\"\n" + head + "problems = [\"no/such/problem.toml\"]\ndepths = [3]\n",
       "4:13:", "no such problem file 'no/such/problem.toml'"},
      {"glob",
       "id = \"glob\"\n" + head + "problems = [\"/nonexistent-dir/*.toml\"]\ndepths = [3]\n",
       "4:13:", "'/nonexistent-dir/*.toml': no such directory"},
      {"generator",
       "id = \"generator\"\n" + head +
           "problems = [{ generator = \"rotated-cube\", n = [3] }]\ndepths = [3]\n",
       "4:27:", "unknown generator 'rotated-cube'"},
      {"generator-n",
       "id = \"generator-n\"\n" + head +
           "problems = [{ generator = \"rotated-sphere\", n = [2] }]\ndepths = [3]\n",
       "4:50:", "n = 2 is out of range (accepted: 3..16)"},
      {"quick-key", "id = \"quick-key\"\n" + head + circle + "depths = [3]\n[quick]\nid = \"x\"\n",
       "7:1:", "unknown key 'quick.id'"},
      {"quick-value",
       "id = \"quick-value\"\n" + head + circle + "depths = [3]\n[quick]\ndepths = [0]\n",
       "7:11:", "quick.depths = 0 is out of range"},
      {"precision", "id = \"precision\"\n" + head + circle + "depths = [3]\nprecision = [64]\n",
       "6:13:", "precision applies to scalar \"mpfr\" only"},
      {"duplicate",
       "id = \"duplicate\"\n" + head + "problems = [\"" + example("circle") + "\", \"" +
           example("circle") + "\"]\ndepths = [3]\n",
       "4:", "problem name 'circle' appears twice"},
      {"repeat", "id = \"repeat\"\n" + head + circle + "depths = [3, 3]\n",
       "5:14:", "depths lists a value twice"},
      {"timeout", "id = \"timeout\"\n" + head + circle + "depths = [3]\ntimeout_s = 0\n",
       "6:13:", "timeout_s must be positive"},
      {"cells", "id = \"cells\"\n" + head + circle + "depths = [3]\ncells = 1\n",
       "6:9:", "cells must be true or false, not an integer"},
      {"entry-key",
       "id = \"entry-key\"\n" + head + "problems = [{ file = \"" + example("circle") +
           "\", seed = 1 }]\ndepths = [3]\n",
       "4:", "unknown key 'seed' in a problem file entry"},
  };
  for (const Case& c : cases) {
    INFO(c.id);
    const fs::path config = writeConfig(c.id, c.text);
    checkBadConfig(experiment(config, scratch() / "bad-out"),
                   {config.string() + ":" + c.position, c.message});
  }
  // No run was started and nothing was written for a bad config.
  CHECK(!fs::exists(scratch() / "bad-out"));

  // A problem file that does not load is reported at its own position.
  const fs::path broken = scratch() / "broken.toml";
  std::ofstream(broken) << "name = \"broken\"\nvariables = [\"x\", \"y\"]\n";
  checkBadConfig(experiment(writeConfig("broken-problem", "id = \"broken-problem\"\n" + head +
                                                              "problems = [\"" + broken.string() +
                                                              "\"]\ndepths = [3]\n"),
                            scratch() / "bad-out"),
                 {broken.string(), "missing required key 'domain'"});
  // Unreadable config and bad options.
  checkBadConfig(experiment(scratch() / "configs" / "absent.toml", scratch() / "bad-out"),
                 {"absent.toml", "No such file or directory"});
  const fs::path tiny = writeConfig("tiny", kTiny);
  checkBadConfig(experiment(tiny, scratch() / "bad-out", "--jobs 0"), {"--jobs"});
  checkBadConfig(ndcontour("experiment"), {"config"});
}

TEST_CASE("experiment: a tiny grid writes the combined CSV, one row per run in grid order",
          "[experiment]") {
  const fs::path config = writeConfig("tiny", kTiny);
  const fs::path out = scratch() / "tiny-out";
  fs::remove_all(out);
  const Run run = experiment(config, out, "--jobs 2");
  INFO("stdout: " << run.out << "stderr: " << run.err);
  REQUIRE(run.status == 0);
  CHECK(contains(run.out, "experiment tiny: 4 runs: 4 ran, 0 skipped"));
  const fs::path csv = out / "tiny" / "tiny.csv";
  REQUIRE(fs::exists(csv));
  CHECK(readCsv(csv).front().size() ==
        ndc::kExperimentRunColumns.size() + ndc::kExperimentSummaryColumns.size());
  CHECK(slurp(csv).substr(0, slurp(csv).find('\n')) == kHeader);

  // Grid order: settings (connection) outside, depth inside.
  const auto records = csvRecords(csv);
  REQUIRE(records.size() == 4);
  const std::vector<std::pair<std::string, std::string>> order = {
      {"paper", "3"}, {"paper", "4"}, {"crossing", "3"}, {"crossing", "4"}};
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto& r = records[i];
    INFO(r.at("run"));
    CHECK(r.at("experiment") == "tiny");
    CHECK(r.at("problem") == "circle");
    CHECK(r.at("problem_file") == example("circle"));
    CHECK(r.at("n") == "2");
    CHECK(r.at("k") == "1");
    CHECK(r.at("connection") == order[i].first);
    CHECK(r.at("depth") == order[i].second);
    CHECK(r.at("seed").empty());
    CHECK(r.at("scalar") == "double");
    CHECK(r.at("precision_bits") == "53");
    CHECK(r.at("bounding") == "linearized");
    CHECK(r.at("status") == "ok");
    CHECK(r.at("exit_code") == "0");
    CHECK(r.at("error").empty());
    CHECK(r.at("expect_components") == "1");
    CHECK(r.at("mesh.components") == "1");
    CHECK(r.at("mesh.euler_characteristic") == "0");
    // The comparison with [expect] (components = 1, euler_characteristic = 0).
    CHECK(r.at("expect_ok") == "true");
    CHECK(r.at("expect_notes").empty());
    CHECK(r.at("diagnostics.off_manifold_vertices") == "0");
    CHECK(std::stoi(r.at("cells.solution")) > 0);
    CHECK(std::stod(r.at("timing_s.total")) >= 0);
    // Each run directory holds the solve outputs, its stderr and its command.
    const fs::path runDir = out / "tiny" / "runs" / r.at("run");
    for (const char* file :
         {"summary.json", "mesh.ply", "singular.csv", "stderr.txt", "command.txt"})
      CHECK(fs::exists(runDir / file));
    CHECK(!fs::exists(runDir / "cells.csv"));  // only with `cells = true`
    CHECK(contains(slurp(runDir / "command.txt"), "ndcontour solve "));
  }

  // The rows do not depend on --jobs.
  const fs::path serial = scratch() / "tiny-serial";
  fs::remove_all(serial);
  REQUIRE(experiment(config, serial, "--jobs 1").status == 0);
  const auto again = csvRecords(serial / "tiny" / "tiny.csv");
  REQUIRE(again.size() == records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    CHECK(again[i].at("run") == records[i].at("run"));
    CHECK(again[i].at("cells.solution") == records[i].at("cells.solution"));
  }

  // --quick applies the [quick] table.
  const Run quick = experiment(config, out, "--quick");
  CHECK(quick.status == 0);
  const auto quickRecords = csvRecords(csv);
  REQUIRE(quickRecords.size() == 2);
  for (const auto& r : quickRecords) CHECK(r.at("depth") == "2");
  CHECK(contains(slurp(out / "tiny" / "provenance.json"), "\"quick\": true"));
}

TEST_CASE("experiment: strategy parameters in a config reach the runs and their summaries",
          "[experiment]") {
  const std::string text =
      "id = \"params\"\nartefact = \"table\"\ndescription = \"d\"\n"
      "problems = [\"" +
      example("circle") +
      "\"]\ndepths = [3]\n"
      "connection = [\"paper\", \"paper:extra_layers=1\", "
      "\"crossing:max_face_depth=16\"]\n";
  const fs::path config = writeConfig("params", text);
  const fs::path out = scratch() / "params-out";
  fs::remove_all(out);
  const Run run = experiment(config, out, "--jobs 1");
  INFO("stdout: " << run.out << "stderr: " << run.err);
  REQUIRE(run.status == 0);
  const auto records = csvRecords(out / "params" / "params.csv");
  REQUIRE(records.size() == 3);
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"paper", "\"connection\": {\"extra_layers\": 0, \"thin_thick_normal\": true}"},
      {"paper:extra_layers=1",
       "\"connection\": {\"extra_layers\": 1, \"thin_thick_normal\": true}"},
      {"crossing:max_face_depth=16", "\"connection\": {\"max_face_depth\": 16}"}};
  for (std::size_t i = 0; i < records.size(); ++i) {
    INFO(records[i].at("run"));
    CHECK(records[i].at("connection") == expected[i].first);
    CHECK(records[i].at("status") == "ok");
    // Run ids stay plain folder names: ':' and ',' become '+', '=' becomes '-'.
    CHECK(records[i].at("run").find_first_of(":=,") == std::string::npos);
    const std::string summary =
        slurp(out / "params" / "runs" / records[i].at("run") / "summary.json");
    CHECK(contains(summary, expected[i].second));
  }
  CHECK(contains(records[1].at("run"), ".paper+extra_layers-1."));
}

TEST_CASE("experiment: the comparison with [expect] is recorded per run", "[experiment]") {
  // The circle with a wrong and a right [expect], and one without: the runs succeed (the runner
  // does not pass --check) and the CSV says which matched.
  const fs::path problems = scratch() / "expect-problems";
  fs::create_directories(problems);
  const std::string circle =
      "variables = [\"x\", \"y\"]\ndomain = [[-2, 2], [-2, 2]]\n"
      "equations = [\"x^2 + y^2 - 1\"]\n";
  std::ofstream(problems / "a.toml")
      << "name = \"wrong\"\n" + circle + "[expect]\ncomponents = 2\ngenus = 0\n";
  std::ofstream(problems / "b.toml")
      << "name = \"right\"\n" + circle + "[expect]\ncomponents = 1\n";
  std::ofstream(problems / "c.toml") << "name = \"none\"\n" + circle;
  const fs::path config = writeConfig("expect-grid",
                                      "id = \"expect-grid\"\nartefact = \"table\"\n"
                                      "description = \"d\"\nproblems = [\"" +
                                          (problems / "*.toml").string() + "\"]\ndepths = [3]\n");
  const fs::path out = scratch() / "expect-out";
  fs::remove_all(out);
  const Run run = experiment(config, out);
  INFO("stdout: " << run.out << "stderr: " << run.err);
  REQUIRE(run.status == 0);
  const auto records = csvRecords(out / "expect-grid" / "expect-grid.csv");
  REQUIRE(records.size() == 3);
  CHECK(records[0].at("problem") == "wrong");
  CHECK(records[0].at("status") == "ok");
  CHECK(records[0].at("expect_components") == "2");
  CHECK(records[0].at("expect_ok") == "false");
  CHECK(contains(records[0].at("expect_notes"),
                 "expect components = 2, got 1; expect genus = 0: "
                 "not comparable"));
  CHECK(records[1].at("expect_ok") == "true");
  CHECK(records[1].at("expect_notes").empty());
  CHECK(records[2].at("expect_ok").empty());
  CHECK(records[2].at("expect_components").empty());
  // The run's own warning is in its stderr.txt.
  CHECK(contains(slurp(out / "expect-grid" / "runs" / records[0].at("run") / "stderr.txt"),
                 "expect components = 2, got 1"));
  // No column per key of [expect] or per list element.
  for (const auto& [column, value] : records[0]) {
    CHECK(column.rfind("expect.", 0) != 0);
    CHECK(!contains(column, "singular_points"));
  }
}

TEST_CASE("experiment: re-running skips finished runs and repeats unfinished ones",
          "[experiment]") {
  const fs::path config = writeConfig("tiny", kTiny);
  const fs::path out = scratch() / "resume-out";
  fs::remove_all(out);
  REQUIRE(experiment(config, out).status == 0);
  const fs::path runs = out / "tiny" / "runs";
  std::map<std::string, fs::file_time_type> mtimes;
  for (const auto& entry : fs::directory_iterator(runs))
    mtimes[entry.path().filename().string()] = fs::last_write_time(entry.path() / "summary.json");
  REQUIRE(mtimes.size() == 4);
  const std::string csv = slurp(out / "tiny" / "tiny.csv");

  const Run again = experiment(config, out);
  INFO(again.out << again.err);
  CHECK(again.status == 0);
  CHECK(contains(again.out, "4 runs: 0 ran, 4 skipped"));
  for (const auto& [run, mtime] : mtimes)
    CHECK(fs::last_write_time(runs / run / "summary.json") == mtime);
  CHECK(slurp(out / "tiny" / "tiny.csv") == csv);

  // A run without summary.json is unfinished: it runs again, the others stay.
  const std::string first = mtimes.begin()->first;
  fs::remove(runs / first / "summary.json");
  const Run partial = experiment(config, out);
  CHECK(partial.status == 0);
  CHECK(contains(partial.out, "4 runs: 1 ran, 3 skipped"));
  CHECK(fs::exists(runs / first / "summary.json"));
  CHECK(csvRecords(out / "tiny" / "tiny.csv").size() == 4);
}

TEST_CASE("experiment: cells = true writes cells.csv; the report reads the binary meshes",
          "[experiment]") {
  const fs::path config = writeConfig(
      "fig-cells",
      "id = \"fig-cells\"\nartefact = \"figure\"\ndescription = \"d\"\nproblems = [\"" +
          example("two-circles") + "\"]\nconnection = \"paper\"\ndepths = [3, 4]\ncells = true\n",
      "cells-configs");
  const fs::path out = scratch() / "cells-out";
  fs::remove_all(out);
  const Run run = experiment(config, out);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const fs::path runs = out / "fig-cells" / "runs";
  const fs::path depth4 = runs / "two-circles.L4.linearized.binary.newton.paper.paper.double53";
  const fs::path depth3 = runs / "two-circles.L3.linearized.binary.newton.paper.paper.double53";
  for (const fs::path& dir : {depth3, depth4}) {
    INFO(dir);
    CHECK(fs::exists(dir / "cells.csv"));
    CHECK(contains(slurp(dir / "command.txt"), " --cells --json"));
    CHECK(slurp(dir / "mesh.ply").rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
  }
  CHECK(contains(slurp(out / "fig-cells" / "provenance.json"), "\"cells\": true"));
  // A run without its cells.csv is unfinished and runs again.
  fs::remove(depth3 / "cells.csv");
  const Run resumed = experiment(config, out);
  CHECK(contains(resumed.out, "2 runs: 1 ran, 1 skipped"));
  CHECK(fs::exists(depth3 / "cells.csv"));

  // The report draws the cells and the polyline of the deepest run's binary mesh.ply.
  const std::string report = "report --results " + quoted(out.string()) + " --configs " +
                             quoted(config.parent_path().string());
  const Run good = ndcontour(report);
  INFO(good.out << good.err);
  CHECK(good.status != 2);
  CHECK(contains(slurp(out / "report.md"), "The polyline has "));
  // A truncated mesh.ply is bad input: one line naming it, and status 2.
  const std::string mesh = slurp(depth4 / "mesh.ply");
  std::ofstream(depth4 / "mesh.ply", std::ios::binary) << mesh.substr(0, mesh.size() - 3);
  const Run bad = ndcontour(report);
  INFO(bad.out << bad.err);
  CHECK(bad.status == 2);
  CHECK(contains(bad.err,
                 "ndcontour: " + (depth4 / "mesh.ply").string() + ": element 'edge' declares "));
}

TEST_CASE("experiment: failed and timed-out runs are recorded and reported, never dropped",
          "[experiment]") {
  // torus at depth 14: about 1.4e9 solution cells, over any machine's memory budget, which solve
  // refuses before the work (exit 2); depth 3 succeeds.
  const fs::path failing = writeConfig(
      "failing", "id = \"failing\"\nartefact = \"table\"\ndescription = \"d\"\nproblems = [\"" +
                     example("torus") + "\"]\ndepths = [14, 3]\n");
  const fs::path out = scratch() / "failing-out";
  fs::remove_all(out);
  const Run run = experiment(failing, out);
  INFO("stdout: " << run.out << "stderr: " << run.err);
  CHECK(run.status == 1);
  CHECK(contains(run.out, "2 runs: 2 ran, 0 skipped (finished before), 1 failed"));
  CHECK(contains(run.out, "failed: torus.L14."));
  auto records = csvRecords(out / "failing" / "failing.csv");
  REQUIRE(records.size() == 2);
  CHECK(records[0].at("depth") == "14");
  CHECK(records[0].at("status") == "failed");
  CHECK(records[0].at("exit_code") == "2");
  CHECK(contains(records[0].at("error"), "of memory"));
  CHECK(contains(records[0].at("error"), "over the budget"));
  CHECK(records[0].at("cells.visited").empty());
  CHECK(records[0].at("timing_s.total").empty());
  CHECK(records[1].at("status") == "ok");
  CHECK(!records[1].at("cells.visited").empty());
  // The failure is kept in the run directory and in the provenance.
  CHECK(contains(slurp(out / "failing" / "runs" / records[0].at("run") / "stderr.txt"),
                 "--max-memory"));
  CHECK(contains(slurp(out / "failing" / "provenance.json"), "\"failed\": 1"));
  // A failed run is not finished: the next invocation tries it again.
  const Run again = experiment(failing, out);
  CHECK(again.status == 1);
  CHECK(contains(again.out, "2 runs: 1 ran, 1 skipped (finished before), 1 failed"));

  // A run past its timeout is killed and recorded as such.
  const fs::path slow = writeConfig(
      "slow", "id = \"slow\"\nartefact = \"figure\"\ndescription = \"d\"\nproblems = [\"" +
                  example("sphere-r4") + "\"]\ndepths = [7]\ntimeout_s = 0.001\n");
  const Run timeout = experiment(slow, out);
  CHECK(timeout.status == 1);
  CHECK(contains(timeout.out, "timeout"));
  records = csvRecords(out / "slow" / "slow.csv");
  REQUIRE(records.size() == 1);
  CHECK(records[0].at("status") == "timeout");
  CHECK(records[0].at("exit_code").empty());
  CHECK(contains(records[0].at("error"), "timed out after 0.001 s"));
  CHECK(!fs::exists(out / "slow" / "runs" / records[0].at("run") / "summary.json"));
}

TEST_CASE("experiment: provenance records code, build, config, grid, date and machine",
          "[experiment]") {
  const fs::path config = writeConfig(
      "prov", "id = \"prov\"\nartefact = \"table\"\ndescription = \"d\"\nproblems = [\"" +
                  example("circle") +
                  "\"]\nscalar = [\"double\", \"mpfr\"]\nprecision = [64]\ndepths = [3]\n"
                  "seeds = [1, 2]\n");
  const fs::path out = scratch() / "prov-out";
  fs::remove_all(out);
  const Run run = experiment(config, out, "--jobs 2");
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  CHECK(csvRecords(out / "prov" / "prov.csv").size() == 4);
  const std::string p = slurp(out / "prov" / "provenance.json");
  INFO(p);
  for (const char* field : {"\"schema\": \"ndcontour.provenance/1\"",
                            "\"experiment\": \"prov\"",
                            "\"git\": {",
                            "\"revision\": \"",
                            "\"dirty\": ",
                            "\"compiler\": \"",
                            "\"flags\": \"",
                            "\"build_type\": \"",
                            "\"scalar\": [\"double\", \"mpfr\"]",
                            "\"precision_bits\": [64]",
                            "\"depths\": [3]",
                            "\"seeds\": [1, 2]",
                            "\"bounding\": [\"linearized\"]",
                            "\"connection\": [\"crossing\"]",
                            "\"date\": \"20",
                            "\"hostname\": \"",
                            "\"nproc\": ",
                            "\"cpu_model\": \"",
                            "\"memory_bytes\": ",
                            "\"jobs\": 2",
                            "\"cells\": false",
                            "\"total\": 4"})
    CHECK(contains(p, field));
  CHECK(contains(p, "\"sha256\": \"" + ndc::sha256Hex(slurp(config)) + "\""));
  // The date is UTC ISO 8601.
  const auto date = p.find("\"date\": \"");
  REQUIRE(date != std::string::npos);
  const std::string stamp = p.substr(date + 9, 20);
  CHECK(stamp.size() == 20);
  CHECK(stamp[4] == '-');
  CHECK(stamp[10] == 'T');
  CHECK(stamp[19] == 'Z');
  // The summary numbers parse as JSON numbers with the names of the CSV.
  const auto numbers = ndc::flattenJsonNumbers(p);
  CHECK(std::find_if(numbers.begin(), numbers.end(), [](const auto& n) {
          return n.first == "runs.total" && n.second == "4";
        }) != numbers.end());
}

TEST_CASE("experiment: problem globs and generated problems", "[experiment]") {
  // A glob expands to the sorted matching files; paths are relative to the config's directory
  // outside a repository layout.
  const fs::path dir = scratch() / "globbed";
  fs::create_directories(dir / "problems");
  fs::copy_file(example("circle"), dir / "problems" / "b.toml",
                fs::copy_options::overwrite_existing);
  fs::copy_file(example("two-circles"), dir / "problems" / "a.toml",
                fs::copy_options::overwrite_existing);
  const fs::path config =
      writeConfig("globbed",
                  "id = \"globbed\"\nartefact = \"figure\"\ndescription = \"d\"\n"
                  "problems = [\"problems/*.toml\", { generator = \"rotated-sphere\", "
                  "n = [4], seeds = [7] }]\ndepths = [3]\n",
                  "globbed");
  const fs::path out = scratch() / "globbed-out";
  fs::remove_all(out);
  const Run run = experiment(config, out);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const auto records = csvRecords(out / "globbed" / "globbed.csv");
  REQUIRE(records.size() == 3);
  CHECK(records[0].at("problem_file") == "problems/a.toml");
  CHECK(records[0].at("problem") == "two-circles");
  CHECK(records[1].at("problem_file") == "problems/b.toml");
  CHECK(records[2].at("problem") == "rotated-sphere-n4-s7");
  CHECK(records[2].at("k") == "2");
  CHECK(records[2].at("expect_euler_characteristic") == "2");

  // The generated problem is a file beside the results; solving it repeats the run.
  const fs::path generated = out / "globbed" / "problems" / "rotated-sphere-n4-s7.toml";
  CHECK(records[2].at("problem_file") == generated.generic_string());
  REQUIRE(fs::exists(generated));
  const ndc::Problem problem = ndc::loadProblem(generated);
  CHECK(problem.n() == 4);
  CHECK(problem.k() == 2);
  const Run solve = ndcontour("solve " + quoted(generated.string()) + " --depth 3 --json");
  CHECK(solve.status == 0);
  CHECK(contains(solve.out, "\"solution\": " + records[2].at("cells.solution") + ","));
}

TEST_CASE("experiment: generated problems parse and their sampled points satisfy the equations",
          "[experiment]") {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  for (const std::string generator : {"rotated-circle", "rotated-sphere"}) {
    const int k = generator == "rotated-circle" ? 1 : 2;
    for (int n = k + 1; n <= ndc::kMaxGeneratedDimension; ++n) {
      for (std::uint64_t seed : {0, 1, 17}) {
        INFO(generator << " n = " << n << " seed " << seed);
        const ndc::GeneratedProblem g = ndc::generateProblem(generator, n, seed);
        CHECK(g.name == generator + "-n" + std::to_string(n) + "-s" + std::to_string(seed));
        const ndc::Problem p = ndc::parseProblem(g.text, g.name);
        CHECK(p.name == g.name);
        CHECK(p.n() == n);
        CHECK(p.k() == k);
        CHECK(p.expect.components == 1);
        CHECK(p.expect.eulerCharacteristic == (k == 1 ? 0 : 2));
        // Q is orthogonal.
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) {
            double dot = 0;
            for (int l = 0; l < n; ++l) dot += g.rotation[i * n + l] * g.rotation[j * n + l];
            CHECK(std::abs(dot - (i == j ? 1.0 : 0.0)) < 1e-12);
          }
        // Points of M are zeros of every equation and lie inside the domain with margin.
        for (int s = 0; s < 20; ++s) {
          std::vector<double> u(k + 1);
          double norm = 0;
          for (double& v : u) {
            v = normal(rng);
            norm += v * v;
          }
          for (double& v : u) v /= std::sqrt(norm);
          const std::vector<double> x = ndc::generatedPoint(g, u);
          for (int j = 0; j < n; ++j) {
            CHECK(x[j] > p.domain.lo[j] + 0.1);
            CHECK(x[j] < p.domain.hi[j] - 0.1);
          }
          for (const ndc::Expression& e : p.equations)
            CHECK(std::abs(e.evaluate<double>(std::span<const double>(x))) < 1e-12);
          // A point off M (scaled radius) is not a zero of the quadric.
          std::vector<double> off = x;
          for (int j = 0; j < n; ++j) off[j] = g.offset[j] + 1.1 * (x[j] - g.offset[j]);
          CHECK(std::abs(p.equations[0].evaluate<double>(std::span<const double>(off))) > 0.1);
        }
        // Deterministic, and different seeds give different embeddings.
        CHECK(ndc::generateProblem(generator, n, seed).text == g.text);
        CHECK(ndc::generateProblem(generator, n, seed + 1).text != g.text);
      }
    }
    CHECK_THROWS_AS(ndc::generateProblem(generator, k, 0), std::invalid_argument);
    CHECK_THROWS_AS(ndc::generateProblem(generator, ndc::kMaxGeneratedDimension + 1, 0),
                    std::invalid_argument);
  }
  CHECK_THROWS_AS(ndc::generateProblem("rotated-torus", 4, 0), std::invalid_argument);
}

TEST_CASE("experiment: summary columns, JSON numbers and SHA-256", "[experiment]") {
  // Every summary column of the CSV is a numeric field of summary.json (docs/contracts.md 4.3).
  ndc::Summary summary;
  const auto numbers = ndc::flattenJsonNumbers(ndc::toJson(summary));
  for (const std::string_view column : ndc::kExperimentSummaryColumns) {
    INFO(column);
    CHECK(std::find_if(numbers.begin(), numbers.end(),
                       [&](const auto& n) { return n.first == column; }) != numbers.end());
  }
  const auto parsed =
      ndc::flattenJsonNumbers(R"({"a": {"b": 1.5e-3, "c": null, "d": "x,y"}, "e": [1, -2]})");
  REQUIRE(parsed.size() == 4);
  CHECK(parsed[0] == std::make_pair(std::string("a.b"), std::string("1.5e-3")));
  CHECK(parsed[1] == std::make_pair(std::string("a.c"), std::string("")));
  CHECK(parsed[2] == std::make_pair(std::string("e.0"), std::string("1")));
  CHECK_THROWS(ndc::flattenJsonNumbers("{\"a\": }"));
  CHECK_THROWS(ndc::flattenJsonNumbers("{\"a\": 1"));
  // FIPS 180-2 examples.
  CHECK(ndc::sha256Hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(ndc::sha256Hex("abc") ==
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(ndc::sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  // Two blocks of padding and a message longer than one block.
  CHECK(ndc::sha256Hex(std::string(1000, 'a')) ==
        "41edece42d63e8d9bf515a9ba6932e1c20cbc9f5a5d134645adb5db1b9737ea3");
}

namespace {

/// Sends standard output and error to /dev/null for its lifetime (runExperiment reports there).
class Silence {
 public:
  Silence() : out_(::dup(STDOUT_FILENO)), err_(::dup(STDERR_FILENO)) {
    std::fflush(stdout);
    std::fflush(stderr);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(null, STDERR_FILENO);
    ::close(null);
  }
  ~Silence() {
    std::fflush(stdout);
    std::fflush(stderr);
    ::dup2(out_, STDOUT_FILENO);
    ::dup2(err_, STDERR_FILENO);
    ::close(out_);
    ::close(err_);
  }

 private:
  int out_, err_;
};

}  // namespace

TEST_CASE("experiment: a run killed by a signal is recorded as crashed", "[experiment]") {
  // A stand-in for ndcontour that crashes at depth 3 and is the real tool otherwise.
  const fs::path tool = scratch() / "crashing-ndcontour.sh";
  std::ofstream(tool) << "#!/bin/sh\ncase \"$*\" in *'--depth 3 '*) kill -SEGV $$ ;; esac\nexec "
                      << quoted(ndc::test::binaryPath()) << " \"$@\"\n";
  fs::permissions(tool, fs::perms::owner_all);
  const fs::path config = writeConfig(
      "crash", "id = \"crash\"\nartefact = \"table\"\ndescription = \"d\"\nproblems = [\"" +
                   example("circle") + "\"]\ndepths = [3, 4]\n");
  const fs::path out = scratch() / "crash-out";
  fs::remove_all(out);
  ndc::ExperimentOptions options;
  options.outDir = out;
  options.jobs = 2;
  options.executable = tool.string();
  int status = -1;
  {
    const Silence silence;
    status = ndc::runExperiment(ndc::loadExperimentConfig(config, false), options);
  }
  CHECK(status == 1);
  const auto records = csvRecords(out / "crash" / "crash.csv");
  REQUIRE(records.size() == 2);
  CHECK(records[0].at("status") == "crashed");
  CHECK(records[0].at("exit_code") == "-11");
  CHECK(contains(records[0].at("error"), "killed by signal 11"));
  CHECK(records[0].at("mesh.components").empty());
  CHECK(records[1].at("status") == "ok");
  CHECK(records[1].at("mesh.components") == "1");
}

TEST_CASE("experiment: SIGTERM stops the runner and its children, and keeps finished runs",
          "[experiment]") {
  // A quick run and a slow one (torus-r6 at depth 6 takes tens of seconds), both at once.
  const fs::path config = writeConfig(
      "stopped", "id = \"stopped\"\nartefact = \"table\"\ndescription = \"d\"\nproblems = [\"" +
                     example("circle") + "\", \"" + example("torus-r6") + "\"]\ndepths = [6]\n");
  const fs::path out = scratch() / "stopped-out";
  fs::remove_all(out);
  const auto start = std::chrono::steady_clock::now();
  const std::string command =
      "timeout --preserve-status -s TERM 2 " + quoted(ndc::test::binaryPath()) + " experiment " +
      quoted(config.string()) + " --jobs 2 --out " + quoted(out.string()) + " >/dev/null 2>&1";
  const int raw = std::system(command.c_str());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK((WIFEXITED(raw) && WEXITSTATUS(raw) == 143));
  CHECK(seconds < 30);  // 2 s and a second for the children; the torus alone takes minutes
  // The circle finished and keeps its summary; the torus did not, and left no staging folder.
  int finished = 0;
  for (const auto& run : fs::directory_iterator(out / "stopped" / "runs")) {
    finished += fs::exists(run.path() / "summary.json");
    for (const auto& entry : fs::directory_iterator(run.path()))
      CHECK(entry.path().filename().string().rfind(".ndcontour-partial", 0) != 0);
  }
  CHECK(finished == 1);
  // No CSV is written by an interrupted invocation; the next one resumes.
  CHECK(!fs::exists(out / "stopped" / "stopped.csv"));
}
