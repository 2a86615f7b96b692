// The command-line tool as a process (docs/contracts.md 4.2): --help, --version, `info` on every
// example, and every class of bad input exits with status 2 and one line on standard error.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "applications/load.hpp"
#include "experiments/runner/generate.hpp"
#include "framework/io/io.hpp"
#include "framework/problem/problem.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("cli");
  return dir.path();
}

using ndc::test::quoted;
using ndc::test::slurp;
using Run = ndc::test::CliRun;

/// Runs `ndcontour ARGS` (ARGS already shell-quoted) and captures status, stdout and stderr.
Run ndcontour(const std::string& args) { return ndc::test::runNdcontour(args, scratch()); }

/// Writes `text` to a scratch file and returns its path.
fs::path writeProblem(const std::string& name, const std::string& text) {
  const fs::path file = scratch() / name;
  std::ofstream(file) << text;
  return file;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Status 2, nothing on stdout, exactly one line on stderr holding every part.
void checkBadInput(const Run& run, std::initializer_list<std::string> parts) {
  INFO("stderr: " << run.err << "stdout: " << run.out);
  CHECK(run.status == 2);
  CHECK(run.out.empty());
  CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
  CHECK((!run.err.empty() && run.err.back() == '\n'));
  for (const auto& part : parts) CHECK(contains(run.err, part));
}

const std::string kValid =
    "name = \"p\"\nvariables = [\"x\", \"y\"]\ndomain = [[-2, 2], [-2, 2]]\n"
    "equations = [\"x^2 + y^2 - 1\"]\n";

fs::path problemsDir() { return fs::path(ndc::test::sourceDir()) / "experiments" / "problems"; }

}  // namespace

namespace {

/// The options a subcommand's `--help` lists in its option table (not those its texts mention).
std::set<std::string> helpOptions(const std::string& help) {
  static const std::regex row(R"(^\s+(?:-[a-z],)?(--[a-z][a-z-]*))");
  std::set<std::string> options;
  std::istringstream in(help);
  std::smatch m;
  for (std::string line; std::getline(in, line);) {
    if (std::regex_search(line, m, row) && m[1] != "--help") options.insert(m[1]);
  }
  return options;
}

/// The options of the README's usage lines of a subcommand: the lines that start with
/// `build/bin/ndcontour SUB ` and their indented continuation lines.
std::set<std::string> readmeOptions(const std::string& sub) {
  static const std::regex option("--[a-z][a-z-]*");
  std::ifstream in(fs::path(ndc::test::sourceDir()) / "README.md");
  const std::string start = "build/bin/ndcontour " + sub + " ";
  std::set<std::string> options;
  bool usage = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(start, 0) == 0)
      usage = true;
    else if (line.rfind("    ", 0) != 0)
      usage = false;
    if (!usage) continue;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), option);
         it != std::sregex_iterator(); ++it)
      options.insert(it->str());
  }
  return options;
}

}  // namespace

TEST_CASE("cli: the README's usage lines name exactly the options of --help", "[cli]") {
  for (const std::string sub : {"solve", "experiment", "report", "view"}) {
    INFO("ndcontour " << sub);
    const Run help = ndcontour(sub + " --help");
    REQUIRE(help.status == 0);
    const std::set<std::string> listed = helpOptions(help.out);
    CHECK(!listed.empty());  // the parser found the options (view has one: --out)
    CHECK(readmeOptions(sub) == listed);
  }
}

TEST_CASE("cli: --help and --version", "[cli]") {
  const Run help = ndcontour("--help");
  CHECK(help.status == 0);
  CHECK(contains(help.out, "info"));
  CHECK(contains(help.out, "solve"));

  const Run solveHelp = ndcontour("solve --help");
  CHECK(solveHelp.status == 0);
  for (const char* flag :
       {"--depth", "--tolerance", "--bounding", "--subdivision", "--scalar", "--precision",
        "--classification", "--connection", "--jitter", "--out", "--ascii", "--cells", "--json"})
    CHECK(contains(solveHelp.out, flag));
  // The strategy help comes from the registries: models, the default, parameters.
  CHECK(contains(solveHelp.out, "paper, naive, crossing (default)"));
  CHECK(contains(solveHelp.out, "paper:extra_layers=VALUE"));

  const Run version = ndcontour("--version");
  CHECK(version.status == 0);
  CHECK(version.out == std::string("ndcontour ") + NDC_VERSION + "\n");
}

