// readPly (framework/io/io.hpp): PLY files as writePly writes them, ASCII or
// binary_little_endian, read with every count checked against the file before it is used.
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/io/io.hpp"
#include "framework/util/errors.hpp"

namespace ndc {
namespace {

/// Throws ndc::InputError(`FILE: message`).
struct PlyError {
  std::string file;
  [[noreturn]] void operator()(const std::string& message) const {
    throw InputError(file + ": " + message);
  }
};

/// The scalar types of PLY properties.
enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

/// The type of a PLY type name (`char` .. `double`, or `int8` .. `float64`).
std::optional<PlyType> plyType(std::string_view name) {
  static constexpr std::pair<std::string_view, PlyType> kNames[] = {
      {"char", PlyType::int8},      {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},    {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16},  {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},    {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32},  {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  for (const auto& [text, type] : kNames)
    if (text == name) return type;
  return std::nullopt;
}

std::size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::int8:
    case PlyType::uint8:
      return 1;
    case PlyType::int16:
    case PlyType::uint16:
      return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32:
      return 4;
    case PlyType::float64:
      return 8;
  }
  return 8;
}

bool plyInteger(PlyType t) { return t != PlyType::float32 && t != PlyType::float64; }

/// A property of an element: a scalar, or a list (a length of `countType`, then its items).
struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float64;   ///< of the value, or of each item of a list
  std::optional<PlyType> countType;  ///< a list: the type of its length
};

/// An element declared in a PLY header.
struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;

  /// The property `name` (a list or not, as asked).
  std::optional<std::size_t> find(std::string_view name, bool list = false) const {
    for (std::size_t p = 0; p < properties.size(); ++p)
      if (properties[p].name == name && properties[p].countType.has_value() == list) return p;
    return std::nullopt;
  }

  /// The fewest bytes one record can take: in a binary file every list empty, in an ASCII
  /// file one character and one blank or line end per value.
  std::uint64_t minBytes(bool binary) const {
    std::uint64_t bytes = 0;
    for (const PlyProperty& p : properties)
      bytes += binary ? plySize(p.countType.value_or(p.type)) : 2;
    return std::max<std::uint64_t>(bytes, 1);
  }
};

/// A PLY header: the encoding, the elements, and where the body starts.
struct PlyHeader {
  bool binary = false;
  std::vector<PlyElement> elements;
  std::size_t body = 0;   ///< the offset of the first byte after the end_header line
  std::size_t lines = 0;  ///< the lines of the header
};

/// At most 80 characters of `text`, bytes that are not printable ASCII shown as '?': file
/// content quoted in a one-line error.
std::string shown(std::string_view text) {
  constexpr std::size_t kShown = 80;
  std::string out(text.substr(0, kShown));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
  return text.size() > kShown ? out + "..." : out;
}

