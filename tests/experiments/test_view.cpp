// `ndcontour view` as a process (docs/viewer.md): a page for a good result folder, and every
// class of bad input exits with status 2 and one line on standard error, leaving an earlier page
// alone. The page in a browser: tests/experiments/viewer_test.py (ctest `viewer`).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "experiments/view/view.hpp"
#include "tests/test_process.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("view");
  return dir.path();
}

using ndc::test::quoted;
using ndc::test::slurp;

ndc::test::CliRun view(const std::string& args) {
  return ndc::test::runNdcontour("view " + args, scratch());
}

/// A result folder `name` holding the given files (name, text).
fs::path resultDir(const std::string& name,
                   std::initializer_list<std::pair<std::string, std::string>> files) {
  const fs::path dir = scratch() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const auto& [file, text] : files) std::ofstream(dir / file, std::ios::binary) << text;
  return dir;
}

/// A curve in R^2: three vertices, two segments (ASCII PLY as `solve --ascii` writes it).
const std::string kPly =
    "ply\nformat ascii 1.0\ncomment test\nelement vertex 3\nproperty double x\nproperty double "
    "y\nproperty double z\nproperty double u0\nproperty double u1\nelement edge 2\nproperty int "
    "vertex1\nproperty int vertex2\nend_header\n1 0 0 1 0\n0 1 0 0 1\n-1 0 0 -1 0\n0 1\n1 2\n";
const std::string kSummary =
    "{\"problem\": \"arc\", \"n\": 2, \"k\": 1, \"mesh\": {\"vertices\": 3, \"edges\": 2}, "
    "\"diagnostics\": {\"singular_points\": [{\"point\": [0.0, 1.0], \"sigma_min\": 0.0}]}, "
    "\"topology\": {\"certified\": false, \"reason\": \"</script>\"}}";

/// Status 2, nothing on stdout, one line on stderr holding `part`.
void checkBadInput(const ndc::test::CliRun& run, const std::string& part) {
  INFO("stderr: " << run.err << "stdout: " << run.out);
  CHECK(run.status == 2);
  CHECK(run.out.empty());
  CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
  CHECK(run.err.find(part) != std::string::npos);
}

}  // namespace

TEST_CASE("view: a result folder gives one self-contained page", "[view][cli]") {
  const fs::path dir = resultDir("good", {{"mesh.ply", kPly},
                                          {"summary.json", kSummary},
                                          {"uncertified.csv",
                                           "kind,level,reason,lo0,hi0,lo1,hi1\ncell,3,x,-2,0,0,"
                                           "2\nsingular_point,0,0,0,0,1,1\n"}});
  const ndc::test::CliRun run = view(quoted(dir.string()));
  if (!ndc::view::viewerAvailable()) {
    checkBadInput(run, "scripts/setup.sh");
    CHECK(!fs::exists(dir / "view.html"));
    return;
  }
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.out.find("2 segments") != std::string::npos);
  CHECK(run.out.find("1 singular points, 1 uncertified") != std::string::npos);
  const std::string page = slurp(dir / "view.html");
  CHECK(page.find("id=\"ndc-mesh\"") != std::string::npos);
  CHECK(page.find("\"coordinates\": [\"u0\", \"u1\"]") != std::string::npos);
  CHECK(page.find("<\\/script>") != std::string::npos);  // summary text made script-safe
  CHECK(page.find("<!--NDC_") == std::string::npos);
  CHECK(page.find("src=\"http") == std::string::npos);  // nothing loaded from the network

  const fs::path other = scratch() / "other.html";
  CHECK(view(quoted(dir.string()) + " --out " + quoted(other.string())).status == 0);
  CHECK(fs::file_size(other) == page.size());
}

TEST_CASE("view: an empty result (the zero set misses the domain) gives a page", "[view][cli]") {
  const std::string ply =
      kPly.substr(0, kPly.find("element vertex")) + "element vertex 0" +
      kPly.substr(kPly.find("\nproperty double x"),
                  kPly.find("element edge") - kPly.find("\nproperty double x")) +
      "element edge 0\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  const fs::path dir = resultDir(
      "emptyresult",
      {{"mesh.ply", ply},
       {"summary.json",
        "{\"problem\": \"far\", \"n\": 2, \"k\": 1, \"variables\": [\"p\", \"q\"], \"mesh\": "
        "{\"vertices\": 0, \"edges\": 0, \"components\": 0}, \"diagnostics\": "
        "{\"empty_zero_set\": true, \"singular_points\": []}}"}});
  const ndc::test::CliRun run = view(quoted(dir.string()));
  if (!ndc::view::viewerAvailable()) return;  // the first test case checks the message
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.out.find("0 vertices, 0 segments") != std::string::npos);
  // The page reads the names and empty_zero_set from the summary it inlines (viewer_test.py
  // checks what it shows).
  const std::string page = slurp(dir / "view.html");
  CHECK(page.find("\"variables\": [\"p\", \"q\"]") != std::string::npos);
  CHECK(page.find("\"vertices\": 0") != std::string::npos);
}

