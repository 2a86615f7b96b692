// The PLY files of a run (io.hpp, docs/contracts.md 4.4) in-process: the ASCII writer's exact
// text (what `--ascii` has always written), the binary writer's header, size and bytes, readPly
// on both encodings and on PLY files of other writers, and readPly's one-line errors for
// truncated, garbled and absurd files.
#include <catch2/catch.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "framework/io/io.hpp"
#include "framework/util/errors.hpp"
#include "tests/test_process.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("ply");
  return dir.path();
}

/// Writes `bytes` to a scratch file and returns its path.
fs::path spit(const std::string& name, const std::string& bytes) {
  const fs::path file = scratch() / name;
  std::ofstream(file, std::ios::binary) << bytes;
  return file;
}

/// A curve in R^2 (k = 1): three vertices, two segments.
ndc::RunResult curve() {
  ndc::RunResult r;
  r.n = r.summary.n = 2;
  r.k = r.summary.k = 1;
  r.summary.problem = "curve";
  r.vertices = {0.1, -2.5, 1e-300, 3, 1.0 / 3, -0.75};
  r.simplices = {0, 1, 1, 2};
  return r;
}

/// A surface in R^3 (k = 2): four vertices, two triangles.
ndc::RunResult surface() {
  ndc::RunResult r;
  r.n = r.summary.n = 3;
  r.k = r.summary.k = 2;
  r.summary.problem = "surface";
  r.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.5};
  r.simplices = {0, 1, 2, 0, 1, 3};
  return r;
}

std::string plyText(const ndc::RunResult& r, ndc::PlyFormat format) {
  std::ostringstream out;
  ndc::writePly(out, r, format);
  return out.str();
}

const std::string kVersion = std::string("comment ndcontour ") + NDC_VERSION + " problem ";

/// The headers writePly has always written, and what follows them in ASCII.
const std::string kCurveHeader =
    "element vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
    "property double u0\nproperty double u1\nelement edge 2\nproperty int vertex1\n"
    "property int vertex2\nend_header\n";
const std::string kCurveAscii =
    "0.10000000000000001 -2.5 0 0.10000000000000001 -2.5\n1e-300 3 0 1e-300 3\n"
    "0.33333333333333331 -0.75 0 0.33333333333333331 -0.75\n0 1\n1 2\n";
const std::string kSurfaceHeader =
    "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
    "property double u0\nproperty double u1\nproperty double u2\nelement face 2\n"
    "property list uchar int vertex_indices\nend_header\n";
const std::string kSurfaceAscii =
    "0 0 0 0 0 0\n1 0 0 1 0 0\n0 1 0 0 1 0\n0 0 0.5 0 0 0.5\n3 0 1 2\n3 0 1 3\n";

/// The little-endian value of type T at `at` of `bytes`, whatever the machine's byte order.
template <class T>
T little(const std::string& bytes, std::size_t at) {
  using U = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
  U u = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i)
    u |= static_cast<U>(static_cast<unsigned char>(bytes.at(at + i))) << (8 * i);
  return std::bit_cast<T>(u);
}

/// Appends the little-endian bytes of `v`.
template <class T>
void put(std::string& bytes, T v) {
  using U = std::conditional_t<sizeof(T) == 8, std::uint64_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint8_t>>;
  const U u = std::bit_cast<U>(v);
  for (std::size_t i = 0; i < sizeof(T); ++i) bytes += static_cast<char>((u >> (8 * i)) & 0xff);
}

/// The message of the InputError readPly throws on `file` ("" when it reads it).
std::string readError(const fs::path& file) {
  try {
    ndc::readPly(file);
  } catch (const ndc::InputError& e) {
    return e.what();
  }
  return "";
}

/// readPly refuses `bytes` with one line naming the file and holding `part`.
void refused(const std::string& name, const std::string& bytes, const std::string& part) {
  const fs::path file = spit(name, bytes);
  const std::string message = readError(file);
  INFO(name << ": " << message);
  CHECK(message.rfind(file.string() + ": ", 0) == 0);
  CHECK(message.find('\n') == std::string::npos);
  CHECK(message.find(part) != std::string::npos);
}