TEST_CASE("cli: info on every example problem", "[cli]") {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(problemsDir())) {
    if (entry.path().extension() != ".toml") continue;
    ++count;
    const ndc::Problem p = ndc::loadProblem(entry.path());
    const Run run = ndcontour("info " + quoted(entry.path().string()));
    INFO(entry.path().string() << "\nstdout:\n" << run.out << "stderr:\n" << run.err);
    CHECK(run.status == 0);
    CHECK(run.err.empty());
    CHECK(contains(run.out, "name: " + p.name + "\n"));
    CHECK(contains(run.out, "\nn: " + std::to_string(p.n()) + "\n"));
    CHECK(contains(run.out, "\nk: " + std::to_string(p.k()) + "\n"));
    CHECK(contains(run.out, "\nm: " + std::to_string(p.m()) + "\n"));
    CHECK(contains(run.out, "components: " + std::to_string(*p.expect.components) + "\n"));
  }
  CHECK(count >= 10);

  // Degrees and coefficient counts of the torus: degree 4 in x, y, z, 5^3 coefficients.
  const Run torus = ndcontour("info " + quoted((problemsDir() / "torus.toml").string()));
  CHECK(contains(torus.out, "(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)"));
  CHECK(contains(torus.out, "degrees: x 4 y 4 z 4"));
  CHECK(contains(torus.out, "coefficients: 125"));
  CHECK(contains(torus.out, "z in [-0.5, 0.5]"));
  CHECK(contains(torus.out, "euler_characteristic: 0"));
}

TEST_CASE("cli: every class of bad problem file exits 2 with one line", "[cli]") {
  struct Case {
    const char* name;
    std::string text;
    std::string part;
  };
  const std::string vars = "name = \"p\"\nvariables = [\"x\", \"y\"]\n";
  const std::string dom = "domain = [[-2, 2], [-2, 2]]\n";
  const std::vector<Case> cases = {
      {"syntax.toml", "name = \"p\"\nvariables = [\"x\" \"y\"]\n", "TOML syntax error"},
      {"missing-key.toml", vars + dom, "missing required key 'equations'"},
      {"unknown-variable.toml", vars + dom + "equations = [\"x^2 + q\"]\n", "equation 1"},
      {"function-call.toml", vars + dom + "equations = [\"sin(x) + y\"]\n", "equation 1"},
      {"non-integer-exponent.toml", vars + dom + "equations = [\"x^2.5 + y\"]\n", "exponent"},
      {"negative-exponent.toml", vars + dom + "equations = [\"x^-1 + y\"]\n", "exponent"},
      {"division.toml", vars + dom + "equations = [\"1/(x + y)\"]\n", "division by a non-constant"},
      {"zero-equations.toml", vars + dom + "equations = []\n", "got 0"},
      {"too-many-equations.toml", vars + dom + "equations = [\"x\", \"y\"]\n", "got 2"},
      {"domain-count.toml", vars + "domain = [[-2, 2]]\nequations = [\"x - y\"]\n",
       "domain has 1 intervals"},
      {"inverted.toml", vars + "domain = [[-2, 2], [3, 2]]\nequations = [\"x - y\"]\n",
       "empty or inverted"},
      {"nan.toml", vars + "domain = [[nan, 2], [0, 2]]\nequations = [\"x - y\"]\n",
       "must be finite"},
      {"inf.toml", vars + "domain = [[0, inf], [0, 2]]\nequations = [\"x - y\"]\n",
       "must be finite"},
      {"bad-name.toml", "name = \"Bad Name\"\n", "must match [a-z0-9._-]+"},
      {"unknown-key.toml", kValid + "colour = \"red\"\n", "unknown key 'colour'"},
      {"wrong-type.toml", "name = \"p\"\nvariables = \"x y\"\n", "variables must be an array"},
      {"one-variable.toml", "name = \"p\"\nvariables = [\"x\"]\n", "at least 2 variables"},
      {"application.toml", "application = \"bisector\"\n" + kValid, "in an application problem"},
      {"duplicate-variable.toml", "name = \"p\"\nvariables = [\"x\", \"x\"]\n", "listed twice"},
  };
  for (const Case& c : cases) {
    const fs::path file = writeProblem(c.name, c.text);
    INFO(c.name);
    for (const char* command : {"info ", "solve "}) {
      checkBadInput(ndcontour(command + quoted(file.string())), {file.string() + ":", c.part});
    }
  }

  // Positions: the TOML error's line and column, and an expression error's file column.
  const fs::path syntax = scratch() / "syntax.toml";
  CHECK(contains(ndcontour("info " + quoted(syntax.string())).err, syntax.string() + ":2:"));
  const fs::path unknown = scratch() / "unknown-variable.toml";
  CHECK(contains(ndcontour("info " + quoted(unknown.string())).err, unknown.string() + ":4:21:"));
}

