// The mesh in the formats of other tools (docs/contracts.md 4.4): VTK XML (mesh.vtu, for
// ParaView and meshio) and Wavefront OBJ (mesh.obj).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "framework/io/io.hpp"
#include "framework/io/vertex_rows.hpp"

namespace ndc {

namespace {

/// A double in the shortest form that reads back to the same value.
void put(std::ostream& out, double v) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
  out.write(buffer, end - buffer);
}

std::size_t simplexCount(const RunResult& r) { return r.simplices.size() / (r.k + 1); }

/// The longest edge of the mesh (max-norm in R^n): the scale within which a vertex stands for a
/// point of M.
double longestEdge(const RunResult& r) {
  double longest = 0;
  const int width = r.k + 1;
  for (std::size_t s = 0; s < r.simplices.size() / width; ++s)
    for (int a = 0; a < width; ++a)
      for (int b = a + 1; b < width; ++b) {
        const std::size_t u = r.simplices[s * width + a], v = r.simplices[s * width + b];
        for (int j = 0; j < r.n; ++j)
          longest = std::max(longest, std::abs(r.vertices[u * r.n + j] - r.vertices[v * r.n + j]));
      }
  return longest;
}

/// Per vertex: 1 at the vertex nearest to each located singular point of M, when it lies within
/// one edge length of it (the mesh of the perturbed level set is joined there).
std::vector<int> singularVertices(const RunResult& r) {
  std::vector<int> flag(r.n ? r.vertices.size() / r.n : 0, 0);
  if (r.summary.singularPoints.empty() || flag.empty()) return flag;
  const double reach = longestEdge(r);
  for (const SingularPoint& p : r.summary.singularPoints) {
    std::size_t nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < flag.size(); ++v) {
      double gap = 0;
      for (int j = 0; j < r.n; ++j)
        gap = std::max(gap, std::abs(r.vertices[v * r.n + j] - p.point[j]));
      if (gap < best) best = gap, nearest = v;
    }
    if (best <= reach) flag[nearest] = 1;
  }
  return flag;
}

/// The centroid of simplex s (n coordinates).
std::vector<double> centroid(const RunResult& r, std::size_t s) {
  std::vector<double> c(r.n, 0.0);
  const int width = r.k + 1;
  for (int t = 0; t < width; ++t) {
    const std::size_t v = static_cast<std::size_t>(r.simplices[s * width + t]);
    for (int j = 0; j < r.n; ++j) c[j] += r.vertices[v * r.n + j] / width;
  }
  return c;
}

/// Per simplex: 1 where its centroid lies in a cell left uncertified (uncertified.csv).
std::vector<int> uncertifiedSimplices(const RunResult& r) {
  std::vector<int> flag(simplexCount(r), 0);
  const auto& boxes = r.summary.topology.uncertified;
  if (boxes.empty()) return flag;
  for (std::size_t s = 0; s < flag.size(); ++s) {
    const std::vector<double> c = centroid(r, s);
    for (const UncertifiedCell& box : boxes) {
      bool inside = true;
      for (int j = 0; j < r.n && inside; ++j) inside = c[j] >= box.lo[j] && c[j] <= box.hi[j];
      if (inside) {
        flag[s] = 1;
        break;
      }
    }
  }
  return flag;
}

/// Per simplex: the class of the solution cell of the base grid (`--depth`) that holds its
/// centroid (0 normal, 1 abnormal, 2 failed; -1 where that base cell is not a solution cell,
/// as for a piece of M found by refinement next to it). The grid is recovered from the solution
/// cells' indices and centres; along an axis where every solution cell has the same index, that
/// index is the only one a piece of M in them can have.
std::vector<int> simplexClasses(const RunResult& r) {
  std::vector<int> out(simplexCount(r), -1);
  const std::size_t cells = r.cellClass.size();
  if (!cells) return out;
  const int n = r.n;
  std::vector<double> width(n, 0.0), origin(n, 0.0);
  for (int j = 0; j < n; ++j) {
    for (std::size_t c = 1; c < cells && width[j] == 0; ++c) {
      const int di = r.cellIndex[c * n + j] - r.cellIndex[j];
      if (di) width[j] = (r.cellCentre[c * n + j] - r.cellCentre[j]) / di;
    }
    if (width[j] != 0) origin[j] = r.cellCentre[j] - (r.cellIndex[j] + 0.5) * width[j];
  }
  std::map<std::vector<std::int32_t>, int> classOf;
  for (std::size_t c = 0; c < cells; ++c)
    classOf.emplace(
        std::vector<std::int32_t>(r.cellIndex.begin() + c * n, r.cellIndex.begin() + (c + 1) * n),
        static_cast<int>(r.cellClass[c]));
  std::vector<std::int32_t> index(n);
  for (std::size_t s = 0; s < out.size(); ++s) {
    const std::vector<double> x = centroid(r, s);
    for (int j = 0; j < n; ++j)
      index[j] = width[j] != 0
                     ? static_cast<std::int32_t>(std::floor((x[j] - origin[j]) / width[j]))
                     : r.cellIndex[j];
    const auto it = classOf.find(index);
    if (it != classOf.end()) out[s] = it->second;
  }
  return out;
}

