#include "framework/io/io.hpp"

#include "framework/problem/application.hpp"

#include <signal.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "framework/io/summary_schema.hpp"
#include "framework/io/variable_names.hpp"
#include "framework/io/vertex_rows.hpp"
#include "framework/problem/problem.hpp"
#include "framework/util/errors.hpp"

namespace ndc {
namespace {

std::string number(double v) {
  if (!std::isfinite(v)) return "null";  // JSON has no inf/nan
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

/// Paths an interrupt must remove: the staging folder of writeOutputs and its files, kept as
/// plain character arrays so that the signal handler only calls unlink, rmdir and _exit.
struct InterruptCleanup {
  static constexpr std::size_t kPaths = 12, kLength = 4096;  // every output file
  std::array<std::array<char, kLength>, kPaths> files{};
  std::array<char, kLength> folder{};
  volatile sig_atomic_t count = 0;
  /// The line armTimeout's alarm prints, its exit status, and whether the outputs are already
  /// published (an alarm held back by the publication then has nothing left to stop).
  std::array<char, kLength> timeoutLine{};
  volatile sig_atomic_t timeoutStatus = 0;
  volatile sig_atomic_t published = 0;
};
InterruptCleanup cleanup;

void copyPath(std::array<char, InterruptCleanup::kLength>& to, const std::filesystem::path& p) {
  const std::string s = p.string();
  const std::size_t n = std::min(s.size(), to.size() - 1);
  std::memcpy(to.data(), s.data(), n);
  to[n] = '\0';
}

/// Removes the staging folder (only async-signal-safe calls).
void removeStaging() {
  for (sig_atomic_t i = 0; i < cleanup.count; ++i) ::unlink(cleanup.files[i].data());
  if (cleanup.folder[0] != '\0') ::rmdir(cleanup.folder.data());
}

extern "C" void onInterrupt(int signal) {
  removeStaging();
  ::_exit(128 + signal);
}

extern "C" void onTimeout(int) {
  if (cleanup.published) return;
  removeStaging();
  const char* line = cleanup.timeoutLine.data();
  std::size_t length = 0;
  while (line[length] != '\0') ++length;
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, line, length);
  ::_exit(cleanup.timeoutStatus);
}

/// Blocks SIGINT, SIGTERM and armTimeout's SIGALRM for its lifetime (the few renames that
/// publish a run).
class BlockInterrupts {
 public:
  BlockInterrupts() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGALRM);
    ::sigprocmask(SIG_BLOCK, &set, &saved_);
  }
  ~BlockInterrupts() { ::sigprocmask(SIG_SETMASK, &saved_, nullptr); }
  BlockInterrupts(const BlockInterrupts&) = delete;
  BlockInterrupts& operator=(const BlockInterrupts&) = delete;

 private:
  sigset_t saved_;
};

std::string numberList(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + number(values[i]);
  return out + "]";
}

std::string integerList(const std::vector<std::int64_t>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i)
    out += (i ? ", " : "") + std::to_string(values[i]);
  return out + "]";
}

std::string stringList(const std::vector<std::string>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + jsonQuoted(values[i]);
  return out + "]";
}

}  // namespace

std::string jsonQuoted(const std::string& s) {
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

void writeAtomically(const std::filesystem::path& target, const std::string& text) {
  const auto temporary = target.parent_path() /
                         ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()));
  {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      const std::string reason = failureReason();  // before remove() sets errno
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw InputError(target.string() + ": cannot write the file: " + reason);
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, target, error);
  if (error) throw InputError(target.string() + ": cannot write the file: " + error.message());
}