TEST_CASE("cli: unreadable problem files exit 2 with one line", "[cli]") {
  const fs::path missing = scratch() / "no-such-problem.toml";
  checkBadInput(ndcontour("info " + quoted(missing.string())),
                {missing.string(), "No such file or directory"});
  checkBadInput(ndcontour("solve " + quoted(missing.string())),
                {missing.string(), "No such file or directory"});
  checkBadInput(ndcontour("info " + quoted(scratch().string())),
                {scratch().string(), "is a directory"});
}

/// `ndcontour ARGS` on a terminal (a pseudo-terminal of `script`, util-linux): what it wrote
/// to the terminal, stdout and stderr together.
std::string onTerminal(const std::string& args) {
  const fs::path log = scratch() / "terminal.txt";
  const std::string inner = quoted(ndc::test::binaryPath()) + " " + args;
  const std::string command =
      "script -qec " + quoted(inner) + " /dev/null >" + quoted(log.string()) + " 2>&1 </dev/null";
  CHECK(std::system(command.c_str()) == 0);
  return slurp(log);
}

TEST_CASE("cli: progress covers every stage on a terminal, and is silent with --json", "[cli]") {
  if (std::system("command -v script >/dev/null 2>&1") != 0) {
    WARN("no `script` (util-linux): the terminal is not tested");
    return;
  }
  // A 2-sphere in R^4 at depth 3, which refinement certifies: every stage has work to show.
  const fs::path sphere =
      fs::path(ndc::test::sourceDir()) / "experiments" / "problems" / "sphere-r4.toml";
  const std::string shown = onTerminal("solve " + quoted(sphere.string()) + " --depth 3");
  INFO("terminal: " << shown);
  for (const char* stage : {"subdivision", "projection", "connection", "analysis"}) {
    CHECK(contains(shown, std::string(stage)));
    // Each stage ends at 100 % exactly once, with a line break.
    std::size_t at = 0, ended = 0;
    const std::string end = "] 100%";
    while ((at = shown.find(end, at)) != std::string::npos) {
      const std::size_t line = shown.rfind('\r', at);
      ended += shown.compare(line + 1, std::string(stage).size(), stage) == 0;
      at += end.size();
    }
    CHECK(ended == 1);
  }
  CHECK(contains(shown, "connection, round 1: "));
  CHECK(contains(shown, "mesh: "));  // the report follows on a line of its own
  // --json: the JSON alone, no bar.
  const std::string json = onTerminal("solve " + quoted(sphere.string()) + " --depth 3 --json");
  CHECK(!contains(json, "[#"));
  CHECK(!contains(json, "100%"));
  CHECK(contains(json, "\"topology\""));
  // The split solve counts its pieces on a terminal, and is silent with --json too.
  const std::string split = onTerminal("solve " + quoted(sphere.string()) + " --depth 3 --split 2");
  CHECK(contains(split, "pieces       2 of 2 solved"));
  const std::string splitJson =
      onTerminal("solve " + quoted(sphere.string()) + " --depth 3 --split 2 --json");
  CHECK(!contains(splitJson, "pieces"));
  CHECK(contains(splitJson, "\"topology\""));
  // Not a terminal: nothing but the report.
  const Run piped = ndcontour("solve " + quoted(sphere.string()) + " --depth 3");
  CHECK(piped.status == 0);
  CHECK(piped.err.empty());
}