/// One DataArray of integers.
void intArray(std::ostream& out, const char* type, const std::string& name,
              const std::vector<std::int64_t>& values) {
  out << "        <DataArray type=\"" << type << "\" Name=\"" << name << "\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < values.size(); ++i) out << values[i] << (i % 16 == 15 ? '\n' : ' ');
  out << "\n        </DataArray>\n";
}

std::vector<std::int64_t> widen(const std::vector<int>& v) { return {v.begin(), v.end()}; }

}  // namespace

void writeVtk(std::ostream& out, const RunResult& r) {
  VertexRows rows(r);
  const std::size_t points = rows.count(), count = simplexCount(r);
  const int width = r.k + 1;
  out << "<?xml version=\"1.0\"?>\n"
      << "<!-- ndcontour " << NDC_VERSION << " problem " << r.summary.problem
      << ": points are x y z as in mesh.ply; u0.. the coordinates in R^n -->\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << points << "\" NumberOfCells=\"" << count << "\">\n"
      << "      <PointData>\n";
  // One array per coordinate u_j (and the second image's x2 y2 z2), then the singular flag.
  const std::size_t columns = rows.width();
  for (std::size_t c = 3; c < columns; ++c) {
    const std::size_t j = c - 3;
    const std::string name = j < static_cast<std::size_t>(r.n)
                                 ? "u" + std::to_string(j)
                                 : std::string(1, "xyz"[j - r.n]) + "2";
    out << "        <DataArray type=\"Float64\" Name=\"" << name << "\" format=\"ascii\">\n";
    for (std::size_t v = 0; v < points; ++v) {
      put(out, rows(v)[c]);
      out << (v % 8 == 7 ? '\n' : ' ');
    }
    out << "\n        </DataArray>\n";
  }
  intArray(out, "Int32", "singular", widen(singularVertices(r)));
  out << "      </PointData>\n      <CellData>\n";
  intArray(out, "Int32", "class", widen(simplexClasses(r)));
  intArray(out, "Int32", "uncertified", widen(uncertifiedSimplices(r)));
  out << "      </CellData>\n      <Points>\n"
      << "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t v = 0; v < points; ++v) {
    const auto row = rows(v);
    for (int c = 0; c < 3; ++c) {
      put(out, row[c]);
      out << (c == 2 ? '\n' : ' ');
    }
  }
  out << "        </DataArray>\n      </Points>\n      <Cells>\n";
  intArray(out, "Int64", "connectivity",
           std::vector<std::int64_t>(r.simplices.begin(), r.simplices.end()));
  std::vector<std::int64_t> offsets(count), types(count, r.k == 1 ? 3 : 5);  // VTK_LINE, _TRIANGLE
  for (std::size_t s = 0; s < count; ++s) offsets[s] = static_cast<std::int64_t>((s + 1) * width);
  intArray(out, "Int64", "offsets", offsets);
  intArray(out, "UInt8", "types", types);
  out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
}

void writeObj(std::ostream& out, const RunResult& r) {
  VertexRows rows(r);
  out << "# ndcontour " << NDC_VERSION << " problem " << r.summary.problem << ": v is x y z as in "
      << "mesh.ply (the coordinates in R^n are in mesh.ply and mesh.vtu)\n";
  for (std::size_t v = 0; v < rows.count(); ++v) {
    const auto row = rows(v);
    out << "v ";
    for (int c = 0; c < 3; ++c) {
      put(out, row[c]);
      out << (c == 2 ? '\n' : ' ');
    }
  }
  const int width = r.k + 1;
  for (std::size_t s = 0; s < simplexCount(r); ++s) {
    out << (r.k == 1 ? "l" : "f");
    for (int t = 0; t < width; ++t) out << ' ' << r.simplices[s * width + t] + 1;  // 1-based
    out << '\n';
  }
}

}  // namespace ndc
