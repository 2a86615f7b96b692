// The problem's variable names in every output file (docs/contracts.md 4.4, "Names"), `u0 ..`
// alone where a run has no names or its names would repeat a name of the file; and the binary
// mesh.vtu (base64 and zlib blocks of vtkZLibDataCompressor, decoded by vtu_arrays.hpp) against
// the numbers of mesh.ply.
#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "framework/io/io.hpp"
#include "tests/framework/vtu_arrays.hpp"
#include "tests/test_process.hpp"

namespace fs = std::filesystem;

namespace {

using ndc::test::vtuArrays;

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("names");
  return dir.path();
}

/// A surface in R^4 (k = 2) with `count` x `count` vertices on a grid, named `names`, with one
/// singular point, one uncertified cell and two solution cells.
ndc::RunResult surface(std::vector<std::string> names, int count = 3) {
  ndc::RunResult r;
  r.n = r.summary.n = 4;
  r.k = r.summary.k = 2;
  r.summary.problem = "names";
  r.summary.variables = std::move(names);
  for (int i = 0; i < count; ++i)
    for (int j = 0; j < count; ++j)
      r.vertices.insert(r.vertices.end(), {i * 0.25, j * 0.5, 1.0 / (1 + i + j), -0.125 * i * j});
  for (int i = 0; i + 1 < count; ++i)
    for (int j = 0; j + 1 < count; ++j) {
      const int a = i * count + j;
      r.simplices.insert(r.simplices.end(), {a, a + count, a + 1, a + 1, a + count, a + count + 1});
    }
  r.cellIndex = {0, 0, 0, 0, 1, 0, 0, 0};
  r.cellCentre = {0.1, 0.1, 0.1, 0.1, 0.3, 0.1, 0.1, 0.1};
  r.cellPoint = {0.1, 0.1, 0.1, 0.1, 0.3, 0.1, 0.1, 0.1};
  r.cellClass = {ndc::CellClass::kNormal, ndc::CellClass::kAbnormal};
  r.summary.singularPoints = {{{0.25, 0.5, 0.5, -0.125}, 1e-9}};
  r.summary.topology.certified = false;
  r.summary.topology.uncertified = {{{0, 0, 0, -1}, {0.5, 0.5, 1, 0}, 3, "graph"}};
  return r;
}

using ndc::test::text;

/// The first line of `s`.
std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

std::string cellsCsv(const ndc::RunResult& r) { return text(r, ndc::writeCellsCsv); }
std::string singularCsv(const ndc::RunResult& r) { return text(r, ndc::writeSingularCsv); }
std::string uncertifiedCsv(const ndc::RunResult& r) { return text(r, ndc::writeUncertifiedCsv); }
std::string vtu(const ndc::RunResult& r, ndc::PlyFormat format = ndc::PlyFormat::binary) {
  std::ostringstream out;
  ndc::writeVtk(out, r, format);
  return out.str();
}
std::string ply(const ndc::RunResult& r) {
  std::ostringstream out;
  ndc::writePly(out, r, ndc::PlyFormat::ascii);
  return out.str();
}

/// The headers of the contract (docs/contracts.md 4.4), with no names.
const std::string kCells = "cell,i0,i1,i2,i3,c0,c1,c2,c3,class,p0,p1,p2,p3";
const std::string kSingular = "point,sigma_min,u0,u1,u2,u3";
const std::string kUncertified = "kind,level,reason,lo0,hi0,lo1,hi1,lo2,hi2,lo3,hi3";

}  // namespace