TEST_CASE("cli: usage errors exit 2 with one line", "[cli]") {
  const std::string valid = quoted(writeProblem("valid.toml", kValid).string());
  checkBadInput(ndcontour(""), {"subcommand is required"});
  checkBadInput(ndcontour("frobnicate"), {"unknown subcommand 'frobnicate'", "info, solve"});
  checkBadInput(ndcontour("--frobnicate"), {"unknown option '--frobnicate'"});
  checkBadInput(ndcontour("info"), {"problem"});
  checkBadInput(ndcontour("info " + valid + " extra"), {"extra"});
  checkBadInput(ndcontour("solve"), {"problem"});
  checkBadInput(ndcontour("solve " + valid + " --frobnicate"), {"frobnicate"});

  // A misspelt option, subcommand or key names the one meant; a word near nothing does not.
  checkBadInput(ndcontour("solve " + valid + " --depht 4"),
                {"unknown option '--depht' for solve (did you mean '--depth'?)"});
  checkBadInput(ndcontour("solve " + valid + " --therads=2"), {"did you mean '--threads'?"});
  checkBadInput(ndcontour("solve " + valid + " -depth 4"), {"did you mean '--depth'?"});
  checkBadInput(ndcontour("solv " + valid), {"unknown subcommand 'solv' (did you mean 'solve'?)"});
  CHECK(!contains(ndcontour("frobnicate").err, "did you mean"));
  CHECK(!contains(ndcontour("solve " + valid + " --frobnicate").err, "did you mean"));
  const std::string typo = quoted(writeProblem("typo.toml", kValid + "equatons = []\n").string());
  checkBadInput(ndcontour("solve " + typo),
                {"unknown key 'equatons' (did you mean 'equations'?) (known: name,"});

  // Unknown strategy names list the accepted ones.
  checkBadInput(ndcontour("solve " + valid + " --bounding taylor"),
                {"--bounding", "'taylor'", "bernstein, interval, linearized"});
  checkBadInput(ndcontour("solve " + valid + " --subdivision octree"),
                {"--subdivision", "'octree'", "uniform, binary"});
  checkBadInput(ndcontour("solve " + valid + " --classification magic"),
                {"--classification", "'magic'", "paper"});
  checkBadInput(ndcontour("solve " + valid + " --connection mc"),
                {"--connection", "'mc'", "paper, naive, crossing"});
  checkBadInput(ndcontour("solve " + valid + " --scalar float"),
                {"--scalar", "'float'", "double, mpfr"});
  // Strategy parameters: unknown keys, bad values and malformed specs.
  checkBadInput(ndcontour("solve " + valid + " --connection paper:layers=2"),
                {"--connection", "unknown parameter 'layers'", "extra_layers, thin_thick_normal"});
  checkBadInput(ndcontour("solve " + valid + " --connection paper:extra_layers=9"),
                {"--connection", "'9' is not an integer in 0..8"});
  checkBadInput(ndcontour("solve " + valid + " --connection paper:extra_layers=1,extra_layers=2"),
                {"--connection", "given twice"});
  checkBadInput(ndcontour("solve " + valid + " --connection 'paper:'"),
                {"--connection", "no parameter after ':'"});
  checkBadInput(ndcontour("solve " + valid + " --connection naive:x=1"),
                {"--connection", "unknown parameter 'x'", "it has none"});
  checkBadInput(ndcontour("solve " + valid + " --connection crossing:max_face_depth"),
                {"--connection", "'max_face_depth' is not KEY=VALUE"});

  // Ranges and conversions.
  checkBadInput(ndcontour("solve " + valid + " --depth 0"), {"--depth", "1..30"});
  checkBadInput(ndcontour("solve " + valid + " --depth 31"), {"--depth", "1..30"});
  checkBadInput(ndcontour("solve " + valid + " --depth two"), {"--depth"});
  checkBadInput(ndcontour("solve " + valid + " --depth"), {"--depth"});
  checkBadInput(ndcontour("solve " + valid + " --scalar mpfr --precision 8"),
                {"--precision", "24..4096"});
  checkBadInput(ndcontour("solve " + valid + " --scalar mpfr --precision 5000"),
                {"--precision", "24..4096"});
  checkBadInput(ndcontour("solve " + valid + " --precision 100"), {"--precision", "mpfr"});
  checkBadInput(ndcontour("solve " + valid + " --tolerance -1"), {"--tolerance"});
  checkBadInput(ndcontour("solve " + valid + " --tolerance 0"), {"--tolerance"});
  checkBadInput(ndcontour("solve " + valid + " --jitter abc"), {"--jitter"});
  checkBadInput(ndcontour("solve " + valid + " --jitter -3"), {"--jitter", "not an integer"});
  checkBadInput(ndcontour("bench " + valid + " --jitter -1"), {"--jitter", "not an integer"});
  checkBadInput(ndcontour("solve " + valid + " --jitter 1e3"), {"--jitter", "not an integer"});
  checkBadInput(ndcontour("solve " + valid + " --scalar mpfr --precision -5"), {"--precision"});
  checkBadInput(ndcontour("solve " + valid + " --scalar mpfr --precision 99999999999"),
                {"--precision"});
  checkBadInput(ndcontour("solve " + valid + " --jitter 99999999999999999999999"), {"--jitter"});
  checkBadInput(ndcontour("solve " + valid + " --out " + valid), {"--out", "not a directory"});

  // The depth must fit the packed cell index: n * depth <= 128.
  const fs::path r8 = problemsDir() / "circle-r8.toml";
  checkBadInput(ndcontour("solve " + quoted(r8.string()) + " --depth 17"),
                {"--depth 17", r8.string(), "depth <= 16"});
}