/// `text` with its first `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("ply: --ascii writes exactly the ASCII PLY of earlier versions", "[ply]") {
  CHECK(plyText(curve(), ndc::PlyFormat::ascii) ==
        "ply\nformat ascii 1.0\n" + kVersion + "curve\n" + kCurveHeader + kCurveAscii);
  CHECK(plyText(surface(), ndc::PlyFormat::ascii) ==
        "ply\nformat ascii 1.0\n" + kVersion + "surface\n" + kSurfaceHeader + kSurfaceAscii);
  ndc::TriangleSoup soup;
  soup.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.25}};
  soup.triangles = {{0, 1, 2}};
  soup.part = {7};
  std::ostringstream input;
  ndc::writeInputPly(input, soup, ndc::PlyFormat::ascii);
  CHECK(input.str() ==
        "ply\nformat ascii 1.0\ncomment ndcontour input surfaces\nelement vertex 3\n"
        "property double x\nproperty double y\nproperty double z\nelement face 1\n"
        "property list uchar int vertex_indices\nproperty int part\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0.25\n3 0 1 2 7\n");
}

TEST_CASE("ply: binary PLY by default, its header, size and bytes", "[ply]") {
  // The curve: 3 vertices of 5 doubles, 2 edges of 2 ints.
  const std::string c = plyText(curve(), ndc::PlyFormat::binary);
  const std::string curveHeader =
      "ply\nformat binary_little_endian 1.0\n" + kVersion + "curve\n" + kCurveHeader;
  REQUIRE(c.rfind(curveHeader, 0) == 0);
  CHECK(c.size() == curveHeader.size() + 3 * 5 * 8 + 2 * 2 * 4);
  std::size_t at = curveHeader.size();
  CHECK(little<double>(c, at) == 0.1);
  CHECK(little<double>(c, at + 8) == -2.5);
  CHECK(little<double>(c, at + 16) == 0.0);  // z of a point in R^2
  CHECK(little<double>(c, at + 40) == 1e-300);
  at += 3 * 5 * 8;
  CHECK(little<std::int32_t>(c, at + 8) == 1);
  CHECK(little<std::int32_t>(c, at + 12) == 2);
  // The default is binary.
  std::ostringstream byDefault;
  ndc::writePly(byDefault, curve());
  CHECK(byDefault.str() == c);

  // The surface: 4 vertices of 6 doubles, 2 faces of a uchar 3 and 3 ints.
  const std::string s = plyText(surface(), ndc::PlyFormat::binary);
  const std::string surfaceHeader =
      "ply\nformat binary_little_endian 1.0\n" + kVersion + "surface\n" + kSurfaceHeader;
  REQUIRE(s.rfind(surfaceHeader, 0) == 0);
  CHECK(s.size() == surfaceHeader.size() + 4 * 6 * 8 + 2 * (1 + 3 * 4));
  at = surfaceHeader.size() + 4 * 6 * 8 + 13;
  CHECK(s[at] == 3);
  CHECK(little<std::int32_t>(s, at + 1) == 0);
  CHECK(little<std::int32_t>(s, at + 5) == 1);
  CHECK(little<std::int32_t>(s, at + 9) == 3);
}