namespace {

/// The part of `path` before its last dot ("" at the top).
std::string_view parentPath(std::string_view path) {
  const std::size_t dot = path.rfind('.');
  return dot == std::string_view::npos ? std::string_view() : path.substr(0, dot);
}

/// The part of `path` after its last dot: the field's name in its object.
std::string_view fieldName(std::string_view path) {
  const std::size_t dot = path.rfind('.');
  return dot == std::string_view::npos ? path : path.substr(dot + 1);
}

/// Whether `f` is the element of a list (`PATH[]`) or a map (`PATH.*`), not a field of its own.
bool isElement(const SummaryField& f) { return f.path.ends_with("[]") || f.path.ends_with(".*"); }

/// The field of kSummaryFields with exactly this path (a list's element `PATH[]`, a map's value
/// `PATH.*`).
const SummaryField& schemaField(std::string_view path) {
  for (const SummaryField& f : kSummaryFields)
    if (f.path == path) return f;
  throw std::logic_error("summary schema: no field " + std::string(path));
}

/// Two spaces per level of `path` (one level per dot, plus one).
std::string indentOf(std::string_view path) {
  return std::string(2 * (std::count(path.begin(), path.end(), '.') + 1), ' ');
}

/// Writes summary.json by walking kSummaryFields: the top-level fields one per line, nested
/// objects on one line (a field laid out on a new line starts one, indented by its level), the
/// elements of a list one per line.
class SummaryWriter {
 public:
  SummaryWriter(std::ostream& out, const Summary& s) : o_(out), s_(s) {}

  /// The whole document.
  void document() {
    o_ << "{\n";
    bool first = true;
    for (const SummaryField& f : kSummaryFields) {
      if (!parentPath(f.path).empty()) continue;
      const SummaryValue v = valueOf(f, 0);
      if (std::holds_alternative<SummaryAbsent>(v)) continue;
      o_ << (first ? "  \"" : ",\n  \"") << fieldName(f.path) << "\": ";
      write(f, v, 0);
      first = false;
    }
    o_ << "\n}\n";
  }

 private:
  SummaryValue valueOf(const SummaryField& f, std::size_t element) const {
    if (f.meshStat) return s_.mesh.*f.meshStat;
    return f.value ? f.value(s_, element) : SummaryValue(nullptr);
  }

  /// The fields of object `path` (of the list's or map's element `element`) as `{...}`.
  void object(std::string_view path, std::size_t element) {
    o_ << '{';
    bool first = true;
    for (const SummaryField& f : kSummaryFields) {
      if (parentPath(f.path) != path || isElement(f)) continue;
      const SummaryValue v = valueOf(f, element);
      if (std::holds_alternative<SummaryAbsent>(v)) continue;
      if (!first) o_ << (f.layout == SummaryLayout::newLine ? ",\n" + indentOf(f.path) : ", ");
      o_ << '"' << fieldName(f.path) << "\": ";
      write(f, v, element);
      first = false;
    }
    o_ << '}';
  }

  /// The value `v` of field `f`.
  void write(const SummaryField& f, const SummaryValue& v, std::size_t element) {
    switch (f.type) {
      case SummaryType::object:
        return object(f.path, element);
      case SummaryType::list:
        return list(f, std::get<SummaryKeys>(v).keys.size());
      case SummaryType::map:
        return map(f, std::get<SummaryKeys>(v).keys);
      default:
        return leaf(v);
    }
  }

  /// A list of objects, one element per line.
  void list(const SummaryField& f, std::size_t count) {
    const std::string element = std::string(f.path) + "[]";
    const std::string indent = indentOf(f.path) + "  ";
    o_ << '[';
    for (std::size_t i = 0; i < count; ++i) {
      o_ << (i ? ",\n" : "\n") << indent;
      object(element, i);
    }
    o_ << (count ? "\n" + indentOf(f.path) + "]" : std::string("]"));
  }

  /// An object whose keys come from the run, each with the value of the field `PATH.*`.
  void map(const SummaryField& f, const std::vector<std::string>& keys) {
    const SummaryField& value = schemaField(std::string(f.path) + ".*");
    o_ << '{';
    for (std::size_t i = 0; i < keys.size(); ++i) {
      o_ << (i ? ", " : "") << jsonQuoted(keys[i]) << ": ";
      write(value, valueOf(value, i), i);
    }
    o_ << '}';
  }