TEST_CASE("cli: a valid solve runs the pipeline and writes its outputs", "[cli]") {
  const std::string valid = quoted(writeProblem("valid.toml", kValid).string());
  const fs::path out = scratch() / "out";
  fs::remove_all(out);
  const Run run = ndcontour("solve " + valid +
                            " --depth 5 --bounding interval --subdivision "
                            "uniform --scalar mpfr --precision 200 --classification paper "
                            "--connection paper --out " +
                            quoted(out.string()) + " --json");
  INFO(run.err);
  CHECK(run.status == 0);
  CHECK(run.err.empty());
  // --json: the summary and nothing else on standard output, with the contract's fields.
  CHECK(run.out.rfind("{", 0) == 0);
  for (const char* field :
       {"\"schema\": \"ndcontour.summary/1\"", "\"problem\": \"p\"", "\"n\": 2", "\"k\": 1",
        "\"depth\": 5", "\"bounding\": \"interval\"", "\"subdivision\": \"uniform\"",
        "\"scalar\": \"mpfr\"", "\"precision_bits\": 201", "\"connection\": \"paper\"",
        "\"jitter\": null", "\"components\": 1", "\"open_ends\": 0", "\"max_residual\"",
        "\"ambiguous_cells\"", "\"total\""}) {
    CHECK(contains(run.out, field));
  }
  CHECK(fs::exists(out / "summary.json"));
  CHECK(fs::exists(out / "mesh.ply"));
  CHECK(!fs::exists(out / "cells.csv"));  // only with --cells
  // --tolerance is a chord error: --depth stays the base level, the grid refines below it.
  const Run tolerance = ndcontour("solve " + valid + " --depth 3 --tolerance 1e-4 --json");
  INFO(tolerance.err);
  CHECK(tolerance.status == 0);
  CHECK(tolerance.err.empty());
  CHECK(contains(tolerance.out, "\"depth\": 3"));
  CHECK(contains(tolerance.out, "\"tolerance\": 0.0001"));
  // It needs a connection that refines (a capability): a spec with parameters is one, the
  // paper's connection is not.
  const Run tuned = ndcontour(
      "solve " + valid + " --depth 3 --tolerance 1e-4 --connection crossing:max_face_depth=12");
  INFO(tuned.err);
  CHECK(tuned.status == 0);
  const Run unrefined =
      ndcontour("solve " + valid + " --depth 3 --tolerance 1e-4 --connection paper");
  CHECK(unrefined.status == 2);
  CHECK(unrefined.err ==
        "ndcontour: --tolerance needs a connection that refines: --connection crossing\n");
  const Run plain = ndcontour("solve " + valid + " --depth 3 --json");
  CHECK(contains(plain.out, "\"tolerance\": null"));
  // Strategy parameters: the summary names the strategy and records every value used.
  CHECK(contains(plain.out, "\"connection\": {\"max_face_depth\": 20}"));
  const Run parameters =
      ndcontour("solve " + valid + " --depth 3 --connection paper:extra_layers=1 --json");
  INFO(parameters.err);
  CHECK(parameters.status == 0);
  CHECK(contains(parameters.out, "\"connection\": \"paper\""));
  CHECK(contains(parameters.out,
                 "\"connection\": {\"extra_layers\": 1, \"thin_thick_normal\": true}"));
  checkBadInput(ndcontour("solve " + valid + " --tolerance 0.1 --connection paper"),
                {"--tolerance", "crossing"});
  // Not reachable above --max-depth: a warning, the run itself succeeds.
  const Run unreached = ndcontour("solve " + valid + " --depth 3 --max-depth 3 --tolerance 1e-6");
  CHECK(unreached.status == 0);
  CHECK(contains(unreached.err, "--tolerance 1e-06 not reached"));
}

TEST_CASE("cli: bench times each stage and rejects bad settings", "[cli]") {
  const std::string valid = quoted(writeProblem("bench.toml", kValid).string());
  const Run run = ndcontour("bench " + valid + " --depth 4 --repeat 2 --connection crossing");
  INFO(run.err);
  CHECK(run.status == 0);
  CHECK(contains(run.out, "| problem | n | k | depth |"));
  CHECK(contains(run.out, "| p | 2 | 1 | 4 | linearized | binary | crossing | double |"));
  checkBadInput(ndcontour("bench " + valid + " --connection mc"), {"--connection", "mc"});
  checkBadInput(ndcontour("bench " + valid + " --repeat 0"), {"--repeat"});
}

