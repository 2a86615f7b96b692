// The report generator (issue 6): CSV reading, aggregation, Markdown and LaTeX tables generated
// from hand-written experiment CSVs, failed runs and missing experiments in results/report.md,
// and bad input (a missing column) as a one-line error that leaves earlier outputs alone; the
// viewer links as one compact table, runs without an expectation counted apart, and lit
// application figures with their legends off the data (issue 43).
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/report/perspective.hpp"
#include "experiments/report/report.hpp"
#include "experiments/report/viewer_links.hpp"
#include "framework/problem/problem.hpp"
#include "tests/test_process.hpp"

namespace fs = std::filesystem;
using namespace ndc::report;
using ndc::CsvTable;
using ndc::parseCsv;
using ndc::readCsv;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("report");
  return dir.path();
}

std::string slurp(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void spit(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << text;
}

/// The columns `ndcontour experiment` writes (experiment.hpp), in order.
const std::vector<std::string> kColumns = {"experiment",
                                           "run",
                                           "problem",
                                           "problem_file",
                                           "n",
                                           "k",
                                           "depth",
                                           "seed",
                                           "scalar",
                                           "precision_bits",
                                           "bounding",
                                           "subdivision",
                                           "projection",
                                           "classification",
                                           "connection",
                                           "status",
                                           "exit_code",
                                           "error",
                                           "expect_components",
                                           "expect_euler_characteristic",
                                           "cells.visited",
                                           "cells.solution",
                                           "cells.normal",
                                           "cells.abnormal",
                                           "cells.failed",
                                           "mesh.vertices",
                                           "mesh.edges",
                                           "mesh.triangles",
                                           "mesh.components",
                                           "mesh.boundary_edges",
                                           "mesh.nonmanifold_edges",
                                           "mesh.euler_characteristic",
                                           "mesh.open_ends",
                                           "mesh.branch_vertices",
                                           "accuracy.max_residual",
                                           "accuracy.max_chord_error",
                                           "diagnostics.ambiguous_cells",
                                           "diagnostics.singular_cells",
                                           "diagnostics.chord_failures",
                                           "timing_s.subdivision",
                                           "timing_s.projection",
                                           "timing_s.connection",
                                           "timing_s.analysis",
                                           "timing_s.total"};

/// A results CSV: the full header (minus `drop`) and one line per row; cells not given are
/// defaults for a successful double run, or empty.
std::string experimentCsv(const std::string& id,
                          const std::vector<std::map<std::string, std::string>>& rows,
                          const std::string& drop = "") {
  const std::map<std::string, std::string> defaults = {{"experiment", id},
                                                       {"n", "2"},
                                                       {"k", "1"},
                                                       {"depth", "5"},
                                                       {"scalar", "double"},
                                                       {"precision_bits", "53"},
                                                       {"bounding", "bernstein"},
                                                       {"subdivision", "binary"},
                                                       {"projection", "newton"},
                                                       {"classification", "paper"},
                                                       {"connection", "crossing"},
                                                       {"status", "ok"},
                                                       {"exit_code", "0"}};
  std::string out;
  bool first = true;
  for (const std::string& c : kColumns)
    if (c != drop) out += (first ? "" : ",") + c, first = false;
  out += "\n";
  for (const auto& row : rows) {
    first = true;
    for (const std::string& c : kColumns) {
      if (c == drop) continue;
      std::string value;
      if (row.count(c))
        value = row.at(c);
      else if (defaults.count(c))
        value = defaults.at(c);
      if (c == "problem_file" && value.empty() && row.count("problem"))
        value = "experiments/problems/" + row.at("problem") + ".toml";
      out += (first ? "" : ",") + value;
      first = false;
    }
    out += "\n";
  }
  return out;
}

/// Two successful runs and one failed run of a bounding ablation on one problem.
const std::vector<std::map<std::string, std::string>> kAblationRows = {
    {{"run", "circle-bernstein"},
     {"problem", "circle"},
     {"bounding", "bernstein"},
     {"cells.visited", "120"},
     {"cells.solution", "40"},
     {"accuracy.max_residual", "2.5e-16"},
     {"timing_s.subdivision", "0.01"},
     {"timing_s.projection", "0.002"},
     {"timing_s.connection", "0.0005"},
     {"timing_s.total", "0.0126"}},
    {{"run", "circle-interval"},
     {"problem", "circle"},
     {"bounding", "interval"},
     {"cells.visited", "300"},
     {"cells.solution", "44"},
     {"accuracy.max_residual", "1e-15"},
     {"timing_s.subdivision", "0.03"},
     {"timing_s.projection", "0.0025"},
     {"timing_s.connection", "0.0005"},
     {"timing_s.total", "0.033"}},
    {{"run", "circle-linearized"},
     {"problem", "circle"},
     {"bounding", "linearized"},
     {"status", "failed"},
     {"exit_code", "1"},
     {"error", "ndcontour: internal error: boom"}}};

}  // namespace