  /// A value that is not a container.
  void leaf(const SummaryValue& v) {
    if (std::holds_alternative<std::nullptr_t>(v)) o_ << "null";
    if (const bool* b = std::get_if<bool>(&v)) o_ << (*b ? "true" : "false");
    if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) o_ << *i;
    if (const std::uint64_t* u = std::get_if<std::uint64_t>(&v)) o_ << std::to_string(*u);
    if (const double* x = std::get_if<double>(&v)) o_ << number(*x);
    if (const std::string* t = std::get_if<std::string>(&v)) o_ << jsonQuoted(*t);
    if (const auto* list = std::get_if<std::vector<double>>(&v)) o_ << numberList(*list);
    if (const auto* list = std::get_if<std::vector<std::int64_t>>(&v)) o_ << integerList(*list);
    if (const auto* list = std::get_if<std::vector<std::string>>(&v)) o_ << stringList(*list);
    if (const SummaryJson* json = std::get_if<SummaryJson>(&v)) o_ << json->text;
  }

  std::ostream& o_;
  const Summary& s_;
};

}  // namespace

std::string toJson(const Summary& s) {
  std::ostringstream o;
  SummaryWriter(o, s).document();
  return o.str();
}

namespace {

/// The `format` line of a PLY header.
const char* formatLine(PlyFormat format) {
  return format == PlyFormat::ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
}

/// Binary PLY data (little endian) streamed to a stream through a buffer of fixed size: a mesh
/// of any size is written without a buffer of its own size (allocating and zeroing 26 MB for
/// the torus at depth 8 cost about as much as writing it).
class BinaryBlock {
 public:
  explicit BinaryBlock(std::ostream& out) : out_(out), data_(new char[kBytes]) {}

  template <class T>
  void put(T value) {
    if (used_ + sizeof value > kBytes) flush();
    char* at = data_.get() + used_;
    std::memcpy(at, &value, sizeof value);
    if constexpr (std::endian::native == std::endian::big) std::reverse(at, at + sizeof value);
    used_ += sizeof value;
  }
  void put(std::span<const double> values) {
    for (double v : values) put(v);
  }

  /// Writes what is still buffered.
  void flush() {
    out_.write(data_.get(), static_cast<std::streamsize>(used_));
    used_ = 0;
  }