TEST_CASE("cli: an equation too large for memory is bad input, not a crash", "[cli]") {
  const std::string big =
      quoted(writeProblem("big.toml",
                          "name = \"big\"\nvariables = [\"x\", \"y\", \"z\", \"w\"]\n"
                          "domain = [[-1, 1], [-1, 1], [-1, 1], [-1, 1]]\n"
                          "equations = [\"(x*y*z*w)^3000 - 1\"]\n")
                 .string());
  checkBadInput(ndcontour("solve " + big + " --depth 2"),
                {"big.toml:4:", "equation 1", "Bernstein coefficients", "at most"});
  checkBadInput(ndcontour("info " + big), {"Bernstein coefficients"});
}

TEST_CASE("cli: a quadric past the dense forms' cap is solved; the bernstein bounding refuses it",
          "[cli]") {
  // The circle in R^13: its quadric has 3^13 Bernstein coefficients (docs/input-limits.md).
  const std::string file =
      quoted(writeProblem("r13.toml", ndc::generateProblem("rotated-circle", 13, 0).text).string());
  const Run info = ndcontour("info " + file);
  INFO(info.err);
  CHECK(info.status == 0);
  const Run solve = ndcontour("solve " + file + " --depth 4 --check --json");
  INFO(solve.err);
  CHECK(solve.status == 0);
  CHECK(contains(solve.out, "\"certified\": true"));
  checkBadInput(ndcontour("solve " + file + " --depth 4 --bounding bernstein"),
                {"bounding 'bernstein'", "equation 1", "linearized"});
}

TEST_CASE("cli: solve compares the mesh with [expect]; --check exits 3 on a mismatch", "[cli]") {
  // The circle has one component: [expect] components = 2 is wrong.
  const fs::path wrong = writeProblem("wrong-expect.toml", kValid + "[expect]\ncomponents = 2\n");
  const std::string args = "solve " + quoted(wrong.string()) + " --depth 4";
  const std::string warning = wrong.string() + ": expect components = 2, got 1\n";

  // Without --check: the warning, one line on standard error, and status 0.
  const Run plain = ndcontour(args);
  INFO("stdout: " << plain.out << "stderr: " << plain.err);
  CHECK(plain.status == 0);
  CHECK(plain.err == warning);
  CHECK(contains(plain.out, "expect: components = 2 got 1\n"));

  // --check: the same warning and status 3, also with --json (the summary still on stdout).
  const Run checked = ndcontour(args + " --check");
  CHECK(checked.status == 3);
  CHECK(checked.err == warning);
  const fs::path out = scratch() / "wrong-expect-out";
  fs::remove_all(out);
  const Run json = ndcontour(args + " --check --json --out " + quoted(out.string()));
  CHECK(json.status == 3);
  CHECK(json.err == warning);
  CHECK(json.out.rfind("{", 0) == 0);
  const std::string field =
      "\"expect\": {\"components\": {\"wanted\": 2, \"got\": 1, \"ok\": false}}";
  CHECK(contains(json.out, field));
  CHECK(contains(slurp(out / "summary.json"), field));

  // A right [expect]: ok true, nothing on standard error, status 0 with --check.
  const fs::path right = writeProblem(
      "right-expect.toml", kValid + "[expect]\ncomponents = 1\neuler_characteristic = 0\n");
  const Run good = ndcontour("solve " + quoted(right.string()) + " --depth 4 --check --json");
  INFO("stderr: " << good.err);
  CHECK(good.status == 0);
  CHECK(good.err.empty());
  CHECK(contains(good.out,
                 "\"expect\": {\"components\": {\"wanted\": 1, \"got\": 1, \"ok\": true}, "
                 "\"euler_characteristic\": {\"wanted\": 0, \"got\": 0, \"ok\": true}}"));

  // A key that cannot be compared is reported (a warning and in the summary), not a mismatch.
  const fs::path other =
      writeProblem("other-expect.toml", kValid + "[expect]\ncomponents = 1\ngenus = 0\n");
  const Run notes = ndcontour("solve " + quoted(other.string()) + " --depth 4 --check --json");
  INFO("stderr: " << notes.err);
  CHECK(notes.status == 0);
  CHECK(std::count(notes.err.begin(), notes.err.end(), '\n') == 1);
  CHECK(contains(notes.err, other.string() + ": expect genus = 0: not comparable (genus needs a "
                                             "surface (k = 2), the problem has k = 1)\n"));

  // An unknown key is an error naming the known ones, as an unknown top-level key is.
  for (const char* key : {"loops", "euler", "Components"}) {
    const fs::path bad = writeProblem(
        "bad-expect.toml", kValid + "[expect]\ncomponents = 1\n" + std::string(key) + " = 0\n");
    const Run refused = ndcontour("solve " + quoted(bad.string()) + " --depth 4 --out " +
                                  quoted((out / "refused").string()));
    INFO("stderr: " << refused.err);
    CHECK(refused.status == 2);
    CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
    CHECK(contains(refused.err, "unknown key '" + std::string(key) + "' in expect"));
    CHECK(contains(refused.err, "(known: components, euler_characteristic, "));
    CHECK(!fs::exists(out / "refused"));
  }
  CHECK(contains(notes.out,
                 "\"genus\": {\"wanted\": 0, \"got\": null, \"ok\": null, "
                 "\"not_comparable\": \"genus needs a surface"));

  // Without [expect] the summary has no `expect`.
  const std::string valid = quoted(writeProblem("valid.toml", kValid).string());
  const Run none = ndcontour("solve " + valid + " --depth 4 --json");
  CHECK(none.status == 0);
  CHECK(!contains(none.out, "\"expect\""));

  // Help lists --check and the exit statuses.
  const Run help = ndcontour("solve --help");
  CHECK(contains(help.out, "--check"));
  CHECK(contains(help.out, "3 solve --check"));
  CHECK(contains(ndcontour("--help").out, "Exit status: 0 success"));

  // Bad input still exits 2 with one line, --check or not.
  checkBadInput(
      ndcontour(
          "solve " +
          quoted(
              writeProblem("bad-expect.toml", kValid + "[expect]\ncomponents = 1.5\n").string()) +
          " --check"),
      {"bad-expect.toml:6:", "expect.components must be an integer"});
}