TEST_CASE("ply: readPly reads the binary and the ASCII file of a mesh alike", "[ply]") {
  for (const ndc::RunResult& r : {curve(), surface()}) {
    INFO(r.summary.problem);
    const ndc::PlyMesh a = ndc::readPly(spit("a.ply", plyText(r, ndc::PlyFormat::ascii)));
    const ndc::PlyMesh b = ndc::readPly(spit("b.ply", plyText(r, ndc::PlyFormat::binary)));
    const std::size_t n = static_cast<std::size_t>(r.n), corners = r.k + 1u;
    REQUIRE(b.xyz.size() == r.vertices.size() / n);
    for (std::size_t v = 0; v < b.xyz.size(); ++v) {
      CHECK(b.u[v] ==
            std::vector<double>(r.vertices.begin() + v * n, r.vertices.begin() + (v + 1) * n));
      for (std::size_t j = 0; j < 3; ++j) CHECK(b.xyz[v][j] == (j < n ? b.u[v][j] : 0.0));
    }
    REQUIRE(b.simplices.size() == r.simplices.size() / corners);
    for (std::size_t s = 0; s < b.simplices.size(); ++s)
      CHECK(b.simplices[s] == std::vector<int>(r.simplices.begin() + s * corners,
                                               r.simplices.begin() + (s + 1) * corners));
    CHECK(a.xyz == b.xyz);
    CHECK(a.u == b.u);
    CHECK(a.simplices == b.simplices);
  }
  // input.ply: faces with a `part` after the list.
  ndc::TriangleSoup soup;
  soup.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.25}, {2, 2, 2}};
  soup.triangles = {{0, 1, 2}, {1, 2, 3}};
  soup.part = {0, 1};
  for (const ndc::PlyFormat format : {ndc::PlyFormat::ascii, ndc::PlyFormat::binary}) {
    std::ostringstream text;
    ndc::writeInputPly(text, soup, format);
    if (format == ndc::PlyFormat::binary)
      CHECK(text.str().size() == text.str().find("end_header\n") + 11 + 4 * 24 + 2 * 17);
    const ndc::PlyMesh m = ndc::readPly(spit("input.ply", text.str()));
    CHECK(m.xyz == soup.vertices);
    CHECK(m.simplices == std::vector<std::vector<int>>{{0, 1, 2}, {1, 2, 3}});
  }
}

TEST_CASE("ply: readPly reads other writers' types, elements and properties", "[ply]") {
  std::string bytes =
      "ply\r\nformat binary_little_endian 1.0\r\ncomment another writer\r\nelement vertex 2\r\n"
      "property float x\r\nproperty float y\r\nproperty float z\r\nproperty uchar red\r\n"
      "property double u0\r\nelement material 1\r\nproperty list uchar float weights\r\n"
      "element face 1\r\nproperty uint flags\r\nproperty list int uint vertex_indices\r\n"
      "end_header\r\n";
  for (float x : {1.0f, 2.0f, 3.0f}) put(bytes, x);
  put(bytes, std::uint8_t{255});
  put(bytes, 0.5);
  for (float x : {4.0f, 5.0f, 6.0f}) put(bytes, x);
  put(bytes, std::uint8_t{0});
  put(bytes, -0.5);
  put(bytes, std::uint8_t{2});
  put(bytes, 1.5f);
  put(bytes, 2.5f);
  put(bytes, std::uint32_t{9});
  put(bytes, std::int32_t{3});
  for (std::uint32_t v : {0u, 1u, 1u}) put(bytes, v);
  const ndc::PlyMesh m = ndc::readPly(spit("other.ply", bytes));
  CHECK(m.xyz == std::vector<std::array<double, 3>>{{1, 2, 3}, {4, 5, 6}});
  CHECK(m.u == std::vector<std::vector<double>>{{0.5}, {-0.5}});
  CHECK(m.simplices == std::vector<std::vector<int>>{{0, 1, 1}});
  // ASCII: `null` (how writePly spells a value that is not finite) is NaN; blanks and tabs; a
  // leading +.
  const ndc::PlyMesh n =
      ndc::readPly(spit("null.ply",
                        "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\n"
                        "property double y\nproperty double z\nend_header\nnull\t+2  3\n"));
  REQUIRE(n.xyz.size() == 1);
  CHECK(std::isnan(n.xyz[0][0]));
  CHECK(n.xyz[0][1] == 2);
  CHECK(n.xyz[0][2] == 3);
}