 private:
  static constexpr std::size_t kBytes = std::size_t{1} << 18;
  std::ostream& out_;
  std::unique_ptr<char[]> data_;
  std::size_t used_ = 0;
};

/// The header of mesh.ply.
void meshHeader(std::ostream& out, const RunResult& r, const VertexRows& rows, PlyFormat format) {
  const ApplicationData* app = r.application.get();
  out << "ply\n"
      << formatLine(format) << "comment ndcontour " << NDC_VERSION << " problem "
      << r.summary.problem << "\n";
  if (app)
    out << "comment application " << app->name
        << ": x y z is the image in R^3, u0.. the surface parameters\n";
  // The variables' names of u0 .. (an extension: x y z are taken by the 3-D image).
  const std::vector<std::string> names = variableNames(r);
  if (!names.empty()) {
    out << "comment variables";
    for (const std::string& name : names) out << ' ' << name;
    out << "\n";
  }
  out << "element vertex " << rows.count() << "\n";
  out << "property double x\nproperty double y\nproperty double z\n";
  for (int j = 0; j < r.n; ++j) out << "property double u" << j << "\n";
  if (rows.second()) out << "property double x2\nproperty double y2\nproperty double z2\n";
  const std::size_t simplexCount = r.simplices.size() / (r.k + 1);
  if (r.k == 1) {
    out << "element edge " << simplexCount << "\nproperty int vertex1\nproperty int vertex2\n";
  } else {
    out << "element face " << simplexCount << "\nproperty list uchar int vertex_indices\n";
  }
  out << "end_header\n";
}

/// One row of values as ASCII PLY: each as `number` writes it (`%.17g`), separated by spaces.
void asciiRow(std::ostream& out, std::span<const double> row) {
  for (std::size_t i = 0; i < row.size(); ++i)
    out << number(row[i]) << (i + 1 < row.size() ? ' ' : '\n');
}

void asciiMeshBody(std::ostream& out, const RunResult& r, VertexRows& rows) {
  for (std::size_t v = 0; v < rows.count(); ++v) asciiRow(out, rows(v));
  const std::size_t simplexCount = r.simplices.size() / (r.k + 1);
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

void binaryMeshBody(std::ostream& out, const RunResult& r, VertexRows& rows) {
  BinaryBlock data(out);
  for (std::size_t v = 0; v < rows.count(); ++v) data.put(rows(v));
  const std::size_t corners = static_cast<std::size_t>(r.k) + 1;
  const std::size_t simplexCount = r.simplices.size() / corners;
  for (std::size_t s = 0; s < simplexCount; ++s) {
    if (r.k != 1) data.put(static_cast<std::uint8_t>(corners));
    for (std::size_t i = 0; i < corners; ++i) data.put(r.simplices[s * corners + i]);
  }
  data.flush();
}

}  // namespace

void writePly(std::ostream& out, const RunResult& r, PlyFormat format) {
  VertexRows rows(r);
  meshHeader(out, r, rows, format);
  if (format == PlyFormat::ascii)
    asciiMeshBody(out, r, rows);
  else
    binaryMeshBody(out, r, rows);
}

namespace {

/// The header names `prefix0 .. prefix{n-1}`.
std::vector<std::string> numbered(const std::string& prefix, int n) {
  std::vector<std::string> names;
  for (int j = 0; j < n; ++j) names.push_back(prefix + std::to_string(j));
  return names;
}

/// Writes `names` as CSV header cells, each after a comma.
void headerCells(std::ostream& out, const std::vector<std::string>& names) {
  for (const std::string& name : names) out << ',' << name;
}

/// Concatenates header name lists.
std::vector<std::string> joined(std::initializer_list<std::vector<std::string>> lists) {
  std::vector<std::string> all;
  for (const auto& list : lists) all.insert(all.end(), list.begin(), list.end());
  return all;
}

}  // namespace

void writeCellsCsv(std::ostream& out, const RunResult& r) {
  // The contract's columns, then the variables' names as aliases of i, c and p (i_x, c_x, p_x).
  const auto i = numbered("i", r.n), c = numbered("c", r.n), p = numbered("p", r.n);
  const auto taken = joined({{"cell", "class"}, i, c, p});
  auto aliases = aliasNames(r, "i_", taken);
  const auto ca = aliasNames(r, "c_", taken), pa = aliasNames(r, "p_", taken);
  if (ca.empty() || pa.empty()) aliases.clear();
  out << "cell";
  headerCells(out, i);
  headerCells(out, c);
  out << ",class";
  headerCells(out, p);
  if (!aliases.empty()) headerCells(out, joined({aliases, ca, pa}));
  out << '\n';
  // Centres and points in the documented coordinates: knot parameters for B-spline variables.
  const auto at = [&](int j, double x) {
    return r.application ? r.application->parameter(j, x) : x;
  };
  for (std::size_t cell = 0; cell < r.cellClass.size(); ++cell) {
    std::ostringstream index, centre, point;
    for (int j = 0; j < r.n; ++j) {
      index << ',' << r.cellIndex[cell * r.n + j];
      centre << ',' << number(at(j, r.cellCentre[cell * r.n + j]));
      point << ',' << number(at(j, r.cellPoint[cell * r.n + j]));
    }
    out << cell << index.str() << centre.str() << ',' << className(r.cellClass[cell])
        << point.str();
    if (!aliases.empty()) out << index.str() << centre.str() << point.str();
    out << '\n';
  }
}

void writeSingularCsv(std::ostream& out, const RunResult& r) {
  // The contract's columns, then the variables' names as aliases of u0 ...
  const auto u = numbered("u", r.n);
  const auto aliases = aliasNames(r, "", joined({{"point", "sigma_min"}, u}));
  out << "point,sigma_min";
  headerCells(out, u);
  headerCells(out, aliases);
  out << '\n';
  for (std::size_t i = 0; i < r.summary.singularPoints.size(); ++i) {
    const SingularPoint& p = r.summary.singularPoints[i];
    std::ostringstream coordinates;
    for (int j = 0; j < r.n; ++j)
      coordinates << ','
                  << (static_cast<std::size_t>(j) < p.point.size() ? number(p.point[j]) : "");
    out << i << ',' << number(p.sigmaMin) << coordinates.str();
    if (!aliases.empty()) out << coordinates.str();
    out << '\n';
  }
}

void writeUncertifiedCsv(std::ostream& out, const RunResult& r) {
  // The contract's columns, then the variables' names as aliases of lo and hi (lo_x, hi_x).
  std::vector<std::string> bounds;
  for (int j = 0; j < r.n; ++j) {
    bounds.push_back("lo" + std::to_string(j));
    bounds.push_back("hi" + std::to_string(j));
  }
  const auto taken = joined({{"kind", "level", "reason"}, bounds});
  const auto lo = aliasNames(r, "lo_", taken), hi = aliasNames(r, "hi_", taken);
  const bool alias = !lo.empty() && !hi.empty();
  out << "kind,level,reason";
  headerCells(out, bounds);
  for (std::size_t j = 0; alias && j < lo.size(); ++j) out << ',' << lo[j] << ',' << hi[j];
  out << '\n';
  const auto row = [&](const std::string& head, const std::vector<std::string>& box) {
    std::string cells;
    for (const std::string& v : box) cells += ',' + v;
    out << head << cells << (alias ? cells : std::string()) << '\n';
  };
  for (const UncertifiedCell& c : r.summary.topology.uncertified) {
    std::vector<std::string> box;
    for (int j = 0; j < r.n; ++j) box.insert(box.end(), {number(c.lo[j]), number(c.hi[j])});
    row("cell," + std::to_string(c.level) + ',' + c.reason, box);
  }
  for (const SingularPoint& p : r.summary.singularPoints) {
    std::vector<std::string> box;
    for (int j = 0; j < r.n; ++j) {
      const std::string v = static_cast<std::size_t>(j) < p.point.size() ? number(p.point[j]) : "";
      box.insert(box.end(), {v, v});
    }
    row("singular_point,,sigma_min=" + number(p.sigmaMin), box);
  }
}

void writeInputPly(std::ostream& out, const TriangleSoup& input, PlyFormat format) {
  out << "ply\n"
      << formatLine(format) << "comment ndcontour input surfaces\nelement vertex "
      << input.vertices.size() << "\nproperty double x\nproperty double y\nproperty double z\n"
      << "element face " << input.triangles.size()
      << "\nproperty list uchar int vertex_indices\nproperty int part\nend_header\n";
  if (format == PlyFormat::ascii) {
    for (const auto& v : input.vertices)
      out << number(v[0]) << ' ' << number(v[1]) << ' ' << number(v[2]) << '\n';
    for (std::size_t t = 0; t < input.triangles.size(); ++t)
      out << "3 " << input.triangles[t][0] << ' ' << input.triangles[t][1] << ' '
          << input.triangles[t][2] << ' ' << input.part[t] << '\n';
    return;
  }
  BinaryBlock vertices(out);
  for (const auto& v : input.vertices) vertices.put(std::span<const double>(v));
  vertices.flush();
  BinaryBlock faces(out);
  for (std::size_t t = 0; t < input.triangles.size(); ++t) {
    faces.put(std::uint8_t{3});
    for (int c : input.triangles[t]) faces.put(static_cast<std::int32_t>(c));
    faces.put(static_cast<std::int32_t>(input.part[t]));
  }
  faces.flush();
}

namespace {

/// The two triangles of ruled.ply for polyline edge (a, b): a a2 b2 and a b2 b, where x2 is
/// vertex x of the second image (numbered after the first).
std::array<std::int64_t, 6> ruledTriangles(const RunResult& r, std::size_t e,
                                           std::size_t vertexCount) {
  const std::int64_t a = r.simplices[2 * e], b = r.simplices[2 * e + 1];
  const std::int64_t a2 = a + static_cast<std::int64_t>(vertexCount),
                     b2 = b + static_cast<std::int64_t>(vertexCount);
  return {a, a2, b2, a, b2, b};
}

}  // namespace

void writeRuledPly(std::ostream& out, const RunResult& r, PlyFormat format) {
  // Each polyline edge (a, b) sweeps the quad S1(a) S2(a) S2(b) S1(b) of bitangent segments.
  const ApplicationData& app = *r.application;
  const std::size_t vertexCount = r.n ? r.vertices.size() / r.n : 0;
  const std::size_t edgeCount = r.simplices.size() / 2;
  out << "ply\n"
      << formatLine(format) << "comment ndcontour ruled surface of bitangent segments\n"
      << "element vertex " << 2 * vertexCount
      << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << 2 * edgeCount
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  const bool ascii = format == PlyFormat::ascii;
  BinaryBlock vertices(out);
  for (int which = 0; which < 2; ++which)
    for (std::size_t v = 0; v < vertexCount; ++v) {
      const std::span<const double> x(r.vertices.data() + v * r.n, static_cast<std::size_t>(r.n));
      const auto y = which == 0 ? app.image(x) : (*app.secondImage)(x);
      if (ascii)
        out << number(y[0]) << ' ' << number(y[1]) << ' ' << number(y[2]) << '\n';
      else
        vertices.put(std::span<const double>(y));
    }
  vertices.flush();
  BinaryBlock faces(out);
  for (std::size_t e = 0; e < edgeCount; ++e) {
    const auto t = ruledTriangles(r, e, vertexCount);
    if (ascii) {
      out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << "\n3 " << t[3] << ' ' << t[4] << ' '
          << t[5] << '\n';
      continue;
    }
    for (int i = 0; i < 6; ++i) {
      if (i % 3 == 0) faces.put(std::uint8_t{3});
      faces.put(static_cast<std::int32_t>(t[i]));
    }
  }
  faces.flush();
}

void installInterruptCleanup() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

void armTimeout(double seconds, const std::string& line, int status) {
  copyPath(cleanup.timeoutLine, line + "\n");
  cleanup.timeoutStatus = status;
  cleanup.published = 0;
  struct sigaction action {};
  action.sa_handler = onTimeout;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGALRM, &action, nullptr);
  itimerval timer{};
  const double whole = std::floor(seconds);
  timer.it_value.tv_sec = static_cast<time_t>(whole);
  timer.it_value.tv_usec = static_cast<suseconds_t>((seconds - whole) * 1e6);
  if (timer.it_value.tv_sec == 0 && timer.it_value.tv_usec == 0) timer.it_value.tv_usec = 1;
  ::setitimer(ITIMER_REAL, &timer, nullptr);
}