TEST_CASE("names: the variables' names in every output, beside u0 ..", "[io][names]") {
  const ndc::RunResult r = surface({"x", "y", "z", "w"});
  // summary.json: a list of strings.
  CHECK(ndc::toJson(r.summary).find("\n  \"variables\": [\"x\", \"y\", \"z\", \"w\"],\n") !=
        std::string::npos);
  // mesh.ply: a comment line; the properties stay u0 ...
  const std::string header = ply(r).substr(0, ply(r).find("end_header"));
  CHECK(header.find("\ncomment variables x y z w\n") != std::string::npos);
  CHECK(header.find("property double u3\n") != std::string::npos);
  CHECK(header.find("property double w\n") == std::string::npos);
  // mesh.vtu: the arrays u0 .. and one per name with the same values.
  const auto arrays = vtuArrays(vtu(r));
  for (int j = 0; j < 4; ++j) {
    const std::string name(1, "xyzw"[j]);
    INFO(name);
    REQUIRE(arrays.count(name) == 1);
    CHECK(arrays.at(name) == arrays.at("u" + std::to_string(j)));
  }
  CHECK(vtu(r).find("the coordinates in R^n, also named x y z w -->") != std::string::npos);
  // The CSV files: the contract's columns, then the names.
  CHECK(firstLine(cellsCsv(r)) == kCells + ",i_x,i_y,i_z,i_w,c_x,c_y,c_z,c_w,p_x,p_y,p_z,p_w");
  CHECK(firstLine(singularCsv(r)) == kSingular + ",x,y,z,w");
  CHECK(firstLine(uncertifiedCsv(r)) == kUncertified + ",lo_x,hi_x,lo_y,hi_y,lo_z,hi_z,lo_w,hi_w");
  // Each alias column repeats its contract column.
  std::istringstream rows(singularCsv(r));
  std::string line;
  std::getline(rows, line);
  std::getline(rows, line);
  CHECK(line == "0,1.0000000000000001e-09,0.25,0.5,0.5,-0.125,0.25,0.5,0.5,-0.125");
  const std::string cell = uncertifiedCsv(r).substr(uncertifiedCsv(r).find('\n') + 1);
  CHECK(firstLine(cell) == "cell,3,graph,0,0.5,0,0.5,0,1,-1,0,0,0.5,0,0.5,0,1,-1,0");
  const std::string cells = cellsCsv(r).substr(cellsCsv(r).find('\n') + 1);
  CHECK(firstLine(cells) ==
        "0,0,0,0,0,0.10000000000000001,0.10000000000000001,0.10000000000000001,"
        "0.10000000000000001,normal,0.10000000000000001,0.10000000000000001,"
        "0.10000000000000001,0.10000000000000001,0,0,0,0,0.10000000000000001,"
        "0.10000000000000001,0.10000000000000001,0.10000000000000001,0.10000000000000001,"
        "0.10000000000000001,0.10000000000000001,0.10000000000000001");
  // readPly reads the file with the comment as before.
  const fs::path file = scratch() / "named.ply";
  std::ofstream(file, std::ios::binary) << ply(r);
  CHECK(ndc::readPly(file).u.size() == 9);
}

TEST_CASE("names: u0 .. alone without names, or where a name would repeat one of the file",
          "[io][names]") {
  // No names (a run built without a problem), names that are u0 .. already, names that repeat a
  // column of the file: the contract's files exactly, and summary.json keeps the names it has.
  for (const std::vector<std::string>& names :
       std::vector<std::vector<std::string>>{{}, {"u0", "u1", "u2", "u3"}}) {
    const ndc::RunResult r = surface(names);
    CHECK(ply(r).find("comment variables") == std::string::npos);
    CHECK(firstLine(cellsCsv(r)) == kCells);
    CHECK(firstLine(singularCsv(r)) == kSingular);
    CHECK(firstLine(uncertifiedCsv(r)) == kUncertified);
    CHECK(vtuArrays(vtu(r)).size() == 4 + 1 + 2 + 1 + 3);  // u, singular, cell data, points, cells
  }
  CHECK(ndc::toJson(surface({}).summary).find("\"variables\"") == std::string::npos);
  // u1 before u0: the names are kept in the PLY comment and summary.json, not as columns.
  const ndc::RunResult swapped = surface({"u1", "u0", "a", "b"});
  CHECK(ply(swapped).find("\ncomment variables u1 u0 a b\n") != std::string::npos);
  CHECK(firstLine(singularCsv(swapped)) == kSingular);
  CHECK(vtuArrays(vtu(swapped)).count("a") == 0);
  // `class` and `sigma_min` repeat names of singular.csv and mesh.vtu only: the files whose
  // aliases have a prefix take the names.
  const ndc::RunResult classy = surface({"class", "sigma_min", "c", "d"});
  CHECK(firstLine(cellsCsv(classy)).starts_with(kCells + ",i_class,i_sigma_min,i_c,i_d,c_class"));
  CHECK(firstLine(singularCsv(classy)) == kSingular);
  CHECK(firstLine(uncertifiedCsv(classy)) ==
        kUncertified + ",lo_class,hi_class,lo_sigma_min,hi_sigma_min,lo_c,hi_c,lo_d,hi_d");
  CHECK(vtuArrays(vtu(classy)).count("class") == 1);  // the cell data only
  CHECK(vtuArrays(vtu(classy)).count("sigma_min") == 0);
}

