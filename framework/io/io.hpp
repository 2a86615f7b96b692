/// \file io.hpp
/// Output files of a run (docs/contracts.md 4.3-4.5): summary.json, mesh.ply (binary or ASCII
/// PLY), cells.csv, singular.csv and uncertified.csv; and the PLY reader the report uses
/// (readPly, in framework/io/ply_read.cpp).
#pragma once

#include <array>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "framework/io/result.hpp"

namespace ndc {

/// The encoding of a PLY file (docs/contracts.md 4.4): `binary_little_endian 1.0` (the
/// default of `solve --out`) or `ascii 1.0` (`solve --ascii`).
enum class PlyFormat { binary, ascii };

/// Writes the mesh as PLY: vertices with float64 `x y z` (the first three coordinates,
/// zero-padded for n = 2, or an application's image in R^3), `u0 .. u{n-1}` (and `x2 y2 z2` for
/// an application with a second image); `face` with `list uchar int vertex_indices` (k >= 2: a
/// triangle, a tetrahedron for k = 3, k + 1 indices for any k) or `edge` with `int vertex1,
/// vertex2` (k = 1). Binary data goes out in one write per element.
void writePly(std::ostream& out, const RunResult& result, PlyFormat format = PlyFormat::binary);

/// Writes an application's input surfaces (`input.ply`): vertices `x y z`, faces with
/// `vertex_indices` and `int part` (which surface or instance).
void writeInputPly(std::ostream& out, const TriangleSoup& input,
                   PlyFormat format = PlyFormat::binary);

/// Writes `ruled.ply` of a convex-hull result: per polyline edge (a, b) the two triangles of the
/// quad S1(a) S2(a) S2(b) S1(b) of bitangent segments. Needs the application's second image.
void writeRuledPly(std::ostream& out, const RunResult& result,
                   PlyFormat format = PlyFormat::binary);

/// Writes the mesh as VTK XML, an `UnstructuredGrid` for ParaView and meshio (`mesh.vtu`,
/// `--vtk`): the points `x y z` of mesh.ply, VTK_TETRA (k = 3), VTK_TRIANGLE (k = 2) or VTK_LINE
/// (k = 1) cells (InputError for k >= 4: formatRefusal), the point data
/// `u0 .. u{n-1}` (and `x2 y2 z2`), the same coordinates once more under the problem's variable
/// names (where they repeat no other name) and `singular` (1 at the vertex nearest to a located
/// singular point, within one edge length), the cell data `class` (of the base solution cell
/// holding the simplex: 0 normal, 1 abnormal, 2 failed, -1 none) and `uncertified` (1 inside a
/// cell of uncertified.csv). Binary data compressed with zlib (vtkZLibDataCompressor, base64
/// inline) by default, ASCII data with PlyFormat::ascii (`--ascii`).
void writeVtk(std::ostream& out, const RunResult& result, PlyFormat format = PlyFormat::binary);

/// Writes the mesh as legacy VTK (`mesh.vtk`, `--vtk-legacy`; `# vtk DataFile Version 4.2`,
/// ASCII, an UNSTRUCTURED_GRID): the points, cells and arrays of writeVtk, the arrays as FIELD
/// data. A format that meshio reads curves from besides VTU (its PLY reader knows no `edge`
/// element and its OBJ reader no `l` record). InputError for k >= 4, as writeVtk.
void writeLegacyVtk(std::ostream& out, const RunResult& result);

/// Writes the mesh as Wavefront OBJ (`mesh.obj`, `--obj`): `v x y z` per vertex as in mesh.ply,
/// then `f a b c` (k = 2) or `l a b` (k = 1) with 1-based vertex numbers. InputError for k >= 3
/// (formatRefusal).
void writeObj(std::ostream& out, const RunResult& result);

/// Why the mesh file of option `flag` (`--vtk`, `--vtk-legacy`, `--obj`) cannot hold a mesh of
/// dimension k, as one sentence starting with `flag`; empty when it can. VTK's cells end at the
/// tetrahedron (k <= 3), OBJ has points, lines and faces (k <= 2); mesh.ply holds any k.
/// `solve` refuses such an option before its work (exit status 2), the writers throw.
std::string formatRefusal(const std::string& flag, int k);

/// Writes cells.csv: cell number, multi-index, centre, class, projected point.
void writeCellsCsv(std::ostream& out, const RunResult& result);

/// Writes singular.csv: the header `point,sigma_min,u0,..,u{n-1}`, then one row per located
/// singular point of M (its number, the smallest singular value of the Jacobian there, and its
/// n coordinates). Only the header when there is none.
void writeSingularCsv(std::ostream& out, const RunResult& result);

/// Writes uncertified.csv: the header `kind,level,reason,lo0,hi0,..`, then one row per cell
/// left uncertified at the maximum depth (`cell`, its level, which part of the certificate
/// failed, its box) and one per located singular point (`singular_point`, sigma_min, the point
/// as a box of width 0). Written only when the run is not certified.
void writeUncertifiedCsv(std::ostream& out, const RunResult& result);

/// `s` as a JSON string literal (quotes, backslashes and control characters escaped).
std::string jsonQuoted(const std::string& s);

/// Writes `text` to `target` through a temporary file in the same directory renamed into place,
/// so that a reader never sees half a file and a failure leaves the previous file alone. Throws
/// ndc::InputError when the file cannot be written.
void writeAtomically(const std::filesystem::path& target, const std::string& text);

/// What writeOutputs writes besides the files every run has.
struct OutputOptions {
  /// The encoding of mesh.ply, input.ply and ruled.ply, and of mesh.vtu's arrays (`--ascii`).
  PlyFormat format = PlyFormat::binary;
  bool cells = false;      ///< whether to write cells.csv (`--cells`)
  bool vtk = false;        ///< whether to write mesh.vtu (`--vtk`)
  bool legacyVtk = false;  ///< whether to write mesh.vtk (`--vtk-legacy`)
  bool obj = false;        ///< whether to write mesh.obj (`--obj`)
};

/// Writes mesh.ply, mesh.vtu, mesh.vtk and mesh.obj (only with `options.vtk`,
/// `options.legacyVtk`, `options.obj`), cells.csv (only with `options.cells`), singular.csv,
/// uncertified.csv when the run is not certified (input.ply and ruled.ply for applications that
/// have them) and last summary.json into `dir` (created if needed); returns the file names
/// written, in that order. Every file is first written into a hidden staging folder in `dir`
/// (`.ndcontour-partial-PID`): a full disk or an interrupt there leaves the previous run whole.
/// Then, with SIGINT and SIGTERM blocked, the previous summary.json is removed and the files
/// are renamed into place, summary.json (whose presence marks a finished run) last. Throws
/// ndc::InputError if `dir` cannot be written. A file of an earlier run that this run does not
/// write (cells.csv without `cells`, mesh.vtu, mesh.vtk, mesh.obj, input.ply, ruled.ply,
/// uncertified.csv) is removed: the folder then holds exactly this run's files.
std::vector<std::string> writeOutputs(const std::filesystem::path& dir, const RunResult& result,
                                      const OutputOptions& options = {});

/// Installs SIGINT and SIGTERM handlers for a `solve`: they remove writeOutputs' staging
/// folder if one is being written and exit with status 128 + the signal (130, 143) at once.
/// Nothing in `--out` has been touched before the outputs are published, so earlier results
/// stay as they were.
void installInterruptCleanup();

/// Arms a wall-clock limit of `seconds` for a `solve`: when it expires, the staging folder of
/// writeOutputs (if one is being written) is removed, `line` is printed on standard error and
/// the process exits with `status`. An expiry while the outputs are being published waits for
/// the publication to end and is then ignored: the run finished.
void armTimeout(double seconds, const std::string& line, int status);

/// Stops the limit of armTimeout: the run is finished and only prints what it found.
void disarmTimeout();

/// A mesh read back from a `mesh.ply` (docs/contracts.md 4.4): per vertex `x y z` and the
/// point in R^n (`u0 .. u{n-1}`), and the simplices as vertex indices: segments (k = 1),
/// triangles (k = 2), k + 1 indices for any k.
struct PlyMesh {
  std::vector<std::array<double, 3>> xyz;   ///< the 3-D image of each vertex
  std::vector<std::vector<double>> u;       ///< the point in R^n of each vertex
  std::vector<std::vector<int>> simplices;  ///< k + 1 vertex indices each
};

/// Reads a PLY as writePly writes it (e.g. `mesh.ply` of `ndcontour solve`), ASCII or
/// binary_little_endian: the `vertex` element's `x y z` and `u0, u1, ..` properties, and `edge`
/// (`vertex1 vertex2`) or `face` (the `vertex_indices` list) elements; other elements and
/// properties are skipped. Throws ndc::InputError (`FILE: message`, one line) when the file
/// cannot be read, is not PLY, is big-endian, has a bad header line or type, declares more
/// records than the file can hold, ends early, has a bad value, an index out of range or
/// bytes after the last element (binary), or its vertices lack `x y z`. Memory is bounded by
/// the file's size, never by a count in its header.
PlyMesh readPly(const std::filesystem::path& file);

}  // namespace ndc
