// The mesh in the formats of other tools (docs/contracts.md 4.4): VTK XML (mesh.vtu, for
// ParaView and meshio), legacy VTK (mesh.vtk) and Wavefront OBJ (mesh.obj), each for the
// dimensions k its cells can hold (formatRefusal).
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "framework/io/io.hpp"
#include "framework/io/variable_names.hpp"
#include "framework/io/vertex_rows.hpp"
#include "framework/util/base64.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

namespace {

/// A double in the shortest form that reads back to the same value.
void put(std::ostream& out, double v) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
  out.write(buffer, end - buffer);
}

std::size_t simplexCount(const RunResult& r) { return r.simplices.size() / (r.k + 1); }

/// The VTK cell type of a k-simplex: VTK_LINE, VTK_TRIANGLE or VTK_TETRA. For k >= 4, which
/// VTK has no cell for, InputError naming `file` and the option `flag` that asked for it.
std::uint8_t vtkCellType(int k, const char* file, const char* flag) {
  const std::string refusal = formatRefusal(flag, k);
  if (!refusal.empty()) throw InputError(std::string(file) + ": " + refusal);
  return k == 1 ? 3 : k == 2 ? 5 : 10;
}

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

/// The DataArrays of mesh.vtu, ASCII (`--ascii`) or binary: each array's bytes in blocks of
/// 32 KiB compressed with zlib, after the header of vtkZLibDataCompressor (UInt64: the block
/// count, the block size, the size of the last block when partial, then each compressed size),
/// header and blocks in base64 apart, as VTK writes them. An empty array is written as ASCII
/// (an empty binary array has no blocks, which some readers refuse).
class VtkArrays {
 public:
  VtkArrays(std::ostream& out, PlyFormat format) : out_(out), ascii_(format == PlyFormat::ascii) {}

  /// One DataArray of `values` (Float64, Int32, Int64 or UInt8 as `type` says); `name` empty
  /// for none; `components` per tuple.
  template <class T>
  void write(const char* type, const std::string& name, const std::vector<T>& values,
             int components = 1) {
    const bool ascii = ascii_ || values.empty();
    out_ << "        <DataArray type=\"" << type << '"';
    if (!name.empty()) out_ << " Name=\"" << name << '"';
    if (components != 1) out_ << " NumberOfComponents=\"" << components << '"';
    out_ << " format=\"" << (ascii ? "ascii" : "binary") << "\">\n";
    if (ascii)
      text(values, components);
    else
      binary(values.data(), values.size() * sizeof(T));
    out_ << "\n        </DataArray>\n";
  }

 private:
  /// ASCII values, `components` per tuple and a few tuples per line.
  template <class T>
  void text(const std::vector<T>& values, int components) {
    const std::size_t line = components == 1 ? 8 : static_cast<std::size_t>(components);
    for (std::size_t i = 0; i < values.size(); ++i) {
      if constexpr (std::is_floating_point_v<T>)
        put(out_, values[i]);
      else
        out_ << static_cast<std::int64_t>(values[i]);
      out_ << (i % line == line - 1 ? '\n' : ' ');
    }
  }

  /// The bytes compressed in blocks, header and data each in base64.
  void binary(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    const std::size_t blocks = (size + kBlock - 1) / kBlock;
    std::vector<std::uint64_t> header = {blocks, kBlock, size % kBlock};
    std::vector<unsigned char> packed;
    std::vector<unsigned char> block(compressBound(kBlock));
    for (std::size_t b = 0; b < blocks; ++b) {
      // Block b: zlib at its fastest level (doubles of coordinates shrink by about a tenth at
      // any level; the default level takes twice the time for 1 % more).
      const std::size_t length = std::min(kBlock, size - b * kBlock);
      uLongf written = static_cast<uLongf>(block.size());
      if (compress2(block.data(), &written, bytes + b * kBlock, static_cast<uLong>(length),
                    Z_BEST_SPEED) != Z_OK)
        throw std::runtime_error("mesh.vtu: zlib could not compress a block");
      header.push_back(written);
      packed.insert(packed.end(), block.begin(),
                    block.begin() + static_cast<std::ptrdiff_t>(written));
    }
    out_ << "          ";
    out_ << base64(header.data(), header.size() * 8) << base64(packed.data(), packed.size());
  }

