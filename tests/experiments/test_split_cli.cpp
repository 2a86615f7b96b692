// `ndcontour solve --split S` as a process (docs/split.md): the glued solve has the single
// solve's topology on the examples of the issue and on a seeded corpus of surfaces and curves
// that cross the cut planes and the domain's faces; its summary has every field of a solve's; the
// local executor gives the same mesh whatever the pieces at once; bad combinations exit 2.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "framework/util/json.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("split");
  return dir.path();
}

using ndc::test::quoted;
using ndc::test::slurp;

/// A summary.json by path.
std::map<std::string, std::string> summaryOf(const std::string& json) {
  std::map<std::string, std::string> out;
  for (const ndc::JsonLeaf& leaf : ndc::jsonLeaves(json)) out[leaf.path] = leaf.text;
  return out;
}

/// `ndcontour solve FILE ARGS --json`, its summary (the run must succeed).
std::map<std::string, std::string> solve(const fs::path& file, const std::string& args) {
  const ndc::test::CliRun run =
      ndc::test::runNdcontour("solve " + quoted(file.string()) + " " + args + " --json", scratch());
  INFO("solve " << file.string() << " " << args << "\nstderr: " << run.err);
  REQUIRE(run.status == 0);
  return summaryOf(run.out);
}

fs::path example(const std::string& name) {
  return fs::path(ndc::test::sourceDir()) / "experiments" / "problems" / (name + ".toml");
}

/// The topology the certificate speaks of.
std::string topology(const std::map<std::string, std::string>& s) {
  return "components " + s.at("mesh.components") + ", euler " + s.at("mesh.euler_characteristic") +
         ", boundary components " + s.at("mesh.boundary_components");
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("split: the torus, genus2 and a 2-sphere in R^6 glue to the single solve's topology",
          "[split][cli]") {
  struct Case {
    const char* name;
    int depth, pieces;
    const char* scalar;
  };
  for (const Case c :
       {Case{"torus", 4, 8, "double"}, Case{"torus", 3, 8, "mpfr"}, Case{"genus2", 4, 8, "double"},
        Case{"sphere-r6", 3, 64, "double"}, Case{"circle-r5", 4, 32, "double"}}) {
    const std::string args =
        "--depth " + std::to_string(c.depth) + " --scalar " + std::string(c.scalar);
    const auto single = solve(example(c.name), args);
    const auto split = solve(example(c.name), args + " --split " + std::to_string(c.pieces));
    INFO(c.name << " depth " << c.depth << ", " << c.pieces << " pieces, " << c.scalar << ": "
                << split.at("topology.reason"));
    CHECK(single.at("topology.certified") == "true");
    CHECK(split.at("topology.certified") == "true");
    CHECK(topology(split) == topology(single));
    CHECK(split.at("mesh.nonmanifold_edges") == "0");
    CHECK(split.at("settings.depth") == std::to_string(c.depth));
    CHECK(std::stod(split.at("accuracy.max_residual")) < 1e-10);
  }
}

TEST_CASE("split: no certified split contradicts a certified single solve (seeded corpus)",
          "[split][cli]") {
  // Spheres (k = 2) and circles (sphere and plane, k = 1) in [-1, 1]^3 at random centres and
  // radii: they cross the cut planes x, y, z = 0 anywhere and often leave the domain.
  std::mt19937 rng(20261206);
  std::uniform_real_distribution<double> centre(-0.6, 0.6), radius(0.25, 1.1), normal(-1, 1);
  int certified = 0, runs = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const double a = centre(rng), b = centre(rng), c = centre(rng), r = radius(rng);
    std::ostringstream text;
    text << "name = \"random-" << trial << "\"\nvariables = [\"x\", \"y\", \"z\"]\n"
         << "domain = [[-1, 1], [-1, 1], [-1, 1]]\nequations = [\"(x - " << a << ")^2 + (y - " << b
         << ")^2 + (z - " << c << ")^2 - " << r * r << "\"";
    if (trial % 2)
      text << ", \"" << normal(rng) << "*x + " << normal(rng) << "*y + z - " << c << "\"";
    text << "]\n";
    const fs::path file = scratch() / ("random-" + std::to_string(trial) + ".toml");
    std::ofstream(file) << text.str();
    for (const int depth : {3, 4}) {
      const std::string args = "--depth " + std::to_string(depth);
      const auto single = solve(file, args);
      const auto split = solve(file, args + " --split 8");
      ++runs;
      INFO(text.str() << "depth " << depth << ": " << split.at("topology.reason"));
      if (split.at("topology.certified") != "true") continue;
      ++certified;
      CHECK(split.at("mesh.nonmanifold_edges") == "0");
      if (single.at("topology.certified") == "true") CHECK(topology(split) == topology(single));
    }
  }
  // Not vacuous: most splits certify.
  CHECK(certified * 4 >= runs * 3);
}

TEST_CASE(
    "split: the summary has a solve's fields, the pieces stay in --out, the mesh is the "
    "same whatever the pieces at once",
    "[split][cli]") {
  const fs::path out1 = scratch() / "out1", out2 = scratch() / "out2";
  const std::string base = "solve " + quoted(example("torus").string()) + " --depth 4 --split 8";
  auto run =
      ndc::test::runNdcontour(base + " --threads 1 --out " + quoted(out1.string()), scratch());
  REQUIRE(run.status == 0);
  CHECK(contains(run.out, "topology: certified"));
  run = ndc::test::runNdcontour(base + " --threads 2 --out " + quoted(out2.string()), scratch());
  REQUIRE(run.status == 0);
  CHECK(slurp(out1 / "mesh.ply") == slurp(out2 / "mesh.ply"));
  for (int p = 0; p < 8; ++p) {
    const fs::path piece = out1 / "pieces" / ("piece-00" + std::to_string(p));
    CHECK(fs::exists(piece / "summary.json"));
    CHECK(fs::exists(piece / "mesh.ply"));
  }
  CHECK(!fs::exists(out1 / "pieces.partial"));
  // Every field of a single solve's summary, no more.
  const auto single = solve(example("torus"), "--depth 4");
  std::set<std::string> fields, splitFields;
  for (const std::string& path : ndc::jsonLeafPaths(slurp(out1 / "summary.json")))
    splitFields.insert(path);
  for (const auto& [path, value] : single) fields.insert(path);
  CHECK(splitFields == fields);
}

TEST_CASE("split: combinations it cannot take exit 2 with one line", "[split][cli]") {
  const std::string torus = "solve " + quoted(example("torus").string()) + " --depth 3 ";
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--split 3", "power of two"},
      {"--split 1024", "power of two"},
      {"--split 512", "needs --depth 4"},
      {"--split 8 --cells --out " + quoted((scratch() / "c").string()), "--cells"},
      {"--split 8 --executor nowhere", "unknown executor"},
      {"--split 8 --executor slurm", "needs --out"},
      {"--split 8 --slurm-partition p", "need --executor slurm"},
      {"--split 8 --jitter 3", "--jitter"},
      {"--split 8 --domain 0:1,0:1,0:1", "--domain"},
      {"--domain 0:1,0:1", "3 intervals"},
  };
  for (const auto& [args, part] : bad) {
    const ndc::test::CliRun run = ndc::test::runNdcontour(torus + args, scratch());
    INFO(args << "\nstderr: " << run.err);
    CHECK(run.status == 2);
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    CHECK(contains(run.err, part));
  }
}
