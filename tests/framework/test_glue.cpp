// Gluing the meshes of a split solve (framework/mesh/glue.hpp): grids of triangles cut along a
// plane, glued back with the same and with different vertices on the cut, and curves ending on
// it; pieces that do not meet are counted, never glued silently.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include "framework/mesh/glue.hpp"

namespace {

/// The triangulated rectangle [x0, x1] x [0, 1] in the plane z = 0 of R^3 with nx x ny cells
/// (two triangles each, all oriented alike), as a piece with the box [x0, x1] x [0, 1] x [-1, 1].
ndc::MeshPiece gridPiece(double x0, double x1, int nx, int ny) {
  ndc::MeshPiece piece;
  piece.box.lo = {x0, 0, -1};
  piece.box.hi = {x1, 1, 1};
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      // The ends exactly, as a piece puts its boundary vertices on its box's faces.
      const double x = i == nx ? x1 : x0 + (x1 - x0) * i / nx;
      piece.vertices.insert(piece.vertices.end(), {x, double(j) / ny, 0.0});
    }
  const auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      piece.simplices.insert(piece.simplices.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      piece.simplices.insert(piece.simplices.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return piece;
}

/// Euler characteristic, boundary edges and the largest number of triangles on one edge.
struct Shape {
  long euler = 0, boundaryEdges = 0, maxUses = 0;
};

Shape shapeOf(const ndc::GlueResult& g) {
  std::map<std::pair<int, int>, int> uses;
  for (std::size_t t = 0; t + 2 < g.simplices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const int a = g.simplices[t + e], b = g.simplices[t + (e + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  Shape s;
  const long v = static_cast<long>(g.vertices.size() / 3),
             f = static_cast<long>(g.simplices.size() / 3);
  s.euler = v - static_cast<long>(uses.size()) + f;
  for (const auto& [edge, count] : uses) {
    s.boundaryEdges += count == 1;
    s.maxUses = std::max<long>(s.maxUses, count);
  }
  return s;
}

}  // namespace

TEST_CASE("glue: two halves of a disk with the same cut vertices give the disk", "[glue][split]") {
  for (int ny : {1, 3, 8}) {
    const ndc::GlueResult g =
        ndc::gluePieces(3, 2, {gridPiece(0, 0.5, 4, ny), gridPiece(0.5, 1, 3, ny)}, 1e-9);
    CHECK(g.unmatched == 0);
    CHECK(g.reason.empty());
    CHECK(g.matched == ny + 1);
    CHECK(g.inserted == 0);
    const Shape s = shapeOf(g);
    CHECK(s.euler == 1);
    CHECK(s.boundaryEdges == 2 * ny + 2 * 7);
    CHECK(s.maxUses == 2);
    CHECK(g.vertices.size() / 3 == static_cast<std::size_t>((7 + 1) * (ny + 1)));
  }
}

TEST_CASE("glue: a side refined along the cut is matched by splitting the other side's triangles",
          "[glue][split]") {
  // Seeded: the coarse side has ny cells along the cut, the fine side a multiple of them, and
  // the fine side's shared vertices are moved by less than the tolerance.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    const int ny = 1 + static_cast<int>(rng() % 5), factor = 2 + static_cast<int>(rng() % 3);
    ndc::MeshPiece coarse = gridPiece(0.5, 1, 2, ny), fine = gridPiece(0, 0.5, 3, ny * factor);
    std::uniform_real_distribution<double> jiggle(-1e-12, 1e-12);
    for (std::size_t v = 0; v < fine.vertices.size(); v += 3) fine.vertices[v + 1] += jiggle(rng);
    const bool fineFirst = trial % 2 == 0;
    const auto pieces = fineFirst ? std::vector<ndc::MeshPiece>{fine, coarse}
                                  : std::vector<ndc::MeshPiece>{coarse, fine};
    const ndc::GlueResult g = ndc::gluePieces(3, 2, pieces, 1e-9);
    INFO("ny " << ny << ", factor " << factor);
    CHECK(g.unmatched == 0);
    CHECK(g.matched == ny + 1);
    CHECK(g.inserted == ny * (factor - 1));
    const Shape s = shapeOf(g);
    CHECK(s.euler == 1);
    CHECK(s.maxUses == 2);
    CHECK(s.boundaryEdges == 2 * (2 + 3) + ny + ny * factor);
  }
}

TEST_CASE("glue: pieces that do not meet on the cut are counted, not glued silently",
          "[glue][split]") {
  SECTION("a side without its half of the cut") {
    ndc::MeshPiece right = gridPiece(0.5, 1, 2, 2);
    // Moved off the cut by far more than the tolerance: a gap along the whole face.
    for (std::size_t v = 0; v < right.vertices.size(); v += 3)
      if (right.vertices[v] == 0.5) right.vertices[v] = 0.55;
    const ndc::GlueResult g = ndc::gluePieces(3, 2, {gridPiece(0, 0.5, 2, 2), right}, 1e-9);
    CHECK(g.unmatched == 2);
    CHECK(g.reason.find("other than two triangles") != std::string::npos);
  }
  SECTION("a polyline that is not along the other side's") {
    ndc::MeshPiece left = gridPiece(0, 0.5, 2, 2);
    // The middle vertex of the cut moved along z by a quarter of the cut's length: no edge of
    // the other side lies close enough to take it.
    for (std::size_t v = 0; v < left.vertices.size(); v += 3)
      if (left.vertices[v] == 0.5 && left.vertices[v + 1] == 0.5) left.vertices[v + 2] = 0.3;
    const ndc::GlueResult g = ndc::gluePieces(3, 2, {left, gridPiece(0.5, 1, 2, 2)}, 1e-9);
    CHECK(g.unmatched > 0);
  }
}

TEST_CASE("glue: curves end on the cut in points that pair up", "[glue][split]") {
  // Two arcs of a circle in the plane z = 0 of R^3 meeting x = 0 at (0, +-r): the left and
  // right halves, each a polyline from one crossing to the other.
  const double r = 0.7;
  const auto half = [&](double x0, double x1, int sign, int segments, double shift) {
    ndc::MeshPiece piece;
    piece.box.lo = {x0, -1, -1};
    piece.box.hi = {x1, 1, 1};
    for (int i = 0; i <= segments; ++i) {
      const double t = -M_PI / 2 + M_PI * i / segments;
      const double x = (i == 0 || i == segments) ? 0.0 : sign * r * std::cos(t);
      piece.vertices.insert(piece.vertices.end(), {x, r * std::sin(t) + shift, 0.0});
      if (i > 0) piece.simplices.insert(piece.simplices.end(), {i - 1, i});
    }
    return piece;
  };
  const ndc::GlueResult g =
      ndc::gluePieces(3, 1, {half(-1, 0, -1, 7, 0), half(0, 1, 1, 5, 1e-13)}, 1e-9);
  CHECK(g.unmatched == 0);
  CHECK(g.matched == 2);
  CHECK(g.vertices.size() / 3 == 12);
  CHECK(g.simplices.size() / 2 == 12);
  // A partner missing: one end left open on the cut.
  ndc::MeshPiece open = half(0, 1, 1, 5, 0);
  open.vertices[1] += 0.01;
  const ndc::GlueResult bad = ndc::gluePieces(3, 1, {half(-1, 0, -1, 7, 0), open}, 1e-9);
  CHECK(bad.unmatched == 2);
  CHECK(bad.reason.find("no partner") != std::string::npos);
}