  static constexpr std::size_t kBlock = std::size_t{1} << 15;
  std::ostream& out_;
  bool ascii_;
};

/// The point-data arrays of the coordinates, each a name and its column of VertexRows: the
/// contract's `u0 ..` and `x2 y2 z2`, then the variables' names as aliases of `u0 ..` where
/// none repeats a name of the file.
std::vector<std::pair<std::string, std::size_t>> coordinateArrays(const RunResult& r, bool second) {
  std::vector<std::pair<std::string, std::size_t>> arrays;
  std::vector<std::string> taken = {"singular", "class", "uncertified"};
  for (int j = 0; j < r.n + (second ? 3 : 0); ++j) {
    const std::string name =
        j < r.n ? "u" + std::to_string(j) : std::string(1, "xyz"[j - r.n]) + "2";
    arrays.emplace_back(name, 3 + j);
    taken.push_back(name);
  }
  const std::vector<std::string> aliases = aliasNames(r, "", taken);
  for (std::size_t j = 0; j < aliases.size(); ++j) arrays.emplace_back(aliases[j], 3 + j);
  return arrays;
}

/// The `<!-- -->` line of mesh.vtu: where its numbers come from.
std::string vtkComment(const RunResult& r) {
  std::string line = "<!-- ndcontour " + std::string(NDC_VERSION) + " problem " +
                     r.summary.problem + ": points are x y z as in mesh.ply; u0.. the " +
                     "coordinates in R^n";
  const std::vector<std::string> names = variableNames(r);
  if (!names.empty()) {
    line += ", also named";
    for (const std::string& name : names) line += ' ' + name;
  }
  return line + " -->\n";
}

}  // namespace

void writeVtk(std::ostream& out, const RunResult& r, PlyFormat format) {
  const std::uint8_t cellType = vtkCellType(r.k, "mesh.vtu", "--vtk");
  VertexRows rows(r);
  const std::size_t points = rows.count(), count = simplexCount(r);
  const int width = r.k + 1;
  const bool little = std::endian::native == std::endian::little;
  out << "<?xml version=\"1.0\"?>\n"
      << vtkComment(r) << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\""
      << (little ? "LittleEndian" : "BigEndian") << '"'
      << (format == PlyFormat::ascii
              ? ""
              : " header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"")
      << ">\n  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << points << "\" NumberOfCells=\"" << count << "\">\n"
      << "      <PointData>\n";
  VtkArrays arrays(out, format);
  // The vertex rows by column: x y z, then u0 .. (and x2 y2 z2).
  std::vector<std::vector<double>> column(rows.width(), std::vector<double>(points));
  for (std::size_t v = 0; v < points; ++v) {
    const auto row = rows(v);
    for (std::size_t c = 0; c < row.size(); ++c) column[c][v] = row[c];
  }
  // One array per coordinate u_j (and the second image's x2 y2 z2), then the variables' names
  // (the same values as u_j), then the singular flag.
  for (const auto& [name, c] : coordinateArrays(r, rows.second()))
    arrays.write("Float64", name, column[c]);
  arrays.write("Int32", "singular", singularVertices(r));
  out << "      </PointData>\n      <CellData>\n";
  arrays.write("Int32", "class", simplexClasses(r));
  arrays.write("Int32", "uncertified", uncertifiedSimplices(r));
  out << "      </CellData>\n      <Points>\n";
  std::vector<double> xyz(3 * points);
  for (std::size_t v = 0; v < points; ++v)
    for (int c = 0; c < 3; ++c) xyz[3 * v + c] = column[c][v];
  arrays.write("Float64", "", xyz, 3);
  out << "      </Points>\n      <Cells>\n";
  arrays.write("Int64", "connectivity",
               std::vector<std::int64_t>(r.simplices.begin(), r.simplices.end()));
  std::vector<std::int64_t> offsets(count);
  for (std::size_t s = 0; s < count; ++s) offsets[s] = static_cast<std::int64_t>((s + 1) * width);
  arrays.write("Int64", "offsets", offsets);
  arrays.write("UInt8", "types", std::vector<std::uint8_t>(count, cellType));
  out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
}

namespace {

/// One FIELD array of a legacy VTK file: its line, then the values, a few per line.
template <class T>
void legacyArray(std::ostream& out, const std::string& name, const std::vector<T>& values) {
  out << name << " 1 " << values.size() << (std::is_floating_point_v<T> ? " double\n" : " int\n");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if constexpr (std::is_floating_point_v<T>)
      put(out, values[i]);
    else
      out << values[i];
    out << (i % 8 == 7 || i + 1 == values.size() ? '\n' : ' ');
  }
}

}  // namespace