/// `v` as `%.17g` does: a value of the file quoted in an error.
std::string valueText(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

/// The line of `text` at `at` without its line end ("\n" or "\r\n"); `at` moves past it.
std::optional<std::string_view> nextLine(std::string_view text, std::size_t& at) {
  if (at >= text.size()) return std::nullopt;
  const std::size_t end = std::min(text.find('\n', at), text.size());
  std::string_view line = text.substr(at, end - at);
  at = std::min(end + 1, text.size());
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

/// The words of a line, separated by blanks.
std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  for (std::size_t i = line.find_first_not_of(" \t"); i != std::string_view::npos;
       i = line.find_first_not_of(" \t", i)) {
    const std::size_t end = std::min(line.find_first_of(" \t", i), line.size());
    words.push_back(line.substr(i, end - i));
    i = end;
  }
  return words;
}

/// `format ascii 1.0` or `format binary_little_endian 1.0`: whether the body is binary.
bool readFormatLine(const std::vector<std::string_view>& w, std::string_view line,
                    const PlyError& fail) {
  if (w.size() == 3 && w[2] == "1.0") {
    if (w[1] == "ascii") return false;
    if (w[1] == "binary_little_endian") return true;
    if (w[1] == "binary_big_endian")
      fail("binary_big_endian PLY is not read (only ascii and binary_little_endian)");
  }
  fail("unknown PLY format '" + shown(line) + "' (accepted: ascii 1.0, binary_little_endian 1.0)");
}

/// `element NAME COUNT`.
PlyElement readElementLine(const std::vector<std::string_view>& w, std::string_view line,
                           const PlyError& fail) {
  if (w.size() != 3) fail("bad header line '" + shown(line) + "'");
  PlyElement e;
  e.name = w[1];
  const char* end = w[2].data() + w[2].size();
  const auto [last, ec] = std::from_chars(w[2].data(), end, e.count);
  if (ec != std::errc() || last != end)
    fail("bad element count '" + shown(w[2]) + "' in '" + shown(line) + "'");
  return e;
}

/// `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME`.
PlyProperty readPropertyLine(const std::vector<std::string_view>& w, std::string_view line,
                             const PlyError& fail) {
  const bool list = w.size() == 5 && w[1] == "list";
  if (!list && w.size() != 3) fail("bad header line '" + shown(line) + "'");
  const auto typeOf = [&](std::string_view name) {
    const std::optional<PlyType> t = plyType(name);
    if (!t) fail("unknown property type '" + shown(name) + "' in '" + shown(line) + "'");
    return *t;
  };
  PlyProperty p;
  p.name = w.back();
  p.type = typeOf(w[list ? 3 : 1]);
  if (list) {
    p.countType = typeOf(w[2]);
    if (!plyInteger(*p.countType)) fail("a list length must be an integer: '" + shown(line) + "'");
  }
  return p;
}

/// The header, from `ply` to `end_header`.
PlyHeader readPlyHeader(std::string_view text, const PlyError& fail) {
  PlyHeader h;
  std::size_t at = 0;
  std::optional<std::string_view> line = nextLine(text, at);
  if (!line || *line != "ply") fail("not a PLY file");
  bool format = false;
  for (h.lines = 1;; ++h.lines) {
    line = nextLine(text, at);
    if (!line) fail("the header has no end_header");
    const std::vector<std::string_view> w = splitWords(*line);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") break;
    if (w[0] == "format") {
      h.binary = readFormatLine(w, *line, fail);
      format = true;
    } else if (w[0] == "element") {
      h.elements.push_back(readElementLine(w, *line, fail));
    } else if (w[0] == "property") {
      if (h.elements.empty()) fail("property before element: '" + shown(*line) + "'");
      h.elements.back().properties.push_back(readPropertyLine(w, *line, fail));
    } else {
      fail("bad header line '" + shown(*line) + "'");
    }
  }
  if (!format) fail("the header has no format line");
  h.body = at;
  ++h.lines;
  return h;
}

/// Fails when the records the header declares cannot fit into the `bytes` after it.
void checkCounts(const PlyHeader& h, std::size_t bytes, const PlyError& fail) {
  // An ASCII file's last line may lack its line end.
  std::uint64_t left = bytes + (h.binary ? 0 : 1);
  for (const PlyElement& e : h.elements) {
    const std::uint64_t record = e.minBytes(h.binary);
    if (e.count > left / record)
      fail("element '" + e.name + "' declares " + std::to_string(e.count) +
           " records, more than the " + std::to_string(bytes) + " bytes after the header hold");
    left -= e.count * record;
  }
}

/// The records of an ASCII body: one line each, values separated by blanks.
class AsciiRecords {
 public:
  AsciiRecords(std::string_view body, std::size_t headerLines)
      : text_(body), lineNumber_(headerLines) {}

  /// Starts the next record; false at the end of the file.
  bool next() {
    const std::optional<std::string_view> line = nextLine(text_, at_);
    if (!line) return false;
    record_ = *line;
    pos_ = 0;
    ++lineNumber_;
    return true;
  }

  /// The record's next value; false when it has none or a bad one (not a number, or not an
  /// integer for an integer type). `null` is how writePly spells a value that is not finite;
  /// a leading `+` is accepted.
  bool value(PlyType type, double& v) {
    pos_ = std::min(record_.find_first_not_of(" \t", pos_), record_.size());
    if (pos_ == record_.size()) return false;
    const std::size_t end = std::min(record_.find_first_of(" \t", pos_), record_.size());
    std::string_view token = record_.substr(pos_, end - pos_);
    pos_ = end;
    if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
    if (token == "null") {
      v = std::numeric_limits<double>::quiet_NaN();
      return !plyInteger(type);
    }
    const auto [last, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || last != token.data() + token.size()) return false;
    return !plyInteger(type) || v == std::floor(v);
  }

  std::string where() const { return "line " + std::to_string(lineNumber_); }
  std::string valueError() const { return "a missing or bad value in '" + shown(record_) + "'"; }
  /// Bytes after the last record that are an error (none: trailing lines are ignored).
  std::size_t rest() const { return 0; }

 private:
  std::string_view text_, record_;
  std::size_t at_ = 0, pos_ = 0, lineNumber_;
};

/// A little-endian value of type T at `p`.
template <class T>
double little(const char* p) {
  std::array<char, sizeof(T)> bytes;
  std::memcpy(bytes.data(), p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes.begin(), bytes.end());
  T v;
  std::memcpy(&v, bytes.data(), sizeof(T));
  return static_cast<double>(v);
}

/// The records of a binary_little_endian body: the values one after the other.
class BinaryRecords {
 public:
  BinaryRecords(std::string_view body, std::size_t offset) : data_(body), offset_(offset) {}

  bool next() {
    start_ = at_;
    return true;
  }

  /// The record's next value; false when the file ends first.
  bool value(PlyType type, double& v) {
    const std::size_t size = plySize(type);
    if (data_.size() - at_ < size) return false;
    const char* p = data_.data() + at_;
    at_ += size;
    switch (type) {
      case PlyType::int8:
        v = little<std::int8_t>(p);
        break;
      case PlyType::uint8:
        v = little<std::uint8_t>(p);
        break;
      case PlyType::int16:
        v = little<std::int16_t>(p);
        break;
      case PlyType::uint16:
        v = little<std::uint16_t>(p);
        break;
      case PlyType::int32:
        v = little<std::int32_t>(p);
        break;
      case PlyType::uint32:
        v = little<std::uint32_t>(p);
        break;
      case PlyType::float32:
        v = little<float>(p);
        break;
      case PlyType::float64:
        v = little<double>(p);
        break;
    }
    return true;
  }

  std::string where() const { return "byte " + std::to_string(offset_ + start_); }
  std::string valueError() const { return "the file ends inside it"; }
  /// Bytes after the last record: a count in the header is wrong, or the file is garbled.
  std::size_t rest() const { return data_.size() - at_; }

 private:
  std::string_view data_;
  std::size_t offset_, at_ = 0, start_ = 0;
};

/// One record's values: per scalar property its value (NaN for a list), and the items of one
/// list property.
struct PlyRecord {
  std::vector<double> values;
  std::vector<double> items;
};

/// Fails naming record i of element e: `vertex 4 of 10 (line 17): what`.
template <class Records>
[[noreturn]] void recordFail(const Records& in, const PlyElement& e, std::uint64_t i,
                             const std::string& what, const PlyError& fail) {
  fail(e.name + " " + std::to_string(i + 1) + " of " + std::to_string(e.count) + " (" + in.where() +
       "): " + what);
}

/// Starts record i of e, or fails when the file has ended.
template <class Records>
void nextRecord(Records& in, const PlyElement& e, std::uint64_t i, const PlyError& fail) {
  if (!in.next())
    fail("ends inside element '" + e.name + "' (after " + std::to_string(i) + " of " +
         std::to_string(e.count) + " records)");
}

/// A list length no file can hold.
constexpr std::uint64_t kNoLength = std::numeric_limits<std::uint64_t>::max();

/// Reads record i of e into `r`, keeping the items of list property `keep` (other lists are
/// read and dropped).
template <class Records>
void readRecord(Records& in, const PlyElement& e, std::uint64_t i, std::optional<std::size_t> keep,
                PlyRecord& r, const PlyError& fail) {
  r.values.assign(e.properties.size(), std::numeric_limits<double>::quiet_NaN());
  r.items.clear();
  for (std::size_t p = 0; p < e.properties.size(); ++p) {
    const PlyProperty& q = e.properties[p];
    double v = 0;
    if (!in.value(q.countType.value_or(q.type), v)) recordFail(in, e, i, in.valueError(), fail);
    if (!q.countType) {
      r.values[p] = v;
      continue;
    }
    if (v < 0) recordFail(in, e, i, "list length " + valueText(v), fail);
    // Each item is read from the file before it is stored: a length beyond the file fails.
    const std::uint64_t length = v < 1e18 ? static_cast<std::uint64_t>(v) : kNoLength;
    for (std::uint64_t j = 0; j < length; ++j) {
      double item = 0;
      if (!in.value(q.type, item)) recordFail(in, e, i, in.valueError(), fail);
      if (keep == p) r.items.push_back(item);
    }
  }
}

/// The `vertex` element: x y z and u0, u1, .. of each vertex.
template <class Records>
void readVertices(Records& in, const PlyElement& e, PlyMesh& mesh, const PlyError& fail) {
  if (e.count == 0) return;
  const auto x = e.find("x"), y = e.find("y"), z = e.find("z");
  if (!x || !y || !z) fail("vertex lacks x, y or z");
  std::vector<std::size_t> u;
  for (int j = 0;; ++j) {
    std::string name = "u";
    name += std::to_string(j);
    const auto p = e.find(name);
    if (!p) break;
    u.push_back(*p);
  }
  // checkCounts has bounded the count by the file's size.
  mesh.xyz.reserve(mesh.xyz.size() + e.count);
  mesh.u.reserve(mesh.u.size() + e.count);
  PlyRecord r;
  for (std::uint64_t i = 0; i < e.count; ++i) {
    nextRecord(in, e, i, fail);
    readRecord(in, e, i, std::nullopt, r, fail);
    mesh.xyz.push_back({r.values[*x], r.values[*y], r.values[*z]});
    std::vector<double> point(u.size());
    for (std::size_t j = 0; j < u.size(); ++j) point[j] = r.values[u[j]];
    mesh.u.push_back(std::move(point));
  }
}

/// An `edge` (`vertex1 vertex2`) or `face` (the `vertex_indices` list) element.
template <class Records>
void readSimplices(Records& in, const PlyElement& e, PlyMesh& mesh, const PlyError& fail) {
  if (e.count == 0) return;
  const bool face = e.name == "face";
  std::optional<std::size_t> list, a, b;
  if (face) {
    list = e.find("vertex_indices", true);
    if (!list) list = e.find("vertex_index", true);
    if (!list) fail("face lacks the list vertex_indices");
  } else {
    a = e.find("vertex1");
    b = e.find("vertex2");
    if (!a || !b) fail("edge lacks vertex1 or vertex2");
  }
  mesh.simplices.reserve(mesh.simplices.size() + e.count);
  PlyRecord r;
  const double vertices = static_cast<double>(mesh.xyz.size());
  for (std::uint64_t i = 0; i < e.count; ++i) {
    nextRecord(in, e, i, fail);
    readRecord(in, e, i, list, r, fail);
    if (!face) r.items.assign({r.values[*a], r.values[*b]});
    std::vector<int> s;
    s.reserve(r.items.size());
    for (double v : r.items) {
      if (!(v >= 0 && v < vertices && v == std::floor(v)))
        recordFail(in, e, i,
                   "vertex index " + valueText(v) + " is out of range (" +
                       std::to_string(mesh.xyz.size()) + " vertices)",
                   fail);
      s.push_back(static_cast<int>(v));
    }
    mesh.simplices.push_back(std::move(s));
  }
}

/// Every element of the body in order; elements other than vertex, edge and face are skipped.
template <class Records>
void readBody(Records& in, const PlyHeader& h, PlyMesh& mesh, const PlyError& fail) {
  for (const PlyElement& e : h.elements) {
    if (e.name == "vertex") {
      readVertices(in, e, mesh, fail);
    } else if (e.name == "edge" || e.name == "face") {
      readSimplices(in, e, mesh, fail);
    } else {
      PlyRecord r;
      for (std::uint64_t i = 0; i < e.count; ++i) {
        nextRecord(in, e, i, fail);
        readRecord(in, e, i, std::nullopt, r, fail);
      }
    }
  }
  if (in.rest() > 0)
    fail(std::to_string(in.rest()) +
         " bytes after the last element (a count in the header is wrong, or the file is "
         "garbled)");
}

}  // namespace

PlyMesh readPly(const std::filesystem::path& file) {
  const PlyError fail{file.string()};
  std::ifstream stream(file, std::ios::binary);
  if (!stream) fail("cannot read the file: " + failureReason());
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  const std::string text = std::move(buffer).str();
  const PlyHeader h = readPlyHeader(text, fail);
  const std::string_view body = std::string_view(text).substr(h.body);
  checkCounts(h, body.size(), fail);
  PlyMesh mesh;
  if (h.binary) {
    BinaryRecords in(body, h.body);
    readBody(in, h, mesh, fail);
  } else {
    AsciiRecords in(body, h.lines);
    readBody(in, h, mesh, fail);
  }
  return mesh;
}

}  // namespace ndc
