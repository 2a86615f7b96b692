// The mesh files of a k-manifold for k >= 3 (docs/contracts.md 4.4): mesh.ply's `face` lists of
// k + 1 indices (read back by readPly, binary and ASCII), mesh.vtu and mesh.vtk with VTK_TETRA
// cells for k = 3, and the formats that cannot hold a k-simplex refused: VTK for k >= 4, OBJ for
// k >= 3, by the writers and by `solve` before its work.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "framework/io/io.hpp"
#include "framework/util/errors.hpp"
#include "tests/framework/vtu_arrays.hpp"
#include "tests/test_process.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("simplices");
  return dir.path();
}

/// The boundary of the (k + 1)-simplex in R^(k + 2), a k-sphere: the k + 2 unit vectors
/// (scaled apart so that every coordinate differs) and the k + 2 facets, facet f leaving out
/// vertex f.
ndc::RunResult sphere(int k) {
  ndc::RunResult r;
  r.n = r.summary.n = k + 2;
  r.k = r.summary.k = k;
  r.summary.problem = "simplex-boundary";
  for (int j = 0; j < r.n; ++j) r.summary.variables.push_back(std::string(1, "abcdefghij"[j]));
  for (int v = 0; v < r.n; ++v)
    for (int j = 0; j < r.n; ++j) r.vertices.push_back(v == j ? 1.0 + 0.125 * v : 0.0);
  for (int f = 0; f < r.n; ++f)
    for (int v = 0; v < r.n; ++v)
      if (v != f) r.simplices.push_back(v);
  return r;
}

using ndc::test::text;

std::string ply(const ndc::RunResult& r, ndc::PlyFormat format) {
  return text(r, [&](std::ostream& o, const ndc::RunResult& x) { ndc::writePly(o, x, format); });
}

std::string vtu(const ndc::RunResult& r, ndc::PlyFormat format) {
  return text(r, [&](std::ostream& o, const ndc::RunResult& x) { ndc::writeVtk(o, x, format); });
}

/// The lines of `s` from the one that starts with `head` on, `count` of them.
std::vector<std::string> linesAfter(const std::string& s, const std::string& head, int count) {
  std::istringstream in(s.substr(s.find("\n" + head) + 1));
  std::vector<std::string> lines;
  for (std::string line; lines.size() < static_cast<std::size_t>(count) && std::getline(in, line);)
    lines.push_back(line);
  return lines;
}