TEST_CASE("view: bad input exits 2 with one line and leaves an earlier page alone", "[view][cli]") {
  checkBadInput(view(quoted((scratch() / "absent").string())), "not a folder");
  checkBadInput(view(quoted(resultDir("empty", {}).string())), "mesh.ply: missing");
  checkBadInput(view(quoted(resultDir("nosummary", {{"mesh.ply", kPly}}).string())),
                "summary.json: missing");
  checkBadInput(
      view(quoted(
          resultDir("badjson", {{"mesh.ply", kPly}, {"summary.json", "{\"n\": 2,"}}).string())),
      "summary.json: malformed JSON");
  checkBadInput(
      view(quoted(resultDir("nok", {{"mesh.ply", kPly}, {"summary.json", "{\"n\": 2}"}}).string())),
      "no field 'k'");
  checkBadInput(
      view(quoted(resultDir("badn", {{"mesh.ply", kPly}, {"summary.json", "{\"n\": 3, \"k\": 1}"}})
                      .string())),
      "summary.json says n = 3");
  const std::string faces = kPly.substr(0, kPly.find("element edge")) +
                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n" +
                            "1 0 0 1 0\n0 1 0 0 1\n-1 0 0 -1 0\n3 0 1 2\n";
  checkBadInput(
      view(quoted(resultDir("badk", {{"mesh.ply", faces}, {"summary.json", kSummary}}).string())),
      "simplex 1 has 3 vertices");
  const std::string truncated = kPly.substr(0, kPly.size() - 8);
  const fs::path dir = resultDir(
      "badply", {{"mesh.ply", truncated}, {"summary.json", kSummary}, {"view.html", "OLD"}});
  checkBadInput(view(quoted(dir.string())), "mesh.ply");
  CHECK(slurp(dir / "view.html") == "OLD");
  checkBadInput(
      view(quoted(
          resultDir("notply", {{"mesh.ply", "solid x\n"}, {"summary.json", kSummary}}).string())),
      "not a PLY file");
  checkBadInput(view(""), "");
  // A page that cannot be written (its folder does not exist).
  const fs::path good = resultDir("good2", {{"mesh.ply", kPly}, {"summary.json", kSummary}});
  checkBadInput(
      view(quoted(good.string()) + " --out " + quoted((scratch() / "no/such/dir/v.html").string())),
      ndc::view::viewerAvailable() ? "v.html: cannot write" : "scripts/setup.sh");
}

TEST_CASE("view: a 3-manifold's page (k = 3), and k >= n refused", "[view][cli][simplices]") {
  // Two tetrahedra in R^4 sharing a triangle, as `solve --ascii` writes them.
  std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty "
      "double z\n";
  for (int j = 0; j < 4; ++j) ply += "property double u" + std::to_string(j) + "\n";
  ply += "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  for (const char* row :
       {"0 0 0 0 0 0 0", "1 0 0 1 0 0 0", "0 1 0 0 1 0 0", "0 0 1 0 0 1 0", "0 0 0 0 0 0 1"})
    ply += std::string(row) + "\n";
  ply += "4 0 1 2 3\n4 0 1 2 4\n";
  const std::string summary = "{\"problem\": \"two-tets\", \"n\": 4, \"k\": 3}";
  const fs::path dir = resultDir("tets", {{"mesh.ply", ply}, {"summary.json", summary}});
  const ndc::test::CliRun run = view(quoted(dir.string()));
  if (ndc::view::viewerAvailable()) {
    INFO(run.err);
    REQUIRE(run.status == 0);
    CHECK(run.out.find("n = 4, 5 vertices, 2 tetrahedra") != std::string::npos);
    CHECK(slurp(dir / "view.html").find("\"k\": 3") != std::string::npos);
  }
  // k must be below n: a 3-manifold is not in R^3.
  checkBadInput(
      view(quoted(
          resultDir("kn", {{"mesh.ply", ply}, {"summary.json", "{\"n\": 3, \"k\": 3}"}}).string())),
      "(expected 2 <= n <= 64 and 1 <= k < n)");
}