TEST_CASE("cli: solve writes singular.csv and the diagnostics of docs/contracts.md 4.5", "[cli]") {
  const std::string valid = quoted(writeProblem("valid.toml", kValid).string());
  const fs::path out = scratch() / "diagnostics-out";
  fs::remove_all(out);
  // A stale output of an earlier (application) run in the folder goes.
  fs::create_directories(out);
  std::ofstream(out / "input.ply") << "stale";
  std::ofstream(out / "cells.csv") << "stale";
  std::ofstream(out / "summary.json") << "stale";
  // The viewer's page of the earlier run would show its mesh; the staging folder of a killed run
  // (no such process) is litter; a file of the user's stays.
  std::ofstream(out / "view.html") << "stale";
  fs::create_directories(out / ".ndcontour-partial-999999999");
  std::ofstream(out / ".ndcontour-partial-999999999" / "mesh.ply") << "stale";
  std::ofstream(out / "notes.txt") << "mine";
  const Run run = ndcontour("solve " + valid + " --depth 4 --out " + quoted(out.string()));
  INFO("stdout: " << run.out << "stderr: " << run.err);
  CHECK(run.status == 0);
  CHECK(run.err.empty());
  for (const char* name : {"summary.json", "mesh.ply", "singular.csv", "notes.txt"})
    CHECK(fs::exists(out / name));
  CHECK(!fs::exists(out / "view.html"));
  CHECK(!fs::exists(out / ".ndcontour-partial-999999999"));
  CHECK(!fs::exists(out / "input.ply"));
  CHECK(!fs::exists(out / "cells.csv"));  // written only with --cells
  // The circle has no singular point: singular.csv is its header (u0.., then the variables'
  // names, docs/contracts.md 4.4 "Names").
  CHECK(slurp(out / "singular.csv") == "point,sigma_min,u0,u1,x,y\n");
  const std::string summary = slurp(out / "summary.json");
  for (const char* field :
       {"\"singular_points\": []", "\"off_manifold_vertices\": 0",
        "\"perturbation\": {\"level\": [", "\"attempts\": ", "\"degenerate_crossings\": 0"})
    CHECK(contains(summary, field));
  // The human summary: singular points, and every file written.
  CHECK(contains(run.out, "singular points: 0\n"));
  const std::string dir = out.string();
  CHECK(contains(
      run.out, "wrote " + dir + "/mesh.ply, " + dir + "/singular.csv, " + dir + "/summary.json\n"));
  // No stray temporary files.
  for (const auto& entry : fs::directory_iterator(out))
    CHECK(entry.path().filename().string().rfind(".", 0) != 0);
}

namespace {

/// The size a binary PLY of ndcontour must have, from its header: `property double` 8 bytes,
/// `property int` 4, a `list uchar int` of a triangle 1 + 3 * 4.
std::size_t binaryPlySize(const std::string& bytes) {
  const std::size_t header = bytes.find("end_header\n");
  REQUIRE(header != std::string::npos);
  std::istringstream lines(bytes.substr(0, header));
  std::size_t size = header + 11, count = 0, record = 0;
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string word, type;
    words >> word >> type;
    if (word == "element") {
      size += count * record;
      words >> count;
      record = 0;
    } else if (word == "property") {
      record += type == "double" ? 8 : type == "int" ? 4 : 1 + 3 * 4;
    }
  }
  return size + count * record;
}