TEST_CASE("names: the binary mesh.vtu holds exactly the numbers of mesh.ply", "[io][names]") {
  // 60 x 60 vertices: the points' array is 86400 bytes, three zlib blocks.
  const ndc::RunResult r = surface({"x", "y", "z", "w"}, 60);
  const std::string xml = vtu(r);
  CHECK(xml.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos);
  CHECK(xml.find("header_type=\"UInt64\"") != std::string::npos);
  CHECK(xml.find("format=\"ascii\"") == std::string::npos);
  const auto arrays = vtuArrays(xml);
  const fs::path file = scratch() / "grid.ply";
  {
    std::ofstream out(file, std::ios::binary);
    ndc::writePly(out, r);
  }
  const ndc::PlyMesh mesh = ndc::readPly(file);
  REQUIRE(arrays.at("Points").size() == 3 * mesh.xyz.size());
  const std::vector<std::string> u = {"u0", "u1", "u2", "u3"};
  for (std::size_t v = 0; v < mesh.xyz.size(); ++v)
    for (int c = 0; c < 3; ++c) {
      CHECK(arrays.at("Points")[3 * v + c] == mesh.xyz[v][c]);
      CHECK(arrays.at(u[c])[v] == mesh.u[v][c]);
    }
  REQUIRE(arrays.at("connectivity").size() == 3 * mesh.simplices.size());
  for (std::size_t s = 0; s < mesh.simplices.size(); ++s)
    for (int c = 0; c < 3; ++c) CHECK(arrays.at("connectivity")[3 * s + c] == mesh.simplices[s][c]);
  CHECK(arrays.at("offsets").back() == 3.0 * mesh.simplices.size());
  CHECK(arrays.at("types") == std::vector<double>(mesh.simplices.size(), 5.0));
  CHECK(arrays.at("singular").size() == mesh.xyz.size());
  CHECK(arrays.at("class").size() == mesh.simplices.size());
  CHECK(arrays.at("uncertified").size() == mesh.simplices.size());
  // ASCII (`--ascii`): the same numbers, no compressor.
  const std::string ascii = vtu(r, ndc::PlyFormat::ascii);
  CHECK(ascii.find("compressor") == std::string::npos);
  CHECK(ascii.find("format=\"binary\"") == std::string::npos);
  CHECK(vtuArrays(ascii) == arrays);
  // Smaller: compressed binary against ASCII.
  CHECK(xml.size() < ascii.size() / 2);
  // An empty mesh: empty arrays are written as ASCII (readers refuse a binary array of 0 blocks).
  ndc::RunResult empty;
  empty.n = empty.summary.n = 3;
  empty.k = empty.summary.k = 1;
  CHECK(vtu(empty).find("format=\"binary\"") == std::string::npos);
}

TEST_CASE("names: a solve writes the problem's names into every file", "[cli][names]") {
  // A curve in R^5 (x1 .. x5) with every optional file.
  const fs::path out = scratch() / "circle";
  const auto run = ndc::test::runNdcontour(
      "solve " +
          ndc::test::quoted(std::string(NDC_SOURCE_DIR) + "/experiments/problems/circle-r5.toml") +
          " --depth 3 --vtk --obj --cells --out " + ndc::test::quoted(out.string()),
      scratch());
  REQUIRE(run.status == 0);
  CHECK(ndc::test::slurp(out / "summary.json")
            .find("\"variables\": [\"x1\", \"x2\", \"x3\", \"x4\", \"x5\"]") != std::string::npos);
  CHECK(ndc::test::slurp(out / "mesh.ply").find("\ncomment variables x1 x2 x3 x4 x5\n") !=
        std::string::npos);
  CHECK(firstLine(ndc::test::slurp(out / "singular.csv")) ==
        "point,sigma_min,u0,u1,u2,u3,u4,x1,x2,x3,x4,x5");
  CHECK(firstLine(ndc::test::slurp(out / "cells.csv")).ends_with(",p_x5"));
  const auto arrays = vtuArrays(ndc::test::slurp(out / "mesh.vtu"));
  CHECK(arrays.at("x5") == arrays.at("u4"));
  CHECK(arrays.at("types").size() == arrays.at("class").size());
}

TEST_CASE("names: a split solve reads its pieces' uncertified.csv with the names' columns",
          "[cli][names][split]") {
  // The unit circle on [-1, 1]^2 touches the domain's faces: 8 cells stay uncertified, in one
  // solve and in 4 pieces glued (their uncertified.csv carry lo_x, hi_x, .. after lo0, hi0, ..).
  const fs::path problem = scratch() / "tangent.toml";
  std::ofstream(problem) << "name = \"tangent-circle\"\nvariables = [\"x\", \"y\"]\n"
                            "domain = [[-1, 1], [-1, 1]]\nequations = [\"x^2 + y^2 - 1\"]\n";
  const auto cellRows = [](const fs::path& csv) {
    std::istringstream in(ndc::test::slurp(csv));
    int rows = 0;
    for (std::string line; std::getline(in, line);) rows += line.starts_with("cell,");
    return rows;
  };
  for (const std::string split : {"", " --split 4"}) {
    INFO(split);
    const fs::path out = scratch() / ("tangent" + std::to_string(split.size()));
    const auto run =
        ndc::test::runNdcontour("solve " + ndc::test::quoted(problem.string()) + " --depth 4" +
                                    split + " --out " + ndc::test::quoted(out.string()),
                                scratch());
    REQUIRE(run.status == 0);
    CHECK(firstLine(ndc::test::slurp(out / "uncertified.csv")) ==
          "kind,level,reason,lo0,hi0,lo1,hi1,lo_x,hi_x,lo_y,hi_y");
    CHECK(cellRows(out / "uncertified.csv") == 8);
    CHECK(ndc::test::slurp(out / "summary.json").find("\"uncertified_cells\": 8") !=
          std::string::npos);
  }
}