TEST_CASE("CSV: quoted fields, doubled quotes, line breaks in quotes, empty cells, CRLF",
          "[report]") {
  const CsvTable t = parseCsv(
      "a,b,c\r\n"
      "1,\"x, y\",\r\n"
      "\n"
      ",\"say \"\"hi\"\"\",\"two\nlines\"\n"
      "3,,4",
      "t.csv");
  REQUIRE(t.header == std::vector<std::string>{"a", "b", "c"});
  REQUIRE(t.size() == 3);
  CHECK(t.cell(0, "b") == "x, y");
  CHECK(t.cell(0, "c").empty());
  CHECK(t.cell(1, "a").empty());
  CHECK(t.cell(1, "b") == "say \"hi\"");
  CHECK(t.cell(1, "c") == "two\nlines");
  CHECK(t.cell(2, "c") == "4");
  CHECK(t.number(2, "a") == 3);
  CHECK(std::isnan(t.number(2, "b")));  // empty cell: no value
  CHECK_THROWS_WITH(t.number(0, "b"), Catch::Contains("not a number"));
  CHECK_FALSE(t.hasColumn("d"));
  CHECK_THROWS_AS(t.column("d"), ndc::InputError);
  CHECK_THROWS_WITH(t.column("d"), "t.csv: missing column 'd'");
}

TEST_CASE("CSV: malformed input names the file and line", "[report]") {
  CHECK_THROWS_WITH(parseCsv("a,b\n1,\"open\n", "u.csv"), "u.csv:2: unterminated quoted field");
  CHECK_THROWS_WITH(parseCsv("a,b\n1,2\n3\n", "u.csv"), "u.csv:3: row has 1 fields, the header 2");
  CHECK_THROWS_WITH(parseCsv("a,a\n", "u.csv"), "u.csv:1: duplicate column 'a'");
  CHECK_THROWS_WITH(parseCsv("a,\"b\"x\n", "u.csv"), "u.csv:1: text after a closing quote");
  CHECK_THROWS_WITH(parseCsv("", "u.csv"), "u.csv:1: no header line");
  CHECK_THROWS_WITH(readCsv(scratch() / "absent.csv"), Catch::Contains("cannot read"));
}

TEST_CASE("Aggregation: mean, spread, groups in order of appearance, log-log slope", "[report]") {
  const std::vector<double> v = {4, 1, std::nan(""), 3, 2};
  const Stats s = summarize(v);
  CHECK(s.count == 4);
  CHECK(s.mean == Approx(2.5));
  CHECK(s.stddev == Approx(std::sqrt(5.0 / 3.0)));
  CHECK(s.min == 1);
  CHECK(s.max == 4);
  CHECK(s.median == Approx(2.5));
  CHECK(summarize(std::vector<double>{7}).stddev == 0);
  CHECK(std::isnan(summarize(std::vector<double>{}).mean));

  const CsvTable t = parseCsv("g,h,x\nb,1,10\na,1,20\nb,2,30\nb,1,40\n", "g.csv");
  const std::vector<std::string> keys = {"g", "h"};
  const std::vector<Group> groups = groupBy(t, keys);
  REQUIRE(groups.size() == 3);
  CHECK(groups[0].key == std::vector<std::string>{"b", "1"});
  CHECK(groups[0].rows == std::vector<std::size_t>{0, 3});
  CHECK(groups[1].key == std::vector<std::string>{"a", "1"});
  CHECK(summarize(values(t, groups[0].rows, "x")).mean == Approx(25));
  const std::vector<std::string> candidates = {"g", "h", "absent"};
  CHECK(varyingColumns(t, candidates) == std::vector<std::string>{"g", "h"});
  const std::vector<std::string> bad = {"nope"};
  CHECK_THROWS_WITH(groupBy(t, bad), "g.csv: missing column 'nope'");

  const std::vector<double> h = {0.5, 0.25, 0.125}, e = {0.1, 0.025, 0.00625};
  CHECK(logLogSlope(h, e) == Approx(2.0));
  CHECK(std::isnan(logLogSlope(std::vector<double>{1}, std::vector<double>{1})));
}

TEST_CASE("Numbers print with fixed significant digits", "[report]") {
  CHECK(formatNumber(120) == "120");
  CHECK(formatNumber(-3) == "-3");
  CHECK(formatNumber(0.0126, 2) == "0.013");
  CHECK(formatNumber(0.002, 2) == "0.0020");
  CHECK(formatNumber(1.5e-16, 2) == "1.5e-16");
  CHECK(formatNumber(2.5e7 + 0.5, 3) == "2.50e7");
  CHECK(formatNumber(std::nan("")) == "\u2013");
  CHECK(formatFixed(40.8123, 1) == "40.8");
}

TEST_CASE("Tables: Markdown and LaTeX text, with escaping", "[report]") {
  Table t;
  t.id = "tab-x";
  t.caption = "Shares in % of a_b";
  t.columns = {"name", "share %"};
  t.align = "lr";
  t.rows = {{"a|b & c", "40.8"}, {"d_e", formatNumber(std::nan(""))}};
  CHECK(toMarkdown(t) ==
        "| name | share % |\n"
        "|---|--:|\n"
        "| a\\|b & c | 40.8 |\n"
        "| d_e | \u2013 |\n");
  CHECK(toLatex(t) ==
        "% Generated by `ndcontour report` from results/tab-x/tab-x.csv: do not edit.\n"
        "\\begin{table}[htbp]\n"
        "  \\centering\n"
        "  \\caption{Shares in \\% of a\\_b}\n"
        "  \\label{tab-x}\n"
        "  \\small\\setlength{\\tabcolsep}{4pt}\n"
        "  \\resizebox{\\ifdim\\width>\\linewidth\\linewidth\\else\\width\\fi}{!}{%\n"
        "  \\begin{tabular}{lr}\n"
        "    \\toprule\n"
        "    name & share \\% \\\\\n"
        "    \\midrule\n"
        "    a|b \\& c & 40.8 \\\\\n"
        "    d\\_e & -- \\\\\n"
        "    \\bottomrule\n"
        "  \\end{tabular}}\n"
        "\\end{table}\n");
  CHECK(latexEscape("~^\\#$") == "\\textasciitilde{}\\textasciicircum{}\\textbackslash{}\\#\\$");
}