void writeLegacyVtk(std::ostream& out, const RunResult& r) {
  const int cellType = vtkCellType(r.k, "mesh.vtk", "--vtk-legacy");
  VertexRows rows(r);
  const std::size_t points = rows.count(), count = simplexCount(r);
  const int width = r.k + 1;
  const std::vector<std::string> names = variableNames(r);
  // The header: version, title (one line), encoding, dataset.
  out << "# vtk DataFile Version 4.2\nndcontour " << NDC_VERSION << " problem " << r.summary.problem
      << ": points x y z as in mesh.ply; u0.. the coordinates in R^n";
  if (!names.empty()) out << ", also named";
  for (const std::string& name : names) out << ' ' << name;
  out << "\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS " << points << " double\n";
  std::vector<std::vector<double>> column(rows.width(), std::vector<double>(points));
  for (std::size_t v = 0; v < points; ++v) {
    const auto row = rows(v);
    for (std::size_t c = 0; c < row.size(); ++c) column[c][v] = row[c];
    for (int c = 0; c < 3; ++c) {
      put(out, row[c]);
      out << (c == 2 ? '\n' : ' ');
    }
  }
  // The simplices: each its vertex count and vertices; VTK_LINE, VTK_TRIANGLE or VTK_TETRA.
  out << "CELLS " << count << ' ' << count * (width + 1) << '\n';
  for (std::size_t s = 0; s < count; ++s) {
    out << width;
    for (int t = 0; t < width; ++t) out << ' ' << r.simplices[s * width + t];
    out << '\n';
  }
  out << "CELL_TYPES " << count << '\n';
  for (std::size_t s = 0; s < count; ++s) out << cellType << '\n';
  // The arrays of mesh.vtu, by the same names.
  const auto arrays = coordinateArrays(r, rows.second());
  out << "POINT_DATA " << points << "\nFIELD FieldData " << arrays.size() + 1 << '\n';
  for (const auto& [name, c] : arrays) legacyArray(out, name, column[c]);
  legacyArray(out, "singular", singularVertices(r));
  out << "CELL_DATA " << count << "\nFIELD FieldData 2\n";
  legacyArray(out, "class", simplexClasses(r));
  legacyArray(out, "uncertified", uncertifiedSimplices(r));
}

void writeObj(std::ostream& out, const RunResult& r) {
  const std::string refusal = formatRefusal("--obj", r.k);
  if (!refusal.empty()) throw InputError("mesh.obj: " + refusal);
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

std::string formatRefusal(const std::string& flag, int k) {
  const std::string simplex = "a " + std::to_string(k) + "-simplex (k = " + std::to_string(k) + ")";
  if ((flag == "--vtk" || flag == "--vtk-legacy") && k >= 4)
    return flag + ": VTK has no cell for " + simplex +
           ", its cells end at the tetrahedron (k = 3); mesh.ply holds the mesh (k + 1 vertex "
           "indices per face, docs/contracts.md 4.4)";
  if (flag == "--obj" && k >= 3)
    return flag + ": OBJ has no cell for " + simplex +
           ", only points, lines and faces (k <= 2); mesh.ply holds the mesh" +
           (k == 3 ? ", and --vtk writes its tetrahedra" : "");
  return "";
}

}  // namespace ndc
