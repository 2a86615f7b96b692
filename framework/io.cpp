#include "io.hpp"

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "problem.hpp"

namespace ndc {
namespace {

std::string number(double v) {
  if (!std::isfinite(v)) return "null";  // JSON has no inf/nan
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

/// Writes `text` to `dir/name` through a temporary file renamed into place.
void writeAtomically(const std::filesystem::path& dir, const std::string& name,
                     const std::string& text) {
  const auto target = dir / name;
  const auto temporary = dir / ("." + name + ".tmp" + std::to_string(::getpid()));
  {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw InputError(target.string() + ": cannot write the file");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, target, error);
  if (error) throw InputError(target.string() + ": cannot write the file: " + error.message());
}

}  // namespace

std::string toJson(const Summary& s) {
  std::ostringstream o;
  const Settings& t = s.settings;
  o << "{\n  \"schema\": \"ndcontour.summary/1\",\n  \"problem\": " << quoted(s.problem)
    << ",\n  \"n\": " << s.n << ",\n  \"k\": " << s.k << ",\n";
  o << "  \"settings\": {\"depth\": " << t.depth << ", \"bounding\": " << quoted(t.bounding)
    << ", \"subdivision\": " << quoted(t.subdivision) << ", \"scalar\": " << quoted(t.scalar)
    << ", \"precision_bits\": " << t.precisionBits << ", \"projection\": " << quoted(t.projection)
    << ", \"classification\": " << quoted(t.classification)
    << ", \"connection\": " << quoted(t.connection)
    << ", \"jitter\": " << (t.jitter ? std::to_string(*t.jitter) : "null") << "},\n";
  o << "  \"cells\": {\"visited\": " << s.visited << ", \"solution\": " << s.solution
    << ", \"normal\": " << s.normal << ", \"abnormal\": " << s.abnormal
    << ", \"failed\": " << s.failed << "},\n";
  const MeshStats& m = s.mesh;
  o << "  \"mesh\": {\"vertices\": " << m.vertices << ", \"edges\": " << m.edges
    << ", \"triangles\": " << m.triangles << ", \"components\": " << m.components
    << ", \"boundary_edges\": " << m.boundaryEdges
    << ", \"nonmanifold_edges\": " << m.nonmanifoldEdges
    << ", \"euler_characteristic\": " << m.eulerCharacteristic << ", \"open_ends\": " << m.openEnds
    << ", \"branch_vertices\": " << m.branchVertices << "},\n";
  o << "  \"accuracy\": {\"max_residual\": " << number(m.maxResidual)
    << ", \"max_chord_error\": " << number(m.maxChordError) << "},\n";
  o << "  \"diagnostics\": {\"ambiguous_cells\": " << s.ambiguousCells
    << ", \"singular_cells\": " << s.singularCells << ", \"chord_failures\": " << m.chordFailures
    << "},\n";
  o << "  \"timing_s\": {\"subdivision\": " << number(s.tSubdivision)
    << ", \"projection\": " << number(s.tProjection)
    << ", \"connection\": " << number(s.tConnection) << ", \"analysis\": " << number(s.tAnalysis)
    << ", \"total\": " << number(s.tTotal) << "}\n}\n";
  return o.str();
}

void writePly(std::ostream& out, const RunResult& r) {
  const std::size_t vertexCount = r.n ? r.vertices.size() / r.n : 0;
  const std::size_t simplexCount = r.simplices.size() / (r.k + 1);
  out << "ply\nformat ascii 1.0\ncomment ndcontour " << NDC_VERSION << " problem "
      << r.summary.problem << "\nelement vertex " << vertexCount << "\n";
  out << "property double x\nproperty double y\nproperty double z\n";
  for (int j = 0; j < r.n; ++j) out << "property double u" << j << "\n";
  if (r.k == 1) {
    out << "element edge " << simplexCount << "\nproperty int vertex1\nproperty int vertex2\n";
  } else {
    out << "element face " << simplexCount << "\nproperty list uchar int vertex_indices\n";
  }
  out << "end_header\n";
  for (std::size_t v = 0; v < vertexCount; ++v) {
    const double* p = r.vertices.data() + v * r.n;
    // The 3-D image: the first three coordinates, zero-padded.
    for (int j = 0; j < 3; ++j) out << number(j < r.n ? p[j] : 0.0) << ' ';
    for (int j = 0; j < r.n; ++j) out << number(p[j]) << (j + 1 < r.n ? ' ' : '\n');
  }
  for (std::size_t s = 0; s < simplexCount; ++s) {
    const std::int32_t* v = r.simplices.data() + s * (r.k + 1);
    if (r.k == 1) {
      out << v[0] << ' ' << v[1] << '\n';
    } else {
      out << r.k + 1;
      for (int i = 0; i <= r.k; ++i) out << ' ' << v[i];
      out << '\n';
    }
  }
}

void writeCellsCsv(std::ostream& out, const RunResult& r) {
  out << "cell";
  for (int j = 0; j < r.n; ++j) out << ",i" << j;
  for (int j = 0; j < r.n; ++j) out << ",c" << j;
  out << ",class";
  for (int j = 0; j < r.n; ++j) out << ",p" << j;
  out << '\n';
  for (std::size_t c = 0; c < r.cellClass.size(); ++c) {
    out << c;
    for (int j = 0; j < r.n; ++j) out << ',' << r.cellIndex[c * r.n + j];
    for (int j = 0; j < r.n; ++j) out << ',' << number(r.cellCentre[c * r.n + j]);
    out << ',' << className(r.cellClass[c]);
    for (int j = 0; j < r.n; ++j) out << ',' << number(r.cellPoint[c * r.n + j]);
    out << '\n';
  }
}

void writeOutputs(const std::filesystem::path& dir, const RunResult& result) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error || !std::filesystem::is_directory(dir)) {
    throw InputError(dir.string() + ": cannot create the output directory");
  }
  std::ostringstream ply, csv;
  writePly(ply, result);
  writeCellsCsv(csv, result);
  writeAtomically(dir, "mesh.ply", ply.str());
  writeAtomically(dir, "cells.csv", csv.str());
  // summary.json last: its presence marks a finished run.
  writeAtomically(dir, "summary.json", toJson(result.summary));
}

}  // namespace ndc