TEST_CASE("An ablation table from a hand-written CSV matches exactly", "[report]") {
  const CsvTable csv =
      parseCsv(experimentCsv("tab-ablation-bounding", kAblationRows), "ablation.csv");
  const Artefact a = buildArtefact("tab-ablation-bounding", csv, scratch());
  CHECK_FALSE(a.figure);
  CHECK(a.runs == 3);
  REQUIRE(a.failures.size() == 1);
  CHECK(a.failures[0] ==
        "run `circle-linearized` (problem circle, depth 5): failed, exit 1: ndcontour: internal "
        "error: boom");
  REQUIRE(a.tables.size() == 1);
  CHECK(toMarkdown(a.tables[0]) ==
        "| problem | n | k | bounding | visited | solution | max residual | subdivision s | "
        "projection s | connection s | total s |\n"
        "|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|\n"
        "| circle | 2 | 1 | bernstein | 120 | 40 | 2.5e-16 | 0.010 | 0.0020 | 5.0e-4 | 0.013 |\n"
        "| circle | 2 | 1 | interval | 300 | 44 | 1.0e-15 | 0.030 | 0.0025 | 5.0e-4 | 0.033 |\n");
  CHECK(toLatex(a.tables[0]) ==
        "% Generated by `ndcontour report` from "
        "results/tab-ablation-bounding/tab-ablation-bounding.csv: do not edit.\n"
        "\\begin{table}[htbp]\n"
        "  \\centering\n"
        "  \\caption{Ablation of the bounding strategy: cells visited and kept, largest "
        "residual, seconds per stage (mean over seeds).}\n"
        "  \\label{tab-ablation-bounding}\n"
        "  \\small\\setlength{\\tabcolsep}{4pt}\n"
        "  \\resizebox{\\ifdim\\width>\\linewidth\\linewidth\\else\\width\\fi}{!}{%\n"
        "  \\begin{tabular}{lrrlrrrrrrr}\n"
        "    \\toprule\n"
        // More than eight columns: titles of two words on two lines.
        "    problem & n & k & bounding & visited & solution & "
        "\\begin{tabular}[b]{@{}c@{}}max\\\\residual\\end{tabular} & "
        "\\begin{tabular}[b]{@{}c@{}}subdivision\\\\s\\end{tabular} & "
        "\\begin{tabular}[b]{@{}c@{}}projection\\\\s\\end{tabular} & "
        "\\begin{tabular}[b]{@{}c@{}}connection\\\\s\\end{tabular} & "
        "\\begin{tabular}[b]{@{}c@{}}total\\\\s\\end{tabular} \\\\\n"
        "    \\midrule\n"
        "    circle & 2 & 1 & bernstein & 120 & 40 & 2.5e-16 & 0.010 & 0.0020 & 5.0e-4 & 0.013 "
        "\\\\\n"
        "    circle & 2 & 1 & interval & 300 & 44 & 1.0e-15 & 0.030 & 0.0025 & 5.0e-4 & 0.033 "
        "\\\\\n"
        "    \\bottomrule\n"
        "  \\end{tabular}}\n"
        "\\end{table}\n");
  // The sentence is computed from the data: 300 / 120 cells, 0.033 / 0.0126 seconds.
  REQUIRE_FALSE(a.sentences.empty());
  CHECK_THAT(a.sentences[0], Catch::Contains("`interval` visits 2.50 times the cells of "
                                             "`bernstein` and takes 2.62 times its total time"));
}

TEST_CASE("Table 1 sets our counts beside the paper's and lists paper rows we lack", "[report]") {
  const std::vector<std::map<std::string, std::string>> rows = {{{"run", "a"},
                                                                 {"problem", "bisector-fig8a"},
                                                                 {"n", "4"},
                                                                 {"k", "2"},
                                                                 {"cells.normal", "300"},
                                                                 {"cells.abnormal", "100"},
                                                                 {"cells.failed", "0"}},
                                                                {{"run", "b"},
                                                                 {"problem", "blending-fig10a"},
                                                                 {"n", "6"},
                                                                 {"k", "2"},
                                                                 {"cells.normal", "100"},
                                                                 {"cells.abnormal", "300"},
                                                                 {"cells.failed", "0"}}};
  const CsvTable csv = parseCsv(experimentCsv("tab1-degeneracy", rows), "t1.csv");
  const Artefact a = buildArtefact("tab1-degeneracy", csv, scratch());
  REQUIRE(a.tables.size() == 1);
  const Table& t = a.tables[0];
  REQUIRE(t.rows.size() == 6);  // the paper's six examples, in its order
  CHECK(t.rows[0] == std::vector<std::string>{"Bisector, Fig. 8(a)", "bisector-fig8a", "4", "5",
                                              "300", "100", "25.0", "444", "306", "40.8"});
  CHECK(t.rows[1][1] == "(no result)");
  CHECK(t.rows[4][1] == "blending-fig10a");
  CHECK(t.rows[4][6] == "75.0");
  REQUIRE_FALSE(a.sentences.empty());
  CHECK(a.sentences[0] ==
        "Our abnormal share ranges from 25.0% (bisector-fig8a) to 75.0% (blending-fig10a); the "
        "paper's from 24.2% (sweep, Fig. 9(b)) to 69.2% (bisector, Fig. 8(b)).");
}