void disarmTimeout() {
  cleanup.published = 1;
  itimerval none{};
  ::setitimer(ITIMER_REAL, &none, nullptr);
}

namespace {

/// The files of a run, each name with its whole text, in the order they are published.
using OutputFiles = std::vector<std::pair<std::string, std::string>>;

/// Every file of the run, formatted before the first one is written.
OutputFiles formatOutputs(const RunResult& result, const OutputOptions& options) {
  OutputFiles files;
  const auto add = [&](const char* name, auto write) {
    std::ostringstream text;
    write(text);
    files.emplace_back(name, std::move(text).str());
  };
  const PlyFormat format = options.format;
  add("mesh.ply", [&](std::ostream& o) { writePly(o, result, format); });
  if (options.vtk) add("mesh.vtu", [&](std::ostream& o) { writeVtk(o, result, format); });
  if (options.legacyVtk) add("mesh.vtk", [&](std::ostream& o) { writeLegacyVtk(o, result); });
  if (options.obj) add("mesh.obj", [&](std::ostream& o) { writeObj(o, result); });
  if (options.cells) add("cells.csv", [&](std::ostream& o) { writeCellsCsv(o, result); });
  add("singular.csv", [&](std::ostream& o) { writeSingularCsv(o, result); });
  if (!result.summary.topology.certified)
    add("uncertified.csv", [&](std::ostream& o) { writeUncertifiedCsv(o, result); });
  if (const ApplicationData* app = result.application.get()) {
    add("input.ply", [&](std::ostream& o) { writeInputPly(o, app->input, format); });
    if (app->secondImage && result.k == 1)
      add("ruled.ply", [&](std::ostream& o) { writeRuledPly(o, result, format); });
  }
  add("summary.json", [&](std::ostream& o) { o << toJson(result.summary); });
  return files;
}

/// The hidden staging folder of writeOutputs inside `dir`: removed (and forgotten by the
/// interrupt handlers) when a step fails, with ndc::InputError(message).
class Staging {
 public:
  explicit Staging(const std::filesystem::path& dir)
      : dir_(dir), path_(dir / (".ndcontour-partial-" + std::to_string(::getpid()))) {
    std::error_code error;
    removeAbandoned(dir);
    std::filesystem::remove_all(path_, error);
    std::filesystem::create_directory(path_, error);
    if (error)
      throw InputError(dir.string() +
                       ": cannot create a temporary folder in it: " + error.message());
    copyPath(cleanup.folder, path_);
  }