/// The message of what `f` throws as ndc::InputError ("" when it throws nothing).
template <class F>
std::string thrown(F f) {
  try {
    f();
  } catch (const ndc::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("simplices: mesh.ply holds k + 1 indices per face for k = 3 and 4, read back",
          "[io][outputs][simplices]") {
  for (const int k : {3, 4}) {
    const ndc::RunResult r = sphere(k);
    const std::size_t n = r.n, count = n;  // k + 2 vertices and facets
    for (const auto format : {ndc::PlyFormat::binary, ndc::PlyFormat::ascii}) {
      INFO("k = " << k << (format == ndc::PlyFormat::ascii ? ", ascii" : ", binary"));
      const std::string file = ply(r, format);
      const std::string header = file.substr(0, file.find("end_header\n") + 11);
      CHECK(header.find("\nelement face " + std::to_string(count) +
                        "\nproperty list uchar int vertex_indices\nend_header\n") !=
            std::string::npos);
      CHECK(header.find("element edge") == std::string::npos);
      if (format == ndc::PlyFormat::binary) {
        // The body: 8 (3 + n) bytes per vertex, one uchar k + 1 and k + 1 int32 per simplex.
        CHECK(file.size() == header.size() + 8 * count * (3 + n) + count * (1 + 4 * (k + 1)));
      } else {
        // One line per simplex: k + 1, then its vertex indices.
        const auto rows = linesAfter(file, "end_header", 1 + static_cast<int>(count) * 2);
        CHECK(rows.back() == std::to_string(k + 1) + " 0 1 2 3" + (k == 4 ? " 4" : ""));
      }
      const fs::path path = scratch() / ("sphere" + std::to_string(k) + ".ply");
      std::ofstream(path, std::ios::binary) << file;
      const ndc::PlyMesh mesh = ndc::readPly(path);
      REQUIRE(mesh.simplices.size() == count);
      REQUIRE(mesh.u.size() == count);
      for (std::size_t s = 0; s < count; ++s)
        CHECK(mesh.simplices[s] == std::vector<int>(r.simplices.begin() + s * (k + 1),
                                                    r.simplices.begin() + (s + 1) * (k + 1)));
      for (std::size_t v = 0; v < count; ++v)
        CHECK(mesh.u[v] ==
              std::vector<double>(r.vertices.begin() + v * n, r.vertices.begin() + (v + 1) * n));
    }
  }
}

TEST_CASE("simplices: mesh.vtu and mesh.vtk hold a 3-manifold as tetrahedra",
          "[io][outputs][simplices]") {
  // The boundary of the 4-simplex in R^5: 5 vertices, 5 tetrahedra.
  const ndc::RunResult r = sphere(3);
  const auto binary = ndc::test::vtuArrays(vtu(r, ndc::PlyFormat::binary));
  CHECK(vtu(r, ndc::PlyFormat::binary).find("compressor=\"vtkZLibDataCompressor\"") !=
        std::string::npos);
  CHECK(binary.at("types") == std::vector<double>(5, 10.0));  // VTK_TETRA
  CHECK(binary.at("offsets") == std::vector<double>({4, 8, 12, 16, 20}));
  CHECK(binary.at("connectivity") == std::vector<double>(r.simplices.begin(), r.simplices.end()));
  CHECK(binary.at("Points").size() == 15);
  CHECK(binary.at("e") == binary.at("u4"));
  CHECK(binary.at("class").size() == 5);
  CHECK(binary.at("uncertified") == std::vector<double>(5, 0.0));
  // --ascii: the same numbers.
  CHECK(ndc::test::vtuArrays(vtu(r, ndc::PlyFormat::ascii)) == binary);
  // mesh.vtk: each cell `4 a b c d`, each type 10.
  const std::string legacy = text(r, ndc::writeLegacyVtk);
  CHECK(linesAfter(legacy, "CELLS", 3) ==
        std::vector<std::string>({"CELLS 5 25", "4 1 2 3 4", "4 0 2 3 4"}));
  CHECK(linesAfter(legacy, "CELL_TYPES", 6) ==
        std::vector<std::string>({"CELL_TYPES 5", "10", "10", "10", "10", "10"}));
  CHECK(legacy.find("CELL_DATA 5\n") != std::string::npos);
}

TEST_CASE("simplices: VTK for k >= 4 and OBJ for k >= 3 are refused, mesh.ply is not",
          "[io][outputs][simplices]") {
  CHECK(ndc::formatRefusal("--vtk", 3).empty());
  CHECK(ndc::formatRefusal("--obj", 2).empty());
  CHECK(ndc::formatRefusal("--vtk-legacy", 4)
            .starts_with("--vtk-legacy: VTK has no cell for a "
                         "4-simplex (k = 4)"));
  const ndc::RunResult three = sphere(3), four = sphere(4);
  CHECK(thrown([&] { vtu(four, ndc::PlyFormat::binary); }).starts_with("mesh.vtu: --vtk: VTK"));
  CHECK(thrown([&] { text(four, ndc::writeLegacyVtk); }).starts_with("mesh.vtk: --vtk-legacy:"));
  CHECK(thrown([&] {
          text(three, ndc::writeObj);
        }).starts_with("mesh.obj: --obj: OBJ has no cell for a 3-simplex (k = 3)"));
  // writeOutputs formats every file before it writes one: nothing is written.
  const fs::path out = scratch() / "refused";
  ndc::OutputOptions options;
  options.obj = true;
  CHECK_THROWS_AS(ndc::writeOutputs(out, three, options), ndc::InputError);
  CHECK(!fs::exists(out / "mesh.ply"));
  options.obj = false;
  options.vtk = true;
  CHECK(ndc::writeOutputs(out, three, options).at(1) == "mesh.vtu");
}

TEST_CASE("simplices: solve refuses --obj for k = 3 and --vtk for k = 4 before its work",
          "[cli][outputs][simplices]") {
  // A 3-sphere in R^4 and a 4-sphere in R^5 at a depth whose solve would take hours: the
  // refusal comes first, in one line, with status 2, and no output folder is made.
  struct Case {
    std::string toml, flag, message;
  };
  const std::vector<Case> cases = {
      {"name = \"s3\"\nvariables = [\"x\", \"y\", \"z\", \"w\"]\ndomain = [[-1, 1], [-1, 1], "
       "[-1, 1], [-1, 1]]\nequations = [\"x^2 + y^2 + z^2 + w^2 - 0.5\"]\n",
       "--obj", "--obj: OBJ has no cell for a 3-simplex (k = 3)"},
      {"name = \"s4\"\nvariables = [\"a\", \"b\", \"c\", \"d\", \"e\"]\ndomain = [[-1, 1], "
       "[-1, 1], [-1, 1], [-1, 1], [-1, 1]]\nequations = [\"a^2 + b^2 + c^2 + d^2 + e^2 - 0.5\"]\n",
       "--vtk", "--vtk: VTK has no cell for a 4-simplex (k = 4)"}};
  for (const Case& c : cases) {
    INFO(c.flag);
    const fs::path file = scratch() / (c.flag.substr(2) + ".toml");
    std::ofstream(file) << c.toml;
    const fs::path out = scratch() / ("refused" + c.flag);
    const auto run =
        ndc::test::runNdcontour("solve " + ndc::test::quoted(file.string()) + " --depth 12 " +
                                    c.flag + " --out " + ndc::test::quoted(out.string()),
                                scratch(), 60);
    CHECK(run.status == 2);
    CHECK(run.err.starts_with(file.string() + ": " + c.message));
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    CHECK(!fs::exists(out));
  }
}