TEST_CASE("The paper's reference figures are read from a file; a bad one is a one-line error",
          "[report]") {
  const std::vector<std::map<std::string, std::string>> rows = {{{"run", "a"},
                                                                 {"problem", "bisector-fig8b"},
                                                                 {"n", "4"},
                                                                 {"k", "2"},
                                                                 {"cells.normal", "100"},
                                                                 {"cells.abnormal", "300"},
                                                                 {"cells.failed", "0"}}};
  const CsvTable csv = parseCsv(experimentCsv("tab1-degeneracy", rows), "t1.csv");
  const fs::path root = scratch() / "reference-file";
  // The configs directory's sibling reference/ is used when it exists.
  fs::create_directories(root / "configs");
  spit(root / "reference" / "table1.toml",
       "[[row]]\nkey = \"fig8b\"\nlabel = \"Bisector, Fig. 8(b)\"\nfamily = \"bisector\"\n"
       "n = 4\nnormal = 10\nabnormal = 30\nshare = 75.0\n");
  CHECK(referenceDir(root / "configs") == root / "reference");
  const Artefact a = buildArtefact("tab1-degeneracy", csv, scratch(), root / "reference");
  REQUIRE(a.tables.size() == 1);
  REQUIRE(a.tables[0].rows.size() == 1);
  CHECK(a.tables[0].rows[0].back() == "75.0");
  // The repository's own file holds the paper's six examples.
  CHECK(buildArtefact("tab1-degeneracy", csv, scratch(),
                      fs::path(NDC_SOURCE_DIR) / "experiments" / "reference")
            .tables[0]
            .rows.size() == 6);
  // Missing, not TOML, or a row without a number: InputError naming the file.
  const auto error = [&](const fs::path& dir) {
    try {
      buildArtefact("tab1-degeneracy", csv, scratch(), dir);
    } catch (const ndc::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(error(root / "nowhere"),
             Catch::Contains("table1.toml") && Catch::Contains("reference figures are missing"));
  spit(root / "bad" / "table1.toml", "[[row]\nkey = 1\n");
  CHECK_THAT(error(root / "bad"), Catch::Contains("table1.toml") && Catch::Contains("TOML"));
  spit(root / "bad" / "table1.toml", "[[row]]\nkey = \"fig8a\"\nlabel = \"x\"\n");
  CHECK_THAT(error(root / "bad"), Catch::Contains("row 1"));
  CHECK(error(root / "bad").find('\n') == std::string::npos);
}

TEST_CASE("The report names failed runs and missing experiments and still writes", "[report]") {
  const fs::path results = scratch() / "failed" / "results";
  const fs::path configs = scratch() / "failed" / "configs";
  spit(results / "tab-ablation-bounding" / "tab-ablation-bounding.csv",
       experimentCsv("tab-ablation-bounding", kAblationRows));
  spit(configs / "tab-ablation-bounding.toml", "# config\n");
  spit(configs / "fig-app-sweep.toml", "# config\n");
  std::ostringstream log;
  ReportSettings settings;
  settings.results = results;
  settings.configs = configs;
  settings.render = false;
  const ReportOutcome outcome = writeReport(settings, log);
  CHECK(outcome.status == 1);
  CHECK(outcome.failedRuns == 1);
  CHECK(outcome.errors.empty());
  CHECK(outcome.written == std::vector<std::string>{"tab-ablation-bounding"});
  // Every known artefact but the ablation is missing, and so is the configured application.
  CHECK(std::find(outcome.missing.begin(), outcome.missing.end(), "fig-app-sweep") !=
        outcome.missing.end());
  CHECK(std::find(outcome.missing.begin(), outcome.missing.end(), "tab1-degeneracy") !=
        outcome.missing.end());
  const std::string report = slurp(results / "report.md");
  CHECK_THAT(report, Catch::Contains("| [tab-ablation-bounding](#tab-ablation-bounding) | table "
                                     "| 3 | 1 | 1 failed |"));
  CHECK_THAT(report, Catch::Contains("- run `circle-linearized` (problem circle, depth 5): "
                                     "failed, exit 1: ndcontour: internal error: boom"));
  CHECK_THAT(report, Catch::Contains("Failed runs over all experiments: 1"));
  CHECK_THAT(report, Catch::Contains("Missing experiments: tab1-degeneracy"));
  CHECK_THAT(report, Catch::Contains("fig-app-sweep"));
  CHECK(fs::exists(results / "tab-ablation-bounding" / "tab-ablation-bounding.md"));
  CHECK(fs::exists(results / "tab-ablation-bounding" / "tab-ablation-bounding.tex"));
}

TEST_CASE("A missing column is a clear error that leaves earlier outputs alone", "[report]") {
  const fs::path results = scratch() / "missing-column" / "results";
  const fs::path dir = results / "tab1-degeneracy";
  spit(dir / "tab1-degeneracy.csv",
       experimentCsv("tab1-degeneracy", {{{"run", "a"}, {"problem", "bisector-fig8a"}}},
                     "cells.abnormal"));
  spit(dir / "tab1-degeneracy.md", "good old table\n");
  std::ostringstream log;
  ReportSettings settings;
  settings.results = results;
  settings.configs = scratch() / "missing-column" / "configs";
  settings.render = false;
  const ReportOutcome outcome = writeReport(settings, log);
  CHECK(outcome.status == 2);
  REQUIRE(outcome.errors.size() == 1);
  CHECK(outcome.errors[0] ==
        (dir / "tab1-degeneracy.csv").string() + ": missing column 'cells.abnormal'");
  CHECK(slurp(dir / "tab1-degeneracy.md") == "good old table\n");
  CHECK_FALSE(fs::exists(dir / "tab1-degeneracy.tex"));
  CHECK_THAT(slurp(results / "report.md"), Catch::Contains("missing column 'cells.abnormal'"));

  settings.results = scratch() / "no-such-dir";
  CHECK_THROWS_AS(writeReport(settings, log), ndc::InputError);
}

TEST_CASE("Figures: a gnuplot script with inline data, rendered when gnuplot exists", "[report]") {
  std::vector<std::map<std::string, std::string>> rows;
  for (int n : {2, 3, 4})
    for (int seed : {1, 2}) {
      const std::string name = "rotated-circle-n" + std::to_string(n) + "-s" + std::to_string(seed);
      rows.push_back({{"run", name},
                      {"problem", name},
                      {"n", std::to_string(n)},
                      {"seed", std::to_string(seed)},
                      {"cells.normal", "100"},
                      {"cells.abnormal", std::to_string(20 * n + seed)}});
    }
  const fs::path results = scratch() / "figure" / "results";
  spit(results / "fig-degeneracy-vs-n" / "fig-degeneracy-vs-n.csv",
       experimentCsv("fig-degeneracy-vs-n", rows));
  const CsvTable csv = readCsv(results / "fig-degeneracy-vs-n" / "fig-degeneracy-vs-n.csv");
  const Artefact a = buildArtefact("fig-degeneracy-vs-n", csv, results / "fig-degeneracy-vs-n");
  CHECK(a.figure);
  CHECK_THAT(a.gnuplot, Catch::Contains("$s0mean << EOD\n2 29.3277395 29.0780142 29.5774648"));
  CHECK_THAT(a.gnuplot, Catch::Contains("with yerrorlines"));
  REQUIRE_FALSE(a.sentences.empty());
  CHECK_THAT(a.sentences[0], Catch::StartsWith("For k = 1 the abnormal share rises from 29.3% at "
                                               "n = 2 to 44.9% at n = 4, increasing at every "
                                               "step"));
  if (!gnuplotAvailable()) return;
  std::ostringstream log;
  ReportSettings settings;
  settings.results = results;
  settings.configs = scratch() / "figure" / "configs";
  writeReport(settings, log);
  CHECK(fs::file_size(results / "fig-degeneracy-vs-n" / "fig-degeneracy-vs-n.png") > 1000);
  CHECK(fs::file_size(results / "fig-degeneracy-vs-n" / "fig-degeneracy-vs-n.pdf") > 1000);
  CHECK_FALSE(fs::exists(results / "fig-degeneracy-vs-n" / "fig-degeneracy-vs-n.tmp.png"));
}

TEST_CASE("fig-degeneracy-vs-n-k3: one series per depth and no paper points", "[report]") {
  std::vector<std::map<std::string, std::string>> rows;
  for (int n : {4, 5, 6})
    for (int depth : {3, 4})
      for (int jitter : {1, 2}) {
        const std::string name = "sphere3-r" + std::to_string(n);
        rows.push_back({{"run", name + ".L" + std::to_string(depth) + ".j" + std::to_string(jitter)},
                        {"problem", name},
                        {"n", std::to_string(n)},
                        {"k", "3"},
                        {"depth", std::to_string(depth)},
                        {"cells.normal", "100"},
                        {"cells.abnormal", std::to_string(10 * n + depth + jitter)}});
      }
  const CsvTable csv = parseCsv(experimentCsv("fig-degeneracy-vs-n-k3", rows), "k3.csv");
  const Artefact a = buildArtefact("fig-degeneracy-vs-n-k3", csv, scratch());
  CHECK(a.figure);
  CHECK_THAT(a.gnuplot, Catch::Contains("k = 3, depth=3: mean"));
  CHECK_THAT(a.gnuplot, Catch::Contains("k = 3, depth=4: mean"));
  CHECK_THAT(a.gnuplot, !Catch::Contains("$paper"));
  REQUIRE(a.sentences.size() == 4);  // per depth: the trend and the paper's observation
  CHECK_THAT(a.sentences[0], Catch::StartsWith("For k = 3, depth=3 the abnormal share rises"));
  REQUIRE(a.tables.size() == 1);
  CHECK(a.tables[0].rows.size() == 6);  // 2 depths x 3 n
}

TEST_CASE("Table 1's main columns are the paper's settings; the others are extra columns",
          "[report]") {
  // One problem under four settings: only bernstein + paper may fill the main columns.
  std::vector<std::map<std::string, std::string>> rows;
  const std::map<std::string, std::pair<int, int>> counts = {{"bernstein paper", {300, 100}},
                                                             {"bernstein crossing", {300, 100}},
                                                             {"linearized paper", {300, 60}},
                                                             {"linearized crossing", {300, 60}}};
  for (const auto& [setting, nc] : counts) {
    const std::string bounding = setting.substr(0, setting.find(' '));
    const std::string connection = setting.substr(setting.find(' ') + 1);
    rows.push_back({{"run", "fig8a-" + bounding + "-" + connection},
                    {"problem", "bisector-fig8a"},
                    {"n", "4"},
                    {"k", "2"},
                    {"bounding", bounding},
                    {"connection", connection},
                    {"cells.normal", std::to_string(nc.first)},
                    {"cells.abnormal", std::to_string(nc.second)},
                    {"cells.failed", "0"}});
  }
  const CsvTable csv = parseCsv(experimentCsv("tab1-degeneracy", rows), "t1.csv");
  const Artefact a = buildArtefact("tab1-degeneracy", csv, scratch());
  REQUIRE(a.tables.size() == 1);
  const Table& t = a.tables[0];
  CHECK(t.columns == std::vector<std::string>{"example", "problem", "n", "depth", "normal",
                                              "abnormal", "abnormal %", "abnormal % linearized",
                                              "abnormal % crossing", "paper normal",
                                              "paper abnormal", "paper abnormal %"});
  CHECK_THAT(t.caption, Catch::Contains("ours with bounding bernstein, connection paper"));
  // 100 / 400 = 25.0% with bernstein; 60 / 360 = 16.7% with linearized.
  CHECK(t.rows[0] == std::vector<std::string>{"Bisector, Fig. 8(a)", "bisector-fig8a", "4", "5",
                                              "300", "100", "25.0", "16.7", "25.0", "444", "306",
                                              "40.8"});
  CHECK(t.rows[1][1] == "(no result)");
  CHECK(t.rows[1].size() == t.columns.size());
  // The bar chart: ours, the two extra settings and the paper's share per example.
  CHECK_THAT(a.gnuplot, Catch::Contains("$bars << EOD\n0 25 16.6666667 25 40.8\n"));
  CHECK_THAT(a.gnuplot, Catch::Contains("with boxes"));
  REQUIRE_FALSE(a.conclusion.empty());
  CHECK_THAT(a.conclusion[0],
             Catch::StartsWith("In Table 1: our abnormal share ranges from 25.0%"));
}

TEST_CASE("Curve data for splot: polylines chained, two blank lines between them", "[report]") {
  // Two polylines: an open chain 0-1-2 (given out of order) and a closed triangle 3-4-5.
  const std::vector<std::vector<int>> segments = {{1, 2}, {3, 4}, {0, 1}, {4, 5}, {5, 3}};
  const std::vector<std::vector<int>> lines = chainSegments(segments);
  REQUIRE(lines.size() == 2);
  CHECK((lines[0] == std::vector<int>{0, 1, 2} || lines[0] == std::vector<int>{2, 1, 0}));
  CHECK(lines[1].size() == 4);
  CHECK(lines[1].front() == lines[1].back());
  std::vector<std::array<double, 3>> points;
  for (int v = 0; v < 6; ++v) points.push_back({double(v), 0, 0});
  GnuplotScript gp("fig-x");
  gp.data("curve", polylineRows(lines, points));
  const std::string text = gp.text();
  const std::string block = text.substr(text.find("$curve << EOD\n"));
  // Each polyline is its own data set: never one blank line between two polylines.
  CHECK_THAT(block, Catch::Contains("2 0 0\n\n\n"));
  CHECK(block.find("\n\n\n\n") == std::string::npos);
  const std::size_t body = block.find('\n') + 1, end = block.find("EOD\n", body);
  std::string data = block.substr(body, end - body);
  for (std::size_t at = data.find("\n\n\n"); at != std::string::npos; at = data.find("\n\n\n"))
    data.replace(at, 3, "\n#\n");
  CHECK(data.find("\n\n") == std::string::npos);
}

namespace {

/// An ASCII mesh.ply of `points` and `edges` (a curve result).
std::string asciiCurvePly(const std::vector<std::array<double, 3>>& points,
                          const std::vector<std::array<int, 2>>& edges) {
  std::string out = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(points.size()) +
                    "\nproperty double x\nproperty double y\nproperty double z\nelement edge " +
                    std::to_string(edges.size()) +
                    "\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  for (const auto& p : points)
    out += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
  for (const auto& e : edges) out += std::to_string(e[0]) + " " + std::to_string(e[1]) + "\n";
  return out;
}

}  // namespace

TEST_CASE("Application figures: curves as separate polylines, titled by the problem name",
          "[report]") {
  const fs::path dir = scratch() / "application" / "results" / "fig-app-curves";
  // Two separate segments of two points each: with one blank line splot would join them.
  spit(dir / "runs" / "two-arcs.L5" / "mesh.ply",
       asciiCurvePly({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{{0, 1}}, {{2, 3}}}));
  const std::vector<std::map<std::string, std::string>> rows = {{{"run", "two-arcs.L5"},
                                                                 {"problem", "two-arcs"},
                                                                 {"n", "3"},
                                                                 {"k", "1"},
                                                                 {"mesh.vertices", "4"},
                                                                 {"mesh.components", "2"},
                                                                 {"mesh.euler_characteristic", "2"},
                                                                 {"mesh.boundary_edges", "0"},
                                                                 {"mesh.nonmanifold_edges", "0"},
                                                                 {"accuracy.max_residual", "1e-12"},
                                                                 {"timing_s.total", "0.1"}}};
  const CsvTable csv = parseCsv(experimentCsv("fig-app-curves", rows), "app.csv");
  const Artefact a = buildArtefact("fig-app-curves", csv, dir);
  CHECK_THAT(a.gnuplot, Catch::Contains("$mesh0 << EOD\n0 0 0\n1 0 0\n\n\n0 1 0\n1 1 0\n\n\nEOD"));
  CHECK_THAT(a.gnuplot, Catch::Contains("set title \"two-arcs (n = 3, depth 5)\""));
  CHECK(a.gnuplot.find(dir.string()) == std::string::npos);
  // The per-run scripts title their pictures with the problem name, not the results path.
  for (const auto& e :
       fs::directory_iterator(fs::path(NDC_SOURCE_DIR) / "experiments" / "gnuplot")) {
    std::istringstream script(slurp(e.path()));
    for (std::string line; std::getline(script, line);)
      if (line.find("title") != std::string::npos && line.find("set ") != std::string::npos)
        CHECK_FALSE(line.find(".dir") != std::string::npos);
  }
}

TEST_CASE("Convergence: the x axis spans the data's cell sizes", "[report]") {
  std::vector<std::map<std::string, std::string>> rows;
  for (int depth : {3, 4, 5, 6})
    rows.push_back({{"run", "circle-" + std::to_string(depth)},
                    {"problem", "circle"},
                    {"depth", std::to_string(depth)},
                    {"accuracy.max_chord_error", std::to_string(std::ldexp(1.0, -2 * depth))},
                    {"accuracy.max_residual", "1e-15"},
                    {"cells.solution", std::to_string(1 << depth)},
                    {"timing_s.total", "0.01"}});
  const CsvTable csv = parseCsv(experimentCsv("fig-convergence", rows), "c.csv");
  const Artefact a = buildArtefact("fig-convergence", csv, scratch());
  // h from 2^-6 to 2^-3, a quarter beyond: not on to 1.
  CHECK_THAT(a.gnuplot, Catch::Contains("set xrange [0.01250:0.1562]"));
  REQUIRE(a.conclusion.size() == 1);
  CHECK_THAT(a.conclusion[0], Catch::Contains("the chord error falls with order 2.00"));
  CHECK_THAT(a.conclusion[0], Catch::Contains("the cells of curves grow with order 1.00"));
}

TEST_CASE("The conclusion fragment is computed from the results", "[report]") {
  const fs::path results = scratch() / "conclusion" / "results";
  const std::vector<std::map<std::string, std::string>> rows = {
      {{"run", "a"},
       {"problem", "blending-fig10a"},
       {"n", "6"},
       {"k", "2"},
       {"connection", "paper"},
       {"cells.normal", "120"},
       {"cells.abnormal", "280"},
       {"cells.failed", "0"}},
      {{"run", "b"}, {"problem", "bisector-fig8b"}, {"status", "failed"}, {"exit_code", "1"}}};
  spit(results / "tab1-degeneracy" / "tab1-degeneracy.csv", experimentCsv("tab1-degeneracy", rows));
  std::ostringstream log;
  ReportSettings settings;
  settings.results = results;
  settings.configs = scratch() / "conclusion" / "configs";
  settings.reference = fs::path(NDC_SOURCE_DIR) / "experiments" / "reference";
  settings.render = false;
  writeReport(settings, log);
  const std::string conclusion = slurp(results / "conclusion.tex");
  CHECK_THAT(conclusion, Catch::Contains("We ran 2 runs in 1 experiment, of which 1 failed"));
  // 280 / 400 = 70.0% for blending-fig10a, beside the paper's 59.2% (Fig. 10(a)).
  CHECK_THAT(conclusion, Catch::Contains("70.0\\%"));
  CHECK_THAT(conclusion, Catch::Contains("blending (n = 6) 70.0\\%"));
  CHECK_THAT(slurp(results / "report.md"), Catch::Contains("## Conclusion"));
}

TEST_CASE("Viewer links: one row per problem, a short link per run", "[report]") {
  std::vector<std::map<std::string, std::string>> rows;
  for (const std::string problem : {"circle", "torus"})
    for (const std::string connection : {"paper", "crossing"})
      rows.push_back({{"run", problem + ".L5." + connection},
                      {"problem", problem},
                      {"connection", connection}});
  const CsvTable csv = parseCsv(experimentCsv("tab-connection", rows), "links.csv");
  // Every run but torus.L5.paper has a page.
  const std::string md = viewerLinkTable(
      csv, [](const std::string& run) { return run != "torus.L5.paper"; }, "tab-connection/runs/");
  CHECK_THAT(md, Catch::Contains("(`ndcontour view`, 3 pages):\n\n| problem | 3-D views |\n"));
  CHECK_THAT(md, Catch::Contains("| circle | [paper](tab-connection/runs/circle.L5.paper/view.html)"
                                 " · [crossing](tab-connection/runs/circle.L5.crossing/"
                                 "view.html) |\n"));
  CHECK_THAT(md, Catch::Contains("| torus | [crossing](tab-connection/runs/torus.L5.crossing/"
                                 "view.html) |\n"));
  // The link texts are the varying settings, never the long run ids.
  CHECK(md.find("[circle.L5") == std::string::npos);
  CHECK(viewerLinkTable(
            csv, [](const std::string&) { return false; }, "x/")
            .empty());

  // Depths and jitter seeds tell runs apart too; a lone run per problem is a plain "view".
  const CsvTable depths =
      parseCsv(experimentCsv("fig-convergence",
                             {{{"run", "a4"}, {"problem", "a"}, {"depth", "4"}},
                              {{"run", "a5"}, {"problem", "a"}, {"depth", "5"}},
                              {{"run", "a5j1"}, {"problem", "a"}, {"depth", "5"}, {"seed", "1"}}}),
               "depths.csv");
  CHECK_THAT(viewerLinkTable(
                 depths, [](const std::string&) { return true; }, ""),
             Catch::Contains("| a | [L4](a4/view.html) · [L5](a5/view.html) · "
                             "[L5 j1](a5j1/view.html) |"));
  const CsvTable one = parseCsv(experimentCsv("x", {{{"run", "b1"}, {"problem", "b"}}}), "one.csv");
  CHECK_THAT(viewerLinkTable(
                 one, [](const std::string&) { return true; }, "x/runs/"),
             Catch::Contains("| b | [view](x/runs/b1/view.html) |"));
}

TEST_CASE("tab-connection counts runs without an expectation apart, never as wrong", "[report]") {
  // a: right; b: Euler characteristic wrong; c: no expectation; d: components only.
  const auto run = [](std::string name, std::string c, std::string e, std::string gotC,
                      std::string gotE) {
    return std::map<std::string, std::string>{{"run", name},
                                              {"problem", name},
                                              {"expect_components", c},
                                              {"expect_euler_characteristic", e},
                                              {"mesh.components", gotC},
                                              {"mesh.euler_characteristic", gotE},
                                              {"mesh.open_ends", "0"},
                                              {"mesh.boundary_edges", "0"},
                                              {"mesh.nonmanifold_edges", "0"},
                                              {"accuracy.max_chord_error", "0.001"}};
  };
  const CsvTable csv = parseCsv(
      experimentCsv("tab-connection", {run("a", "1", "0", "1", "0"), run("b", "1", "2", "1", "0"),
                                       run("c", "", "", "2", "2"), run("d", "1", "", "1", "4")}),
      "connection.csv");
  const Artefact a = buildArtefact("tab-connection", csv, scratch());
  REQUIRE(a.tables.size() == 2);
  const std::string scores = toMarkdown(a.tables[0]);
  CHECK_THAT(scores,
             Catch::Contains("| crossing | 4 | 0 | 3/3 (100%), 1 not comparable | "
                             "1/2 (50%), 2 not comparable | 1/2 (50%), 2 not comparable |"));
  // Per problem: the run without an expectation is not marked wrong.
  const std::string detail = toMarkdown(a.tables[1]);
  CHECK_THAT(detail, Catch::Contains("| c | 2 | 1 | ? / ? | 2 / 2 |"));
  CHECK_THAT(detail, Catch::Contains("| b | 2 | 1 | 1 / 2 | 1 / 0 * |"));
  REQUIRE_FALSE(a.sentences.empty());
  CHECK_THAT(a.sentences[0], Catch::Contains("`crossing` 1 of 2 (2 not comparable)"));
}

TEST_CASE("Application figures are lit and free of stripes; legends sit off the data", "[report]") {
  // A triangle's pm3d grid a b / c m: m, the midpoint of b and c, gives lighting a normal.
  ndc::PlyMesh triangle;
  triangle.xyz = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  triangle.simplices = {{0, 1, 2}};
  const View front = orthographicView(90, 0);  // gnuplot's `set view 90, 0`: from -y
  CHECK(front.toViewer[1] == Approx(-1));
  CHECK(std::abs(front.toViewer[0]) + std::abs(front.toViewer[2]) < 1e-12);
  using Rows = std::vector<std::vector<double>>;
  CHECK(trianglePm3d(triangle, front) ==
        Rows{{0, 0, 0}, {2, 0, 0}, {}, {0, 2, 0}, {1, 1, 0}, {}, {}});
  // Pushed back: away from the viewer along the view direction, the same place in the picture.
  const std::vector<double> pushed = trianglePm3d(triangle, front, 0.5)[0];
  CHECK(pushed[0] == Approx(0).margin(1e-12));
  CHECK(pushed[1] == Approx(0.5));
  CHECK(pushed[2] == Approx(0).margin(1e-12));

  // The report's figure of a surface result: lit, depth-sorted, the legend outside.
  const fs::path dir = scratch() / "application-lit" / "results" / "fig-app-patch";
  spit(dir / "runs" / "patch.L5" / "mesh.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
       "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n2 0 0\n0 2 0\n3 0 1 2\n");
  std::map<std::string, std::string> row = {{"run", "patch.L5"},
                                            {"problem", "patch"},
                                            {"n", "3"},
                                            {"k", "2"},
                                            {"mesh.vertices", "3"},
                                            {"mesh.components", "1"},
                                            {"mesh.euler_characteristic", "1"},
                                            {"mesh.boundary_edges", "3"},
                                            {"mesh.nonmanifold_edges", "0"},
                                            {"accuracy.max_residual", "1e-12"},
                                            {"timing_s.total", "0.1"}};
  const Artefact a =
      buildArtefact("fig-app-patch", parseCsv(experimentCsv("fig-app-patch", {row}), "p.csv"), dir);
  CHECK_THAT(a.gnuplot, Catch::Contains("set pm3d lighting primary 0.5 specular 0.2"));
  CHECK_THAT(a.gnuplot, Catch::Contains("set pm3d depthorder noborder"));
  CHECK_THAT(a.gnuplot, Catch::Contains("set key outside"));
  CHECK_THAT(a.gnuplot, Catch::Contains("$mesh0 << EOD\n0 0 0\n2 0 0\n\n0 2 0\n1 1 0\n\n\nEOD"));

  // The per-run scripts: every pm3d surface lit, without the borders that drew stripes, and
  // the legend outside the box.
  for (const auto& e :
       fs::directory_iterator(fs::path(NDC_SOURCE_DIR) / "experiments" / "gnuplot")) {
    const std::string script = slurp(e.path());
    INFO(e.path().string());
    CHECK_THAT(script, Catch::Contains("set key outside"));
    if (script.find("with pm3d") == std::string::npos) continue;
    CHECK_THAT(script, Catch::Contains("set pm3d lighting primary 0.5 specular 0.2"));
    CHECK_THAT(script, Catch::Contains("set pm3d depthorder noborder"));
  }
  // ...and scripts/ply2dat.sh --pm3d, which feeds them, writes the same grid.
  const fs::path ply = dir / "runs" / "patch.L5" / "mesh.ply";
  const std::string command = (fs::path(NDC_SOURCE_DIR) / "scripts" / "ply2dat.sh").string() +
                              " --pm3d " + ndc::test::quoted(ply.string());
  std::string out;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
    pclose(pipe);
  }
  CHECK(out == "0 0 0\n2 0 0\n\n0 2 0\n1 1 0\n\n\n");
}