/// Solves `args` into DIR-binary (the default) and DIR-ascii (`--ascii --cells`) and checks
/// that every PLY file of the two reads back the same, that the binary ones have the header
/// and size of docs/contracts.md 4.4, and that only the second folder has cells.csv.
void checkEncodings(const std::string& name, const std::string& args,
                    const std::vector<std::string>& plyFiles) {
  INFO(name);
  const fs::path binary = scratch() / (name + "-binary"), ascii = scratch() / (name + "-ascii");
  fs::remove_all(binary);
  fs::remove_all(ascii);
  const Run b = ndcontour("solve " + args + " --out " + quoted(binary.string()));
  const Run a = ndcontour("solve " + args + " --ascii --cells --out " + quoted(ascii.string()));
  INFO(b.err << a.err);
  REQUIRE(b.status == 0);
  REQUIRE(a.status == 0);
  CHECK(!fs::exists(binary / "cells.csv"));
  CHECK(fs::exists(ascii / "cells.csv"));
  CHECK(contains(a.out, (ascii / "cells.csv").string()));
  CHECK(slurp(binary / "singular.csv") == slurp(ascii / "singular.csv"));
  for (const std::string& file : plyFiles) {
    INFO(file);
    const std::string bytes = slurp(binary / file);
    CHECK(bytes.rfind("ply\nformat binary_little_endian 1.0\ncomment ndcontour ", 0) == 0);
    CHECK(slurp(ascii / file).rfind("ply\nformat ascii 1.0\ncomment ndcontour ", 0) == 0);
    CHECK(bytes.size() == binaryPlySize(bytes));
    const ndc::PlyMesh mb = ndc::readPly(binary / file), ma = ndc::readPly(ascii / file);
    CHECK(!mb.xyz.empty());
    CHECK(!mb.simplices.empty());
    CHECK(mb.xyz == ma.xyz);
    CHECK(mb.u == ma.u);
    CHECK(mb.simplices == ma.simplices);
  }
  // The mesh.ply counts are the summary's.
  const std::string summary = slurp(binary / "summary.json");
  const ndc::PlyMesh mesh = ndc::readPly(binary / "mesh.ply");
  CHECK(contains(summary, "\"mesh\": {\"vertices\": " + std::to_string(mesh.xyz.size()) + ","));
  const std::string simplices = mesh.simplices.front().size() == 2 ? "edges" : "triangles";
  CHECK(contains(summary, "\"" + simplices + "\": " + std::to_string(mesh.simplices.size()) + ","));
}

}  // namespace

TEST_CASE("cli: mesh.ply is binary PLY unless --ascii; cells.csv only with --cells", "[cli]") {
  const std::string circle = quoted(writeProblem("valid.toml", kValid).string());
  const std::string sphere = quoted((problemsDir() / "sphere.toml").string());
  checkEncodings("curve-double", circle + " --depth 4", {"mesh.ply"});
  checkEncodings("curve-mpfr", circle + " --depth 4 --scalar mpfr", {"mesh.ply"});
  checkEncodings("surface-double", sphere + " --depth 3", {"mesh.ply"});
  checkEncodings("surface-mpfr", sphere + " --depth 3 --scalar mpfr --precision 100", {"mesh.ply"});
  // An application: its image and parameters, the second image, input.ply and ruled.ply.
  checkEncodings("convex-hull",
                 quoted((problemsDir() / "convex-hull-wavy-bump.toml").string()) + " --depth 2",
                 {"mesh.ply", "input.ply", "ruled.ply"});

  // A later run without --cells leaves no cells.csv of an earlier one behind.
  const fs::path out = scratch() / "curve-double-ascii";
  REQUIRE(fs::exists(out / "cells.csv"));
  const Run again = ndcontour("solve " + circle + " --depth 4 --out " + quoted(out.string()));
  CHECK(again.status == 0);
  CHECK(!fs::exists(out / "cells.csv"));
  CHECK(slurp(out / "mesh.ply").rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);

  // --ascii and --cells choose files of --out: without it they are usage errors.
  checkBadInput(ndcontour("solve " + circle + " --cells"), {"--cells needs --out DIR"});
  checkBadInput(ndcontour("solve " + circle + " --ascii --json"), {"--ascii needs --out DIR"});
}