  /// Removes the staging folders in `dir` of runs that were killed (SIGKILL, a power cut): their
  /// process no longer exists. A live one (a concurrent solve into `dir`) is left alone.
  static void removeAbandoned(const std::filesystem::path& dir) {
    constexpr std::string_view kPrefix = ".ndcontour-partial-";
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(kPrefix, 0) != 0) continue;
      char* end = nullptr;
      const long pid = std::strtol(name.c_str() + kPrefix.size(), &end, 10);
      if (pid <= 0 || *end != '\0') continue;
      const bool gone = ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
      if (gone) std::filesystem::remove_all(entry.path(), error);
    }
  }

  /// Writes every file into the staging folder.
  void write(const OutputFiles& files) const {
    for (const auto& [name, text] : files) {
      if (cleanup.count < static_cast<sig_atomic_t>(InterruptCleanup::kPaths)) {
        copyPath(cleanup.files[cleanup.count], path_ / name);
        cleanup.count = cleanup.count + 1;
      }
      std::ofstream out(path_ / name, std::ios::binary);
      out.write(text.data(), static_cast<std::streamsize>(text.size()));
      out.flush();
      if (!out) abandon((dir_ / name).string() + ": cannot write the file: " + failureReason());
    }
  }

  /// Moves the staged files into `dir` (summary.json last, as it is last in `files`), after
  /// removing the previous summary.json and the previous outputs this run does not write.
  std::vector<std::string> publish(const OutputFiles& files) const;

  /// Removes the staging folder and throws InputError(message).
  [[noreturn]] void abandon(const std::string& message) const {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
    forget();
    throw InputError(message);
  }

 private:
  static void forget() {
    cleanup.count = 0;
    cleanup.folder[0] = '\0';
  }

  std::filesystem::path dir_, path_;
};