TEST_CASE("ply: truncated, garbled and absurd files are one-line errors", "[ply]") {
  const std::string c = plyText(curve(), ndc::PlyFormat::binary);
  const std::string s = plyText(surface(), ndc::PlyFormat::binary);
  // Every prefix of a binary file is refused, in the header or in the body.
  for (std::size_t cut = 0; cut < c.size(); ++cut) {
    const fs::path file = spit("cut.ply", c.substr(0, cut));
    const std::string message = readError(file);
    INFO("cut at " << cut << ": " << message);
    CHECK(message.rfind(file.string() + ": ", 0) == 0);
    CHECK(message.find('\n') == std::string::npos);
  }
  refused("short.ply", c.substr(0, c.size() - 1), "element 'edge' declares 2 records, more than");
  refused("extra.ply", c + "x", "1 bytes after the last element");
  refused("absurd.ply", replaced(c, "element vertex 3", "element vertex 3000000000000"),
          "element 'vertex' declares 3000000000000 records");
  refused("overflow.ply", replaced(c, "element vertex 3", "element vertex 99999999999999999999"),
          "bad element count '99999999999999999999'");
  refused("negative-count.ply", replaced(c, "element vertex 3", "element vertex -3"),
          "bad element count '-3'");
  std::string index = c;
  index.replace(index.size() - 4, 4, std::string("\x03\0\0\0", 4));
  refused("index.ply", index, "edge 2 of 2 (byte ");
  refused("index.ply", index, "vertex index 3 is out of range (3 vertices)");
  index.replace(index.size() - 4, 4, std::string("\xff\xff\xff\xff", 4));
  refused("index.ply", index, "vertex index -1 is out of range");
  refused("big.ply", replaced(c, "binary_little_endian", "binary_big_endian"),
          "binary_big_endian PLY is not read");
  refused("version.ply", replaced(c, "endian 1.0", "endian 2.0"), "unknown PLY format");
  refused("magic.ply", replaced(c, "ply\n", "plx\n"), "not a PLY file");
  refused("empty.ply", "", "not a PLY file");
  refused("no-format.ply", replaced(c, "format binary_little_endian 1.0\n", ""),
          "the header has no format line");
  refused("no-end.ply", "ply\nformat ascii 1.0\nelement vertex 0\n", "no end_header");
  refused("type.ply", replaced(c, "property double x", "property quad x"),
          "unknown property type 'quad'");
  refused("keyword.ply", replaced(c, "property double x", "propety double x"),
          "bad header line 'propety double x'");
  refused("no-x.ply", replaced(c, "property double x", "property double w"),
          "vertex lacks x, y or z");
  refused("no-list.ply", replaced(s, "vertex_indices", "corners"),
          "face lacks the list vertex_indices");
  // List lengths: negative, or beyond the end of the file.
  std::string length = replaced(s, "list uchar int", "list char int");
  std::size_t faces = length.find("end_header\n") + 11 + 4 * 6 * 8;
  length[faces] = '\xff';
  refused("list-negative.ply", length,
          "face 1 of 2 (byte " + std::to_string(faces) + "): list length -1");
  length = s;
  faces = s.find("end_header\n") + 11 + 4 * 6 * 8;
  length[faces] = static_cast<char>(200);
  refused("list-long.ply", length,
          "face 1 of 2 (byte " + std::to_string(faces) + "): the file ends inside it");

  // ASCII: the same checks, with line numbers.
  const std::string a = plyText(curve(), ndc::PlyFormat::ascii);
  refused("ascii-short.ply", a.substr(0, a.size() - 4),
          "ends inside element 'edge' (after 1 of 2 records)");
  refused("ascii-value.ply", replaced(a, "1e-300 3 0", "1e-300 three 0"),
          "vertex 2 of 3 (line 15): a missing or bad value in '1e-300 three 0 1e-300 3'");
  refused("ascii-fraction.ply", replaced(a, "\n1 2\n", "\n1 2.5\n"),
          "edge 2 of 2 (line 18): a missing or bad value");
  refused("ascii-index.ply", replaced(a, "\n1 2\n", "\n1 7\n"),
          "edge 2 of 2 (line 18): vertex index 7 is out of range (3 vertices)");
  refused("ascii-absurd.ply", replaced(a, "element edge 2", "element edge 2000"),
          "element 'edge' declares 2000 records");
  CHECK(readError(scratch() / "no-such-file.ply") ==
        (scratch() / "no-such-file.ply").string() +
            ": cannot read the file: No such file or directory");
}