std::vector<std::string> Staging::publish(const OutputFiles& files) const {
  // SIGINT, SIGTERM and the timeout are held: the previous summary goes first (the folder reads
  // as unfinished while files are replaced), and so do the previous outputs this run does not
  // write (cells.csv without --cells, input.ply and ruled.ply of an application problem,
  // uncertified.csv of an uncertified run, view.html); summary.json last marks a finished run.
  const BlockInterrupts hold;
  const auto written = [&](const std::string& name) {
    return std::any_of(files.begin(), files.end(), [&](const auto& f) { return f.first == name; });
  };
  std::error_code error;
  // view.html is `ndcontour view`'s page of the previous run: it would show the old mesh.
  for (const char* name : {"summary.json", "cells.csv", "mesh.vtu", "mesh.vtk", "mesh.obj",
                           "input.ply", "ruled.ply", "uncertified.csv", "view.html"})
    if (std::string(name) == "summary.json" || !written(name)) {
      std::filesystem::remove(dir_ / name, error);
      if (error) abandon((dir_ / name).string() + ": cannot remove the previous output");
    }
  std::vector<std::string> names;
  for (const auto& [name, text] : files) {
    std::filesystem::rename(path_ / name, dir_ / name, error);
    if (error) abandon((dir_ / name).string() + ": cannot write the file: " + error.message());
    names.push_back(name);
  }
  std::filesystem::remove(path_, error);
  forget();
  // The run is published: a timeout held back until here has nothing left to stop.
  cleanup.published = 1;
  return names;
}

}  // namespace

std::vector<std::string> writeOutputs(const std::filesystem::path& dir, const RunResult& result,
                                      const OutputOptions& options) {
  createDirectories(dir, "output directory");
  const OutputFiles files = formatOutputs(result, options);
  // Stage: every file into a hidden folder inside `dir` first, so that a full disk or an
  // interrupt while writing leaves the previous run untouched (an interrupt removes the
  // staging folder: see installInterruptCleanup).
  const Staging staging(dir);
  staging.write(files);
  return staging.publish(files);
}

// readPly: framework/io/ply_read.cpp.

}  // namespace ndc
