// Tables and figures from experiment results (issue 6): see report.hpp.
#include "experiments/report/report.hpp"

#include "framework/core/io.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <system_error>

#include "framework/core/problem.hpp"

namespace ndc::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// What a missing number prints as (an en dash; `--` in LaTeX).
constexpr std::string_view kDash = "\u2013";

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot read the file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string shellQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

// --- CSV ---------------------------------------------------------------------------------------

bool CsvTable::hasColumn(std::string_view name) const {
  return std::find(header.begin(), header.end(), name) != header.end();
}

std::size_t CsvTable::column(std::string_view name) const {
  const auto it = std::find(header.begin(), header.end(), name);
  if (it == header.end()) throw InputError(source + ": missing column '" + std::string(name) + "'");
  return static_cast<std::size_t>(it - header.begin());
}

const std::string& CsvTable::cell(std::size_t row, std::string_view name) const {
  return rows.at(row)[column(name)];
}

double CsvTable::number(std::size_t row, std::string_view name) const {
  const std::string& text = cell(row, name);
  if (text.empty() || text == "nan" || text == "NaN" || text == "null") return kNaN;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size())
    throw InputError(source + ": row " + std::to_string(row + 2) + ", column '" +
                     std::string(name) + "': '" + text + "' is not a number");
  return value;
}

void CsvTable::require(std::span<const std::string_view> names) const {
  for (std::string_view name : names) column(name);
}

CsvTable parseCsv(std::string_view text, const std::string& source) {
  CsvTable table;
  table.source = source;
  const auto fail = [&](std::size_t line, const std::string& message) {
    throw InputError(source + ":" + std::to_string(line) + ": " + message);
  };
  const std::size_t n = text.size();
  std::size_t i = 0, line = 1;
  bool haveHeader = false;
  while (i < n) {
    // One record: fields separated by commas up to an unquoted line end.
    const std::size_t recordLine = line;
    std::vector<std::string> record;
    bool quoted = false;
    while (true) {
      std::string field;
      if (i < n && text[i] == '"') {
        quoted = true;
        const std::size_t openLine = line;
        ++i;
        while (true) {
          if (i >= n) fail(openLine, "unterminated quoted field");
          const char c = text[i++];
          if (c == '"') {
            if (i < n && text[i] == '"') {
              field += '"';
              ++i;
            } else {
              break;
            }
          } else {
            if (c == '\n') ++line;
            field += c;
          }
        }
        if (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r')
          fail(line, "text after a closing quote");
      } else {
        while (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
          if (text[i] == '"') fail(line, "quote inside an unquoted field");
          field += text[i++];
        }
      }
      record.push_back(std::move(field));
      if (i < n && text[i] == ',') {
        ++i;
        continue;
      }
      if (i < n && text[i] == '\r') ++i;
      if (i < n && text[i] == '\n') ++i;
      ++line;
      break;
    }
    if (record.size() == 1 && record[0].empty() && !quoted) continue;  // a blank line
    if (!haveHeader) {
      std::set<std::string> seen;
      for (std::size_t c = 0; c < record.size(); ++c) {
        if (record[c].empty())
          fail(recordLine, "empty column name (column " + std::to_string(c + 1) + ")");
        if (!seen.insert(record[c]).second)
          fail(recordLine, "duplicate column '" + record[c] + "'");
      }
      table.header = std::move(record);
      haveHeader = true;
    } else {
      if (record.size() != table.header.size())
        fail(recordLine, "row has " + std::to_string(record.size()) + " fields, the header " +
                             std::to_string(table.header.size()));
      table.rows.push_back(std::move(record));
    }
  }
  if (!haveHeader) fail(1, "no header line");
  return table;
}

CsvTable readCsv(const std::filesystem::path& file) {
  return parseCsv(readText(file), file.string());
}

// --- Aggregation -------------------------------------------------------------------------------

Stats summarize(std::span<const double> values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  Stats s;
  s.count = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  const std::size_t m = v.size() / 2;
  s.median = v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  double sum = 0;
  for (double x : v) sum += (x - s.mean) * (x - s.mean);
  s.stddev = v.size() > 1 ? std::sqrt(sum / static_cast<double>(v.size() - 1)) : 0.0;
  return s;
}

std::vector<Group> groupBy(const CsvTable& table, std::span<const std::string> columns,
                           std::span<const std::size_t> rows) {
  std::vector<std::size_t> index;
  for (const std::string& c : columns) index.push_back(table.column(c));
  std::vector<std::size_t> all;
  if (rows.empty()) {
    all.resize(table.size());
    std::iota(all.begin(), all.end(), std::size_t{0});
    rows = all;
  }
  std::vector<Group> groups;
  std::map<std::vector<std::string>, std::size_t> position;
  for (std::size_t r : rows) {
    std::vector<std::string> key;
    for (std::size_t c : index) key.push_back(table.rows.at(r)[c]);
    const auto [it, inserted] = position.emplace(key, groups.size());
    if (inserted) groups.push_back({std::move(key), {}});
    groups[it->second].rows.push_back(r);
  }
  return groups;
}

std::vector<double> values(const CsvTable& table, std::span<const std::size_t> rows,
                           std::string_view column) {
  std::vector<double> out;
  for (std::size_t r : rows) out.push_back(table.number(r, column));
  return out;
}

std::vector<std::string> varyingColumns(const CsvTable& table,
                                        std::span<const std::string> candidates) {
  std::vector<std::string> out;
  for (const std::string& c : candidates) {
    if (!table.hasColumn(c)) continue;
    std::set<std::string> seen;
    for (std::size_t r = 0; r < table.size(); ++r) seen.insert(table.cell(r, c));
    if (seen.size() > 1) out.push_back(c);
  }
  return out;
}

double logLogSlope(std::span<const double> x, std::span<const double> y) {
  std::vector<std::pair<double, double>> p;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i)
    if (x[i] > 0 && y[i] > 0 && std::isfinite(x[i]) && std::isfinite(y[i]))
      p.emplace_back(std::log(x[i]), std::log(y[i]));
  if (p.size() < 2) return kNaN;
  double mx = 0, my = 0;
  for (auto [a, b] : p) mx += a, my += b;
  mx /= static_cast<double>(p.size());
  my /= static_cast<double>(p.size());
  double sxy = 0, sxx = 0;
  for (auto [a, b] : p) sxy += (a - mx) * (b - my), sxx += (a - mx) * (a - mx);
  return sxx > 0 ? sxy / sxx : kNaN;
}

// --- Formatting --------------------------------------------------------------------------------

std::string formatNumber(double value, int significant) {
  if (!std::isfinite(value)) return std::string(kDash);
  char buffer[64];
  const double a = std::fabs(value);
  if (value == std::round(value) && a < 1e15) {
    std::snprintf(buffer, sizeof buffer, "%.0f", value);
    return buffer;
  }
  if (a >= 1e-3 && a < 1e6) {
    const int decimals = std::max(0, significant - 1 - static_cast<int>(std::floor(std::log10(a))));
    std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
    return buffer;
  }
  std::snprintf(buffer, sizeof buffer, "%.*e", std::max(0, significant - 1), value);
  // 1.23e-05 -> 1.23e-5, 1.2e+06 -> 1.2e6
  std::string text = buffer;
  const std::size_t e = text.find('e');
  std::string mantissa = text.substr(0, e), exponent = text.substr(e + 1);
  std::string sign;
  if (exponent[0] == '-' || exponent[0] == '+') {
    if (exponent[0] == '-') sign = "-";
    exponent.erase(0, 1);
  }
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return mantissa + "e" + sign + exponent;
}

std::string formatFixed(double value, int decimals) {
  if (!std::isfinite(value)) return std::string(kDash);
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

// --- Tables ------------------------------------------------------------------------------------

std::string toMarkdown(const Table& table) {
  const auto escape = [](const std::string& text) {
    std::string out;
    for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
  };
  std::string out = "|";
  const auto add = [&](const std::string& cell) {
    out += ' ';
    out += escape(cell);
    out += " |";
  };
  for (const std::string& c : table.columns) add(c);
  out += "\n|";
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    const char a = c < table.align.size() ? table.align[c] : 'l';
    out += a == 'r' ? "--:|" : a == 'c' ? ":-:|" : "---|";
  }
  out += "\n";
  for (const auto& row : table.rows) {
    out += "|";
    for (const std::string& cell : row) add(cell);
    out += "\n";
  }
  return out;
}

std::string latexEscape(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text.substr(i).starts_with(kDash)) {
      out += "--";
      i += kDash.size() - 1;
      continue;
    }
    const char c = text[i];
    switch (c) {
      case '\\':
        out += "\\textbackslash{}";
        break;
      case '~':
        out += "\\textasciitilde{}";
        break;
      case '^':
        out += "\\textasciicircum{}";
        break;
      case '&':
      case '%':
      case '$':
      case '#':
      case '_':
      case '{':
      case '}':
        out += '\\';
        out += c;
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string toLatex(const Table& table) {
  std::string align;
  for (std::size_t c = 0; c < table.columns.size(); ++c)
    align += c < table.align.size() ? table.align[c] : 'l';
  std::string out = "% Generated by `ndcontour report` from results/" + table.id + "/" + table.id +
                    ".csv: do not edit.\n";
  out += "\\begin{table}[htbp]\n  \\centering\n  \\caption{" + latexEscape(table.caption) +
         "}\n  \\label{" + table.id + "}\n";
  // Shrink a table wider than the text to the text width, never enlarge it (graphicx).
  out += "  \\resizebox{\\ifdim\\width>\\linewidth\\linewidth\\else\\width\\fi}{!}{%\n";
  out += "  \\begin{tabular}{" + align + "}\n    \\toprule\n    ";
  for (std::size_t c = 0; c < table.columns.size(); ++c)
    out += (c ? " & " : "") + latexEscape(table.columns[c]);
  out += " \\\\\n    \\midrule\n";
  for (const auto& row : table.rows) {
    out += "    ";
    for (std::size_t c = 0; c < row.size(); ++c) out += (c ? " & " : "") + latexEscape(row[c]);
    out += " \\\\\n";
  }
  out += "    \\bottomrule\n  \\end{tabular}}\n\\end{table}\n";
  return out;
}

// --- Figures -----------------------------------------------------------------------------------

GnuplotScript::GnuplotScript(std::string id, int width, int height)
    : id_(std::move(id)), width_(width), height_(height) {}

void GnuplotScript::data(const std::string& name, const std::vector<std::vector<double>>& rows) {
  data_ += "$" + name + " << EOD\n";
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (c) data_ += ' ';
      if (std::isfinite(row[c])) {
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.9g", row[c]);
        data_ += buffer;
      } else {
        data_ += "NaN";
      }
    }
    data_ += '\n';
  }
  data_ += "EOD\n";
}

void GnuplotScript::command(const std::string& line) { commands_ += "  " + line + "\n"; }

std::string GnuplotScript::text() const {
  std::string out = "# Generated by `ndcontour report` for " + id_ +
                    ": do not edit (re-run `ndcontour report`).\n"
                    "# Renders OUT.png and OUT.pdf; `gnuplot -e \"out='NAME'\" " +
                    id_ + ".gp` sets OUT.\n";
  out += "if (!exists(\"out\")) out = \"" + id_ + "\"\n";
  out += data_;
  out += "do for [format in \"png pdf\"] {\n";
  out += "  if (format eq \"png\") {\n    set terminal pngcairo size " + std::to_string(width_) +
         "," + std::to_string(height_) + " enhanced font \"Sans,11\"\n  } else {\n";
  char size[64];
  std::snprintf(size, sizeof size, "%.2fin,%.2fin", width_ / 150.0, height_ / 150.0);
  out += "    set terminal pdfcairo size " + std::string(size) + " enhanced font \"Sans,8\"\n  }\n";
  out += "  set output out.\".\".format\n";
  out += commands_;
  out += "  set output\n}\n";
  return out;
}

bool gnuplotAvailable() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

std::string renderGnuplot(const std::filesystem::path& dir, const std::string& id) {
  const std::string tmp = id + ".tmp";
  const std::string command = "cd " + shellQuote(dir.string()) + " && gnuplot -e \"out='" + tmp +
                              "'\" " + shellQuote(id + ".gp") + " > " +
                              shellQuote(id + ".gnuplot.log") + " 2>&1";
  const int status = std::system(command.c_str());
  std::error_code ignored;
  const bool produced = std::filesystem::exists(dir / (tmp + ".png")) &&
                        std::filesystem::exists(dir / (tmp + ".pdf"));
  if (status != 0 || !produced) {
    std::filesystem::remove(dir / (tmp + ".png"), ignored);
    std::filesystem::remove(dir / (tmp + ".pdf"), ignored);
    std::string last;
    std::ifstream log(dir / (id + ".gnuplot.log"));
    for (std::string line; std::getline(log, line);)
      if (!line.empty()) last = line;
    return "gnuplot failed (" + (dir / (id + ".gnuplot.log")).string() + ")" +
           (last.empty() ? "" : ": " + last);
  }
  for (const char* ext : {".png", ".pdf"}) {
    std::error_code error;
    std::filesystem::rename(dir / (tmp + ext), dir / (id + ext), error);
    if (error) return "cannot rename " + tmp + ext + ": " + error.message();
  }
  return "";
}

// --- Reading run outputs -----------------------------------------------------------------------

PlyMesh readPly(const std::filesystem::path& file) {
  std::istringstream in(readText(file));
  const auto fail = [&](const std::string& message) {
    throw InputError(file.string() + ": " + message);
  };
  std::string line;
  if (!std::getline(in, line) || line != "ply") fail("not a PLY file");
  struct Element {
    std::string name;
    std::size_t count = 0;
    std::vector<std::string> properties;
    bool list = false;
  };
  std::vector<Element> elements;
  bool ascii = false;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "end_header") break;
    if (word == "format") {
      std::string format;
      words >> format;
      ascii = format == "ascii";
    } else if (word == "element") {
      Element e;
      words >> e.name >> e.count;
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) fail("property before element");
      std::string type, name;
      words >> type;
      if (type == "list") {
        std::string countType, itemType;
        words >> countType >> itemType;
        elements.back().list = true;
      }
      words >> name;
      elements.back().properties.push_back(name);
    }
  }
  if (!ascii) fail("only ASCII PLY is read");
  PlyMesh mesh;
  for (const Element& e : elements) {
    for (std::size_t i = 0; i < e.count; ++i) {
      if (!std::getline(in, line)) fail("ends inside element '" + e.name + "'");
      std::istringstream words(line);
      if (e.name == "vertex") {
        std::map<std::string, double> value;
        for (const std::string& p : e.properties) {
          double v = 0;
          if (!(words >> v)) fail("bad vertex line: " + line);
          value[p] = v;
        }
        if (!value.count("x") || !value.count("y") || !value.count("z"))
          fail("vertex lacks x, y or z");
        mesh.xyz.push_back({value["x"], value["y"], value["z"]});
        std::vector<double> u;
        for (int j = 0; value.count("u" + std::to_string(j)); ++j)
          u.push_back(value["u" + std::to_string(j)]);
        mesh.u.push_back(std::move(u));
      } else if (e.name == "edge" || e.name == "face") {
        std::vector<int> s;
        int count = 2;
        if (e.list && !(words >> count)) fail("bad " + e.name + " line: " + line);
        for (int j = 0; j < count; ++j) {
          int v = 0;
          if (!(words >> v) || v < 0 || static_cast<std::size_t>(v) >= mesh.xyz.size())
            fail("bad " + e.name + " line: " + line);
          s.push_back(v);
        }
        mesh.simplices.push_back(std::move(s));
      }
    }
  }
  return mesh;
}

// --- Artefacts ---------------------------------------------------------------------------------

namespace {

/// Run settings that may vary within an experiment (jitter seeds are averaged over instead).
const std::vector<std::string> kSettingColumns = {"depth",      "bounding",       "subdivision",
                                                  "projection", "classification", "connection",
                                                  "scalar",     "precision_bits"};

constexpr std::array<std::string_view, 8> kKnownArtefacts = {
    "tab1-degeneracy",       "fig-degeneracy-vs-n",
    "tab-ablation-bounding", "tab-ablation-subdivision",
    "tab-ablation-scalar",   "tab-connection",
    "fig-convergence",       "fig-cells"};
const std::array<std::string_view, 8>& knownList() { return kKnownArtefacts; }

std::string join(const std::vector<std::string>& parts, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i)
    out += (i ? std::string(separator) : "") + parts[i];
  return out;
}

std::string percent(double value) { return formatFixed(value, 1) + "%"; }

bool isOk(const CsvTable& t, std::size_t r) { return t.cell(r, "status") == "ok"; }

std::vector<std::size_t> okRows(const CsvTable& t) {
  std::vector<std::size_t> rows;
  for (std::size_t r = 0; r < t.size(); ++r)
    if (isOk(t, r)) rows.push_back(r);
  return rows;
}

/// One line per failed run: which run, which problem, the status, exit code and error.
std::vector<std::string> failedRuns(const CsvTable& t) {
  std::vector<std::string> out;
  for (std::size_t r = 0; r < t.size(); ++r) {
    if (isOk(t, r)) continue;
    std::string line = "run `" + t.cell(r, "run") + "` (problem " + t.cell(r, "problem");
    if (t.hasColumn("depth") && !t.cell(r, "depth").empty())
      line += ", depth " + t.cell(r, "depth");
    line += "): " + t.cell(r, "status");
    if (t.hasColumn("exit_code") && !t.cell(r, "exit_code").empty())
      line += ", exit " + t.cell(r, "exit_code");
    if (t.hasColumn("error") && !t.cell(r, "error").empty()) line += ": " + t.cell(r, "error");
    out.push_back(line);
  }
  return out;
}

double meanOf(const CsvTable& t, std::span<const std::size_t> rows, std::string_view column) {
  return summarize(values(t, rows, column)).mean;
}

double maxOf(const CsvTable& t, std::span<const std::size_t> rows, std::string_view column) {
  return summarize(values(t, rows, column)).max;
}

/// `column=value` for each of `columns`, e.g. "bounding=interval, depth=6".
std::string settingsLabel(const CsvTable& t, std::size_t row,
                          const std::vector<std::string>& columns) {
  std::vector<std::string> parts;
  for (const std::string& c : columns) parts.push_back(c + "=" + t.cell(row, c));
  return join(parts, ", ");
}

/// Abnormal share in percent of the classified cells, as in the paper's Table 1.
double abnormalShare(double normal, double abnormal) {
  return normal + abnormal > 0 ? 100.0 * abnormal / (normal + abnormal) : kNaN;
}

/// Geometric mean of the ratios a/b over the pairs where both are positive; NaN if none.
double geometricMeanRatio(const std::vector<std::pair<double, double>>& pairs) {
  double sum = 0;
  int count = 0;
  for (auto [a, b] : pairs)
    if (a > 0 && b > 0 && std::isfinite(a) && std::isfinite(b)) sum += std::log(a / b), ++count;
  return count ? std::exp(sum / count) : kNaN;
}

std::vector<std::string> without(std::vector<std::string> columns,
                                 std::initializer_list<std::string_view> drop) {
  std::erase_if(columns, [&](const std::string& c) {
    return std::find(drop.begin(), drop.end(), c) != drop.end();
  });
  return columns;
}

void requireColumns(const CsvTable& t, std::initializer_list<std::string_view> names) {
  const std::vector<std::string_view> list(names);
  t.require(list);
}

// The run-identifying columns every artefact needs.
void requireRunColumns(const CsvTable& t) {
  requireColumns(t, {"experiment", "run", "problem", "status", "error"});
}

// --- tab1-degeneracy: the paper's Table 1 ------------------------------------------------------

struct PaperRow {
  std::string_view key;    ///< matched against the normalised problem name and file stem
  std::string_view label;  ///< the paper's example
  std::string_view family;
  int n;
  double normal, abnormal, share;
};

// Seong, Elber and Kim (2005), Table 1: solution points of Figures 8-10.
constexpr std::array<PaperRow, 6> kPaperTable1 = {{
    {"fig8a", "Bisector, Fig. 8(a)", "bisector", 4, 444, 306, 40.8},
    {"fig8b", "Bisector, Fig. 8(b)", "bisector", 4, 484, 1088, 69.2},
    {"fig8c", "Bisector, Fig. 8(c)", "bisector", 4, 735, 281, 27.6},
    {"fig9", "Sweep, Fig. 9(b)", "sweep", 3, 570, 182, 24.2},
    {"fig10a", "Blending, Fig. 10(a)", "blending", 6, 1054, 1530, 59.2},
    {"fig10b", "Blending, Fig. 10(b)", "blending", 6, 918, 1465, 61.4},
}};

std::string normalised(std::string_view text) {
  std::string out;
  for (char c : text)
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

int paperRowOf(const CsvTable& t, std::size_t r) {
  const std::string name =
      normalised(t.cell(r, "problem")) + " " +
      normalised(std::filesystem::path(t.cell(r, "problem_file")).stem().string());
  // Longest key first so that "fig10a" is not taken for a shorter key.
  int best = -1;
  for (std::size_t i = 0; i < kPaperTable1.size(); ++i) {
    const std::string key(kPaperTable1[i].key);
    std::size_t at = name.find(key);
    while (at != std::string::npos) {
      const std::size_t end = at + key.size();
      // "fig9" must not match "fig9x..." where a letter continues the figure label.
      const bool whole = end >= name.size() ||
                         !std::isalpha(static_cast<unsigned char>(name[end])) || key.back() >= 'a';
      if (whole && (best < 0 || key.size() > kPaperTable1[best].key.size()))
        best = static_cast<int>(i);
      at = name.find(key, at + 1);
    }
  }
  return best;
}

Artefact tab1Degeneracy(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t,
                 {"problem_file", "n", "depth", "cells.normal", "cells.abnormal", "cells.failed"});
  Artefact a;
  a.id = id;
  a.title = "Table 1 reproduced: normal and abnormal solution cells";
  const std::vector<std::string> vary = without(varyingColumns(t, kSettingColumns), {"depth"});
  std::vector<std::string> keys = {"problem", "depth"};
  keys.insert(keys.end(), vary.begin(), vary.end());
  const std::vector<std::size_t> ok = okRows(t);
  const std::vector<Group> groups = groupBy(t, keys, ok);

  Table table;
  table.id = id;
  table.caption =
      "Normal and abnormal solution cells (paper's Table 1), ours beside the paper's; "
      "abnormal % = abnormal / (normal + abnormal).";
  table.columns = {"example", "problem", "n", "depth"};
  if (!vary.empty()) table.columns.push_back("settings");
  for (std::string c :
       {"normal", "abnormal", "abnormal %", "paper normal", "paper abnormal", "paper abnormal %"})
    table.columns.push_back(c);
  table.align = std::string(vary.empty() ? "llrr" : "llrrl") + "rrrrrr";

  struct Ours {
    std::string problem;
    int paper;
    double normal, abnormal, share, failed;
  };
  std::vector<Ours> ours;
  const auto addRow = [&](const Group* g, int paper) {
    std::vector<std::string> row;
    row.push_back(paper >= 0 ? std::string(kPaperTable1[paper].label) : "(not in the paper)");
    if (g) {
      const std::size_t r0 = g->rows.front();
      const double normal = meanOf(t, g->rows, "cells.normal");
      const double abnormal = meanOf(t, g->rows, "cells.abnormal");
      ours.push_back({t.cell(r0, "problem"), paper, normal, abnormal,
                      abnormalShare(normal, abnormal), meanOf(t, g->rows, "cells.failed")});
      row.push_back(t.cell(r0, "problem"));
      row.push_back(t.cell(r0, "n"));
      row.push_back(t.cell(r0, "depth"));
      if (!vary.empty()) row.push_back(settingsLabel(t, r0, vary));
      row.push_back(formatNumber(std::round(normal)));
      row.push_back(formatNumber(std::round(abnormal)));
      row.push_back(formatFixed(abnormalShare(normal, abnormal), 1));
    } else {
      row.push_back("(no result)");
      row.push_back(paper >= 0 ? std::to_string(kPaperTable1[paper].n) : "");
      for (std::size_t c = 0; c < (vary.empty() ? 4u : 5u); ++c) row.push_back(std::string(kDash));
    }
    if (paper >= 0) {
      row.push_back(formatNumber(kPaperTable1[paper].normal));
      row.push_back(formatNumber(kPaperTable1[paper].abnormal));
      row.push_back(formatFixed(kPaperTable1[paper].share, 1));
    } else {
      for (int c = 0; c < 3; ++c) row.push_back(std::string(kDash));
    }
    table.rows.push_back(std::move(row));
  };
  // The paper's order, then our problems that are not in the paper.
  std::vector<bool> used(groups.size(), false);
  for (std::size_t p = 0; p < kPaperTable1.size(); ++p) {
    bool any = false;
    for (std::size_t g = 0; g < groups.size(); ++g)
      if (paperRowOf(t, groups[g].rows.front()) == static_cast<int>(p)) {
        addRow(&groups[g], static_cast<int>(p));
        used[g] = any = true;
      }
    if (!any) addRow(nullptr, static_cast<int>(p));
  }
  for (std::size_t g = 0; g < groups.size(); ++g)
    if (!used[g]) addRow(&groups[g], -1);
  a.tables.push_back(std::move(table));

  // What it shows.
  if (ours.empty()) {
    a.sentences.push_back(
        "No run succeeded, so there is nothing to set beside the paper's "
        "figures (24.2% to 69.2% abnormal).");
    return a;
  }
  const auto lo = std::min_element(ours.begin(), ours.end(),
                                   [](auto& x, auto& y) { return x.share < y.share; });
  const auto hi = std::max_element(ours.begin(), ours.end(),
                                   [](auto& x, auto& y) { return x.share < y.share; });
  a.sentences.push_back("Our abnormal share ranges from " + percent(lo->share) + " (" +
                        lo->problem + ") to " + percent(hi->share) + " (" + hi->problem +
                        "); the paper's from 24.2% (sweep, Fig. 9(b)) to 69.2% (bisector, "
                        "Fig. 8(b)).");
  std::vector<std::string> families;
  std::vector<std::string> paperFamilies;
  for (std::string_view family : {"sweep", "bisector", "blending"}) {
    std::vector<double> mine, theirs;
    int n = 0;
    for (const Ours& o : ours)
      if (o.paper >= 0 && kPaperTable1[o.paper].family == family) mine.push_back(o.share);
    for (const PaperRow& p : kPaperTable1)
      if (p.family == family) theirs.push_back(p.share), n = p.n;
    if (mine.empty()) continue;
    families.push_back(std::string(family) + " (n = " + std::to_string(n) + ") " +
                       percent(summarize(mine).mean));
    paperFamilies.push_back(percent(summarize(theirs).mean));
  }
  if (!families.empty())
    a.sentences.push_back("Mean abnormal share by application: " + join(families, ", ") +
                          "; the paper: " + join(paperFamilies, ", ") + ".");
  // The paper's ordering claims: blending (n = 6) above bisectors (n = 4), Fig. 8(b) highest
  // of the bisectors.
  const auto shareOf = [&](int paper) {
    for (const Ours& o : ours)
      if (o.paper == paper) return o.share;
    return kNaN;
  };
  const double b = shareOf(1);
  if (std::isfinite(b)) {
    const bool highest = std::isfinite(b) && b >= shareOf(0) - 1e-9 && b >= shareOf(2) - 1e-9 &&
                         !(b < shareOf(0)) && !(b < shareOf(2));
    a.sentences.push_back(std::string("The self-intersecting bisector of Fig. 8(b) has ") +
                          percent(b) +
                          (highest ? ", the highest bisector share, as in the paper."
                                   : ", not the highest bisector share, unlike "
                                     "the paper (69.2%)."));
  }
  std::vector<std::pair<double, double>> totals;
  for (const Ours& o : ours)
    if (o.paper >= 0)
      totals.emplace_back(o.normal + o.abnormal,
                          kPaperTable1[o.paper].normal + kPaperTable1[o.paper].abnormal);
  const double ratio = geometricMeanRatio(totals);
  if (std::isfinite(ratio))
    a.sentences.push_back(
        "Our problems are our own stand-ins for the paper's freeform surfaces "
        "and the paper gives no depth, so the cell counts differ: ours are " +
        formatFixed(ratio, 2) + " times the paper's (geometric mean).");
  double failedCells = 0;
  for (const Ours& o : ours) failedCells += o.failed;
  if (failedCells > 0)
    a.sentences.push_back("Cells whose Newton projection failed (" + formatNumber(failedCells) +
                          " in all; the paper has no such class) are left out of the shares.");
  return a;
}

// --- fig-degeneracy-vs-n -----------------------------------------------------------------------

Artefact figDegeneracyVsN(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "cells.normal", "cells.abnormal"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Abnormal share against the ambient dimension n";
  const std::vector<std::string> vary = without(varyingColumns(t, kSettingColumns), {"depth"});
  std::vector<std::string> seriesKeys = {"k"};
  seriesKeys.insert(seriesKeys.end(), vary.begin(), vary.end());
  const std::vector<std::size_t> ok = okRows(t);

  Table data;
  data.id = id;
  data.caption =
      "Abnormal share (% of classified cells) per n: mean, standard deviation, "
      "minimum and maximum over the seeds.";
  data.columns = {"k", "n", "depth", "runs", "mean %", "sd", "min %", "max %"};
  data.align = "rrrrrrrr";
  if (!vary.empty()) {
    data.columns.insert(data.columns.begin() + 1, "settings");
    data.align.insert(1, "l");
  }

  GnuplotScript gp(id);
  gp.command("set xlabel \"ambient dimension n\"");
  gp.command("set ylabel \"abnormal cells (% of classified)\"");
  gp.command("set key top left");
  gp.command("set grid");
  gp.command("set xtics 1");
  gp.command("set yrange [0:*]");
  std::vector<std::string> plots;
  int nMin = 100, nMax = 0;
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};
  const std::vector<Group> series = groupBy(t, seriesKeys, ok);
  std::map<int, double> sphereMean;  // mean share per n of the first k = 2 series
  for (std::size_t s = 0; s < series.size(); ++s) {
    const Group& g = series[s];
    const std::string k = g.key[0];
    const std::string label =
        "k = " + k + (vary.empty() ? "" : ", " + settingsLabel(t, g.rows[0], vary));
    std::vector<std::vector<double>> means, points;
    std::vector<std::pair<int, double>> trend;
    std::vector<std::string> nKey = {"n"};
    std::vector<Group> byN = groupBy(t, nKey, g.rows);
    std::sort(byN.begin(), byN.end(), [](const Group& x, const Group& y) {
      return std::stoi(x.key[0]) < std::stoi(y.key[0]);
    });
    double widest = 0;
    for (const Group& cell : byN) {
      std::vector<double> share;
      std::set<std::string> depths;
      const int n = std::stoi(cell.key[0]);
      for (std::size_t r : cell.rows) {
        share.push_back(abnormalShare(t.number(r, "cells.normal"), t.number(r, "cells.abnormal")));
        points.push_back({n + 0.0, share.back()});
        depths.insert(t.cell(r, "depth"));
      }
      const Stats st = summarize(share);
      means.push_back({n + 0.0, st.mean, st.min, st.max, st.stddev});
      trend.emplace_back(n, st.mean);
      widest = std::max(widest, st.max - st.min);
      nMin = std::min(nMin, n);
      nMax = std::max(nMax, n);
      std::vector<std::string> row = {k,
                                      cell.key[0],
                                      join({depths.begin(), depths.end()}, "/"),
                                      std::to_string(st.count),
                                      formatFixed(st.mean, 1),
                                      formatFixed(st.stddev, 1),
                                      formatFixed(st.min, 1),
                                      formatFixed(st.max, 1)};
      if (!vary.empty()) row.insert(row.begin() + 1, settingsLabel(t, g.rows[0], vary));
      data.rows.push_back(std::move(row));
    }
    if (k == "2" && sphereMean.empty())
      for (const auto& [n, mean] : trend) sphereMean[n] = mean;
    const std::string name = "s" + std::to_string(s);
    gp.data(name + "mean", means);
    gp.data(name + "runs", points);
    const std::string colour = colours[s % 6];
    plots.push_back("$" + name + "mean using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb \"" +
                    colour + "\" title \"" + label + ": mean, min-max\"");
    plots.push_back("$" + name + "runs using ($1+0.08):2 with points pt 6 ps 0.6 lc rgb \"" +
                    colour + "\" title \"" + label + ": runs\"");
    if (trend.empty()) continue;
    // What it shows: first to last n, and whether every step goes up.
    std::string sentence =
        "For " + label + " the abnormal share " +
        (trend.back().second >= trend.front().second ? "rises" : "falls") + " from " +
        percent(trend.front().second) + " at n = " + std::to_string(trend.front().first) + " to " +
        percent(trend.back().second) + " at n = " + std::to_string(trend.back().first);
    std::vector<std::string> drops;
    for (std::size_t i = 1; i < trend.size(); ++i)
      if (trend[i].second < trend[i - 1].second)
        drops.push_back(std::to_string(trend[i - 1].first) + " to " +
                        std::to_string(trend[i].first));
    if (trend.size() > 2)
      sentence += drops.empty()
                      ? ", increasing at every step"
                      : ", not monotonically (it drops from n = " + join(drops, ", ") + ")";
    sentence += "; the seeds spread it by up to " + formatFixed(widest, 1) + " points.";
    a.sentences.push_back(sentence);
    if (trend.size() > 1)
      a.sentences.push_back(
          trend.back().second > trend.front().second
              ? "This agrees with the paper's observation (Sec. 5, Table 1) that degeneracies "
                "become more likely in higher dimensions (k = " +
                    k + ")."
              : "This differs from the paper's observation (Sec. 5) that degeneracies become "
                "more likely in higher dimensions (k = " +
                    k + ").");
  }
  if (!plots.empty()) {
    // The paper's Table 1 (surfaces, k = 2, freeform inputs) at its dimensions, for reference.
    std::vector<std::vector<double>> paper;
    std::map<int, std::vector<double>> paperByN;
    for (const PaperRow& p : kPaperTable1) {
      paper.push_back({p.n + 0.0, p.share});
      paperByN[p.n].push_back(p.share);
    }
    gp.data("paper", paper);
    plots.push_back(
        "$paper with points pt 2 ps 1.5 lw 2 lc rgb \"black\" title \"paper, Table 1 "
        "(k = 2, freeform inputs)\"");
    if (!sphereMean.empty()) {
      std::vector<std::string> ours, theirs;
      for (const auto& [n, shares] : paperByN) {
        const Stats p = summarize(shares);
        theirs.push_back(p.count > 1 ? formatFixed(p.min, 1) + "-" + formatFixed(p.max, 1) +
                                           "% at n = " + std::to_string(n)
                                     : percent(p.mean) + " at n = " + std::to_string(n));
        const auto it = sphereMean.find(n);
        ours.push_back(it != sphereMean.end() ? percent(it->second) : std::string("not run"));
      }
      a.sentences.push_back("The paper's Table 1 (surfaces from freeform inputs) has " +
                            join(theirs, ", ") + "; our rotated spheres give " + join(ours, ", ") +
                            " there.");
    }
    gp.command("set xrange [" + formatFixed(nMin - 0.5, 1) + ":" + formatFixed(nMax + 0.5, 1) +
               "]");
    gp.command("plot " + join(plots, ", \\\n       "));
    a.gnuplot = gp.text();
  } else {
    a.sentences.push_back("No run succeeded, so there is no curve.");
  }
  a.tables.push_back(std::move(data));
  return a;
}

// --- tab-ablation-*: one strategy family compared ----------------------------------------------

Artefact tabAblation(const std::string& id, const CsvTable& t, const std::string& family) {
  requireRunColumns(t);
  requireColumns(
      t, {"n", "k", "depth", "cells.visited", "cells.solution", "accuracy.max_residual",
          "timing_s.subdivision", "timing_s.projection", "timing_s.connection", "timing_s.total"});
  const bool scalar = family == "scalar";
  if (scalar)
    requireColumns(t, {"scalar", "precision_bits"});
  else
    t.column(family);
  Artefact a;
  a.id = id;
  a.title = "Ablation: " + family;
  const auto variant = [&](std::size_t r) {
    if (!scalar) return t.cell(r, family);
    return t.cell(r, "scalar") == "double"
               ? std::string("double")
               : t.cell(r, "scalar") + " " + t.cell(r, "precision_bits");
  };
  std::vector<std::string> other =
      without(varyingColumns(t, kSettingColumns), {"scalar", "precision_bits"});
  std::erase(other, family);
  std::vector<std::string> keys = {"problem"};
  keys.insert(keys.end(), other.begin(), other.end());
  const std::vector<std::size_t> ok = okRows(t);

  Table table;
  table.id = id;
  table.caption = "Ablation of the " + family + (scalar ? " type" : " strategy") +
                  ": cells visited and kept, largest residual, seconds per stage (mean over "
                  "seeds).";
  table.columns = {"problem", "n", "k"};
  for (const std::string& c : other) table.columns.push_back(c);
  for (std::string c :
       {family, std::string("visited"), std::string("solution"), std::string("max residual"),
        std::string("subdivision s"), std::string("projection s"), std::string("connection s"),
        std::string("total s")})
    table.columns.push_back(c);
  table.align = "lrr" + std::string(other.size(), 'r') + "lrrrrrrr";

  // Per variant: for each problem (and other setting), mean visited, time, residual.
  std::vector<std::string> variants;
  std::map<std::string, std::map<std::vector<std::string>, std::array<double, 4>>> measured;
  for (const Group& g : groupBy(t, keys, ok)) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<std::size_t>> byVariant;
    for (std::size_t r : g.rows) {
      if (!byVariant.count(variant(r))) order.push_back(variant(r));
      byVariant[variant(r)].push_back(r);
    }
    for (const std::string& v : order) {
      if (std::find(variants.begin(), variants.end(), v) == variants.end()) variants.push_back(v);
      const auto& rows = byVariant[v];
      const std::size_t r0 = rows.front();
      std::vector<std::string> row = {t.cell(r0, "problem"), t.cell(r0, "n"), t.cell(r0, "k")};
      for (const std::string& c : other) row.push_back(t.cell(r0, c));
      const double visited = meanOf(t, rows, "cells.visited");
      const double residual = maxOf(t, rows, "accuracy.max_residual");
      const double total = meanOf(t, rows, "timing_s.total");
      const double solution = meanOf(t, rows, "cells.solution");
      measured[v][g.key] = {visited, total, residual, solution};
      row.push_back(v);
      row.push_back(formatNumber(std::round(visited)));
      row.push_back(formatNumber(std::round(solution)));
      row.push_back(formatNumber(residual, 2));
      for (std::string_view stage :
           {"timing_s.subdivision", "timing_s.projection", "timing_s.connection"})
        row.push_back(formatNumber(meanOf(t, rows, stage), 2));
      row.push_back(formatNumber(total, 2));
      table.rows.push_back(std::move(row));
    }
  }
  a.tables.push_back(std::move(table));
  if (variants.empty()) {
    a.sentences.push_back("No run succeeded, so there is nothing to compare.");
    return a;
  }
  const std::string& base = variants.front();
  for (std::size_t v = 1; v < variants.size(); ++v) {
    std::vector<std::pair<double, double>> cells, time;
    int sameSolution = 0, common = 0;
    for (const auto& [key, m] : measured[variants[v]]) {
      const auto it = measured[base].find(key);
      if (it == measured[base].end()) continue;
      ++common;
      cells.emplace_back(m[0], it->second[0]);
      time.emplace_back(m[1], it->second[1]);
      if (m[3] == it->second[3]) ++sameSolution;
    }
    if (!common) continue;
    a.sentences.push_back("`" + variants[v] + "` visits " +
                          formatFixed(geometricMeanRatio(cells), 2) + " times the cells of `" +
                          base + "` and takes " + formatFixed(geometricMeanRatio(time), 2) +
                          " times its total time (geometric means over " + std::to_string(common) +
                          " problem settings); it keeps the same number of solution cells in " +
                          std::to_string(sameSolution) + " of them.");
  }
  std::vector<std::string> residuals;
  for (const std::string& v : variants) {
    double worst = kNaN;
    for (const auto& [key, m] : measured[v])
      if (std::isfinite(m[2])) worst = std::isfinite(worst) ? std::max(worst, m[2]) : m[2];
    residuals.push_back("`" + v + "` " + formatNumber(worst, 2));
  }
  a.sentences.push_back("Largest residual over all problems: " + join(residuals, ", ") + ".");
  return a;
}

// --- tab-connection ----------------------------------------------------------------------------

Artefact tabConnection(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "connection", "expect_components", "expect_euler_characteristic",
                     "mesh.components", "mesh.euler_characteristic", "mesh.open_ends",
                     "mesh.boundary_edges", "mesh.nonmanifold_edges", "accuracy.max_chord_error"});
  Artefact a;
  a.id = id;
  a.title = "Connection strategies over the problem corpus";
  const std::vector<std::string> other =
      without(varyingColumns(t, kSettingColumns), {"connection"});
  std::vector<std::string> keys = {"connection"};
  keys.insert(keys.end(), other.begin(), other.end());

  Table table;
  table.id = id;
  table.caption =
      "Connections over the corpus: runs (failed), share of runs with an expected "
      "topology that get the components, the Euler characteristic and both right "
      "(a failed run counts as wrong), total open ends, boundary and non-manifold "
      "edges, median and largest chord error.";
  table.columns = keys;
  for (std::string c :
       {"runs", "failed", "components right", "Euler right", "both right", "open ends",
        "boundary edges", "non-manifold edges", "median chord error", "max chord error"})
    table.columns.push_back(c);
  table.align = std::string(keys.size(), 'l') + "rrrrrrrrrr";

  const auto expected = [&](std::size_t r, const char* what) {
    return t.number(r, std::string("expect_") + what);
  };
  const auto right = [&](std::size_t r, const char* what) {
    const double e = expected(r, what);
    return isOk(t, r) && std::isfinite(e) && t.number(r, std::string("mesh.") + what) == e;
  };
  struct Score {
    std::string label;
    int runs = 0, withExpect = 0, components = 0, euler = 0, both = 0;
    double boundary = 0, nonmanifold = 0, openEnds = 0;
  };
  std::vector<Score> scores;
  for (const Group& g : groupBy(t, keys)) {
    Score s;
    s.label = join(g.key, ", ");
    int failed = 0;
    std::vector<std::size_t> ok;
    for (std::size_t r : g.rows) {
      ++s.runs;
      if (!isOk(t, r)) {
        ++failed;
      } else {
        ok.push_back(r);
        s.openEnds += t.number(r, "mesh.open_ends");
        s.boundary += t.number(r, "mesh.boundary_edges");
        s.nonmanifold += t.number(r, "mesh.nonmanifold_edges");
      }
      if (!std::isfinite(expected(r, "components")) &&
          !std::isfinite(expected(r, "euler_characteristic")))
        continue;
      ++s.withExpect;
      const bool c = right(r, "components"), e = right(r, "euler_characteristic");
      s.components += c;
      s.euler += e;
      s.both += c && e;
    }
    const Stats chord = summarize(values(t, ok, "accuracy.max_chord_error"));
    const auto share = [&](int count) {
      return s.withExpect ? std::to_string(count) + "/" + std::to_string(s.withExpect) + " (" +
                                formatFixed(100.0 * count / s.withExpect, 0) + "%)"
                          : std::string(kDash);
    };
    std::vector<std::string> row = g.key;
    row.push_back(std::to_string(s.runs));
    row.push_back(std::to_string(failed));
    row.push_back(share(s.components));
    row.push_back(share(s.euler));
    row.push_back(share(s.both));
    row.push_back(formatNumber(s.openEnds));
    row.push_back(formatNumber(s.boundary));
    row.push_back(formatNumber(s.nonmanifold));
    row.push_back(formatNumber(chord.median, 2));
    row.push_back(formatNumber(chord.max, 2));
    table.rows.push_back(std::move(row));
    scores.push_back(s);
  }
  a.tables.push_back(std::move(table));

  // Per problem: components / Euler characteristic of each connection beside the expectation.
  std::vector<std::string> connections;
  for (std::size_t r = 0; r < t.size(); ++r)
    if (std::find(connections.begin(), connections.end(), t.cell(r, "connection")) ==
        connections.end())
      connections.push_back(t.cell(r, "connection"));
  std::vector<std::string> rowKeys = {"problem"};
  const std::vector<std::string> detailOther = without(other, {});
  rowKeys.insert(rowKeys.end(), detailOther.begin(), detailOther.end());
  Table detail;
  detail.id = id;
  detail.caption =
      "Per problem: components / Euler characteristic of each connection (b: "
      "boundary edges, nm: non-manifold edges when not 0; * marks a wrong "
      "topology; runs over several seeds show how many were right).";
  detail.columns = rowKeys;
  detail.columns.insert(detail.columns.begin() + 1, {"n", "k", "expected"});
  for (const std::string& c : connections) detail.columns.push_back(c);
  detail.align = "l" + std::string("rrl") + std::string(rowKeys.size() - 1, 'l') +
                 std::string(connections.size(), 'l');
  for (const Group& g : groupBy(t, rowKeys)) {
    const std::size_t r0 = g.rows.front();
    const auto show = [](double v) {
      return std::isfinite(v) ? formatNumber(v) : std::string("?");
    };
    std::vector<std::string> row = {
        g.key[0], t.cell(r0, "n"), t.cell(r0, "k"),
        show(expected(r0, "components")) + " / " + show(expected(r0, "euler_characteristic"))};
    for (std::size_t i = 1; i < g.key.size(); ++i) row.push_back(g.key[i]);
    for (const std::string& c : connections) {
      std::vector<std::size_t> runs;
      for (std::size_t r : g.rows)
        if (t.cell(r, "connection") == c) runs.push_back(r);
      if (runs.empty()) {
        row.push_back(std::string(kDash));
        continue;
      }
      const std::size_t r = runs.front();
      std::string text;
      if (!isOk(t, r)) {
        text = t.cell(r, "status");
      } else {
        text = formatNumber(t.number(r, "mesh.components")) + " / " +
               formatNumber(t.number(r, "mesh.euler_characteristic"));
        const double b = t.number(r, "mesh.boundary_edges"),
                     nm = t.number(r, "mesh.nonmanifold_edges");
        if (b > 0) text += " b" + formatNumber(b);
        if (nm > 0) text += " nm" + formatNumber(nm);
        const bool hasExpect = std::isfinite(expected(r, "components")) ||
                               std::isfinite(expected(r, "euler_characteristic"));
        const bool wrong = (std::isfinite(expected(r, "components")) && !right(r, "components")) ||
                           (std::isfinite(expected(r, "euler_characteristic")) &&
                            !right(r, "euler_characteristic"));
        if (hasExpect && wrong) text += " *";
      }
      if (runs.size() > 1) {
        int good = 0;
        for (std::size_t x : runs)
          good += right(x, "components") && right(x, "euler_characteristic");
        text += " (" + std::to_string(good) + "/" + std::to_string(runs.size()) + " right)";
      }
      row.push_back(text);
    }
    detail.rows.push_back(std::move(row));
  }
  a.tables.push_back(std::move(detail));

  std::vector<std::string> parts;
  for (const Score& s : scores)
    if (s.withExpect)
      parts.push_back("`" + s.label + "` " + std::to_string(s.both) + " of " +
                      std::to_string(s.withExpect));
  if (!parts.empty())
    a.sentences.push_back("Runs with both the components and the Euler characteristic right: " +
                          join(parts, ", ") + ".");
  parts.clear();
  for (const Score& s : scores)
    parts.push_back("`" + s.label + "` " + formatNumber(s.boundary) + " boundary and " +
                    formatNumber(s.nonmanifold) + " non-manifold edges, " +
                    formatNumber(s.openEnds) + " open ends");
  if (!parts.empty())
    a.sentences.push_back("In total " + join(parts, "; ") +
                          ". The paper's connection (Sec. 4) keeps holes in surfaces, which "
                          "shows as boundary edges where the expected surface is closed.");
  return a;
}

// --- fig-convergence ---------------------------------------------------------------------------

Artefact figConvergence(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "accuracy.max_chord_error", "accuracy.max_residual",
                     "cells.solution", "timing_s.total"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Convergence with the depth";
  const std::vector<std::string> vary = without(varyingColumns(t, kSettingColumns), {"depth"});
  std::vector<std::string> keys = {"problem"};
  keys.insert(keys.end(), vary.begin(), vary.end());
  const std::vector<std::size_t> ok = okRows(t);

  Table data;
  data.id = id;
  data.caption =
      "Chord error, residual, solution cells and total seconds per depth (h = "
      "2^-depth of the domain; mean over seeds).";
  data.columns = {"problem", "k", "depth", "chord error", "residual", "solution cells", "total s"};
  data.align = "lrrrrrr";
  if (!vary.empty()) {
    data.columns.insert(data.columns.begin() + 1, "settings");
    data.align.insert(1, "l");
  }
  GnuplotScript gp(id, 1100, 850);
  gp.command("set multiplot layout 2,2 title \"" + id +
             ": convergence with the cell size h = 2^{-depth}\"");
  gp.command("set logscale xy");
  gp.command("set format y \"10^{%L}\"");
  gp.command("set xlabel \"h (relative cell size)\"");
  gp.command("set grid");
  gp.command("set key bottom right font \",8\"");
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                           "#ff7f0e", "#8c564b", "#e377c2", "#7f7f7f"};
  std::array<std::vector<std::string>, 4> panels;
  std::vector<std::vector<double>> chordRef, cellsRef1, cellsRef2;
  const std::vector<Group> series = groupBy(t, keys, ok);
  for (std::size_t s = 0; s < series.size(); ++s) {
    const Group& g = series[s];
    const std::size_t r0 = g.rows.front();
    const std::string label =
        t.cell(r0, "problem") + (vary.empty() ? "" : " " + settingsLabel(t, r0, vary));
    const int k = static_cast<int>(t.number(r0, "k"));
    std::vector<Group> byDepth = groupBy(t, std::vector<std::string>{"depth"}, g.rows);
    std::sort(byDepth.begin(), byDepth.end(), [](const Group& x, const Group& y) {
      return std::stoi(x.key[0]) < std::stoi(y.key[0]);
    });
    std::vector<std::vector<double>> rows;
    std::vector<double> h, chord, residual, cells, time;
    for (const Group& d : byDepth) {
      const double hh = std::ldexp(1.0, -std::stoi(d.key[0]));
      h.push_back(hh);
      chord.push_back(meanOf(t, d.rows, "accuracy.max_chord_error"));
      residual.push_back(meanOf(t, d.rows, "accuracy.max_residual"));
      cells.push_back(meanOf(t, d.rows, "cells.solution"));
      time.push_back(meanOf(t, d.rows, "timing_s.total"));
      rows.push_back({hh, chord.back(), residual.back(), cells.back(), time.back()});
      std::vector<std::string> row = {t.cell(r0, "problem"),
                                      t.cell(r0, "k"),
                                      d.key[0],
                                      formatNumber(chord.back(), 2),
                                      formatNumber(residual.back(), 2),
                                      formatNumber(std::round(cells.back())),
                                      formatNumber(time.back(), 2)};
      if (!vary.empty()) row.insert(row.begin() + 1, settingsLabel(t, r0, vary));
      data.rows.push_back(std::move(row));
    }
    const std::string name = "s" + std::to_string(s);
    gp.data(name, rows);
    const std::string style = " with linespoints pt 7 ps 0.7 lc rgb \"" +
                              std::string(colours[s % 8]) + "\" title \"" + label + "\"";
    for (int p = 0; p < 4; ++p)
      panels[p].push_back("$" + name + " using 1:($" + std::to_string(p + 2) + ">0?$" +
                          std::to_string(p + 2) + ":NaN)" + style);
    // Reference slopes through the finest point of the first series of their kind.
    const auto reference = [&](std::vector<std::vector<double>>& ref, const std::vector<double>& y,
                               double slope) {
      if (!ref.empty() || h.size() < 2 || !(y.back() > 0)) return;
      const double h1 = h.back(), h0 = h.front();
      // Half a decade below the data, so that the guide does not hide the curve.
      const double y1 = 0.3 * y.back();
      ref = {{h0, y1 * std::pow(h0 / h1, slope)}, {h1, y1}};
    };
    reference(chordRef, chord, 2.0);
    reference(k == 1 ? cellsRef1 : cellsRef2, cells, -static_cast<double>(k));
    if (h.size() < 2) continue;
    const double chordSlope = logLogSlope(h, chord), cellSlope = logLogSlope(h, cells),
                 timeSlope = logLogSlope(h, time);
    const Stats res = summarize(residual);
    a.sentences.push_back(
        label + " (k = " + std::to_string(k) + ", depths " + byDepth.front().key[0] + " to " +
        byDepth.back().key[0] + "): the chord error falls as h^" + formatFixed(chordSlope, 2) +
        " (expected h^2), the solution cells grow as h^" + formatFixed(cellSlope, 2) +
        " (expected h^-" + std::to_string(k) + "), the time as h^" + formatFixed(timeSlope, 2) +
        "; the residual stays between " + formatNumber(res.min, 2) + " and " +
        formatNumber(res.max, 2) + ".");
  }
  if (series.empty()) {
    a.sentences.push_back("No run succeeded, so there is no curve.");
    a.tables.push_back(std::move(data));
    return a;
  }
  const std::string refStyle = " with lines dt 2 lw 2 lc rgb \"black\"";
  if (!chordRef.empty()) {
    gp.data("refchord", chordRef);
    panels[0].push_back("$refchord" + refStyle + " title \"O(h^2)\"");
  }
  if (!cellsRef1.empty()) {
    gp.data("refcells1", cellsRef1);
    panels[2].push_back("$refcells1" + refStyle + " title \"O(h^{-1})\"");
  }
  if (!cellsRef2.empty()) {
    gp.data("refcells2", cellsRef2);
    panels[2].push_back("$refcells2 with lines dt 3 lw 2 lc rgb \"black\" title \"O(h^{-2})\"");
  }
  const char* titles[] = {"max chord error", "max residual |F_i|", "solution cells",
                          "total time (s)"};
  for (int p = 0; p < 4; ++p) {
    gp.command(std::string("set title \"") + titles[p] + "\"");
    gp.command(std::string("set ylabel \"") + titles[p] + "\"");
    gp.command("plot " + join(panels[p], ", \\\n       "));
  }
  gp.command("unset multiplot");
  a.gnuplot = gp.text();
  a.tables.push_back(std::move(data));
  return a;
}

// --- fig-cells: a Figure-2-style picture of the solution cells ---------------------------------

Artefact figCells(const std::string& id, const CsvTable& t, const std::filesystem::path& dir) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "cells.normal", "cells.abnormal", "mesh.components"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Solution cells of a 2-D problem (cf. the paper's Figures 2 and 3)";
  // The first 2-D problem with a successful run, at its largest depth.
  std::optional<std::size_t> pick;
  for (std::size_t r : okRows(t))
    if (t.cell(r, "n") == "2" &&
        std::filesystem::exists(dir / "runs" / t.cell(r, "run") / "cells.csv") &&
        (!pick || (t.cell(r, "problem") == t.cell(*pick, "problem") &&
                   t.number(r, "depth") > t.number(*pick, "depth"))))
      pick = r;
  if (!pick) {
    a.sentences.push_back("No successful 2-D run with a cells.csv, so there is no picture.");
    return a;
  }
  const std::size_t r = *pick;
  const std::filesystem::path run = dir / "runs" / t.cell(r, "run");
  const CsvTable cells = readCsv(run / "cells.csv");
  requireColumns(cells, {"i0", "i1", "c0", "c1", "class", "p0", "p1"});
  // Cell size per axis from two cells with different indices on that axis.
  std::array<double, 2> half = {kNaN, kNaN};
  for (int j = 0; j < 2; ++j) {
    const std::string i = "i" + std::to_string(j), c = "c" + std::to_string(j);
    for (std::size_t x = 1; x < cells.size() && !std::isfinite(half[j]); ++x) {
      const double di = cells.number(x, i) - cells.number(0, i);
      if (di != 0) half[j] = 0.5 * std::fabs((cells.number(x, c) - cells.number(0, c)) / di);
    }
  }
  if (!std::isfinite(half[0])) half[0] = std::isfinite(half[1]) ? half[1] : 0.01;
  if (!std::isfinite(half[1])) half[1] = half[0];
  std::map<std::string, std::vector<std::vector<double>>> byClass;
  std::vector<std::vector<double>> points;
  for (std::size_t x = 0; x < cells.size(); ++x) {
    byClass[cells.cell(x, "class")].push_back(
        {cells.number(x, "c0"), cells.number(x, "c1"), half[0], half[1]});
    points.push_back({cells.number(x, "p0"), cells.number(x, "p1")});
  }
  // A canvas of the cells' aspect ratio (the plot keeps x and y to scale).
  double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
  for (std::size_t x = 0; x < cells.size(); ++x)
    for (int j = 0; j < 2; ++j) {
      const double c = cells.number(x, j ? "c1" : "c0");
      lo[j] = std::min(lo[j], c - half[j]);
      hi[j] = std::max(hi[j], c + half[j]);
    }
  const double aspect =
      cells.size() ? std::clamp((hi[1] - lo[1]) / (hi[0] - lo[0]), 0.3, 1.5) : 1.0;
  GnuplotScript gp(id, 1000, static_cast<int>(150 + 850 * aspect));
  gp.command("set size ratio -1");
  gp.command("set title \"" + t.cell(r, "problem") + ", depth " + t.cell(r, "depth") +
             ": solution cells and the polyline\"");
  gp.command("set xlabel \"x_0\"");
  gp.command("set ylabel \"x_1\"");
  gp.command("set key outside bottom center horizontal");
  std::vector<std::string> plots;
  const std::map<std::string, std::string> colour = {
      {"normal", "#6baed6"}, {"abnormal", "#fb6a4a"}, {"failed", "#969696"}};
  for (const auto& [cls, rows] : byClass) {
    const std::string name = "cells_" + cls;
    gp.data(name, rows);
    const auto it = colour.find(cls);
    plots.push_back("$" + name +
                    " using 1:2:($1-$3):($1+$3):($2-$4):($2+$4) with boxxyerror fs "
                    "solid 0.6 border lc rgb \"#555555\" fc rgb \"" +
                    (it != colour.end() ? it->second : std::string("#fdd0a2")) + "\" title \"" +
                    cls + " (" + std::to_string(rows.size()) + ")\"");
  }
  std::string meshNote;
  const std::filesystem::path ply = run / "mesh.ply";
  if (std::filesystem::exists(ply)) {
    const PlyMesh mesh = readPly(ply);
    std::vector<std::vector<double>> segments;
    for (const auto& s : mesh.simplices) {
      for (std::size_t v = 0; v <= s.size(); ++v) {
        const int i = s[v % s.size()];
        if (v == s.size() && s.size() == 2) break;
        const auto& u = mesh.u[i];
        segments.push_back(u.size() >= 2 ? std::vector<double>{u[0], u[1]}
                                         : std::vector<double>{mesh.xyz[i][0], mesh.xyz[i][1]});
      }
      segments.push_back({});
    }
    gp.data("curve", segments);
    plots.push_back("$curve with lines lw 2 lc rgb \"black\" title \"polyline\"");
    meshNote = " The polyline has " + std::to_string(mesh.xyz.size()) + " vertices and " +
               t.cell(r, "mesh.components") + " component(s)" +
               (t.hasColumn("expect_components") && !t.cell(r, "expect_components").empty()
                    ? " (expected " + t.cell(r, "expect_components") + ")."
                    : ".");
  }
  gp.data("points", points);
  plots.push_back("$points with points pt 7 ps 0.5 lc rgb \"#08306b\" title \"solution points\"");
  gp.command("plot " + join(plots, ", \\\n       "));
  a.gnuplot = gp.text();
  const double normal = t.number(r, "cells.normal"), abnormal = t.number(r, "cells.abnormal");
  a.sentences.push_back("At depth " + t.cell(r, "depth") + " the subdivision keeps " +
                        std::to_string(cells.size()) + " cells of `" + t.cell(r, "problem") +
                        "` (run `" + t.cell(r, "run") + "`): " + formatNumber(normal) +
                        " normal and " + formatNumber(abnormal) + " abnormal (" +
                        percent(abnormalShare(normal, abnormal)) +
                        "); abnormal cells are those whose projected point lies outside the "
                        "cell, as in the paper's Figure 3(b)." +
                        meshNote);
  return a;
}

// --- fig-app-*: the mesh of each application problem -------------------------------------------

Artefact figApplication(const std::string& id, const CsvTable& t,
                        const std::filesystem::path& dir) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "mesh.vertices", "mesh.components",
                     "mesh.euler_characteristic", "mesh.boundary_edges", "mesh.nonmanifold_edges",
                     "accuracy.max_residual", "timing_s.total"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Application: " + id.substr(std::string("fig-app-").size());
  // Per problem the successful run at the largest depth.
  std::vector<std::size_t> picks;
  for (const Group& g : groupBy(t, std::vector<std::string>{"problem"}, okRows(t))) {
    std::size_t best = g.rows.front();
    for (std::size_t r : g.rows)
      if (t.number(r, "depth") > t.number(best, "depth")) best = r;
    if (std::filesystem::exists(dir / "runs" / t.cell(best, "run") / "mesh.ply"))
      picks.push_back(best);
  }
  if (picks.empty()) {
    a.sentences.push_back("No successful run with a mesh.ply, so there is no picture.");
    return a;
  }
  const int columns = static_cast<int>(std::min<std::size_t>(picks.size(), 3));
  const int rowsCount = static_cast<int>((picks.size() + columns - 1) / columns);
  GnuplotScript gp(id, 500 * columns, 480 * rowsCount);
  if (picks.size() > 1)
    gp.command("set multiplot layout " + std::to_string(rowsCount) + "," + std::to_string(columns) +
               " title \"" + id + "\"");
  gp.command("set view equal xyz");
  gp.command("set xyplane relative 0");
  gp.command("set xlabel \"x\"");
  gp.command("set ylabel \"y\"");
  gp.command("set zlabel \"z\"");
  gp.command("set palette defined (0 \"#08519c\", 1 \"#6baed6\", 2 \"#c6dbef\")");
  gp.command("unset colorbox");
  gp.command("unset key");
  for (std::size_t p = 0; p < picks.size(); ++p) {
    const std::size_t r = picks[p];
    const std::filesystem::path run = dir / "runs" / t.cell(r, "run");
    a.shownRuns.push_back(t.cell(r, "run"));
    const PlyMesh mesh = readPly(run / "mesh.ply");
    const auto polygons = [](const PlyMesh& m) {
      std::vector<std::vector<double>> rows;
      for (const auto& s : m.simplices) {
        for (int v : s) rows.push_back({m.xyz[v][0], m.xyz[v][1], m.xyz[v][2]});
        rows.push_back({});
      }
      return rows;
    };
    const std::string name = "mesh" + std::to_string(p);
    gp.data(name, polygons(mesh));
    // An application's input surfaces (input.ply) and ruled surface (ruled.ply, e.g. the
    // convex hull's bitangent segments) are drawn behind the result, as in Figures 6-10.
    std::string context;
    for (const auto& [file, style] :
         {std::pair<std::string, std::string>{"input",
                                              "fs transparent solid 0.3 fc rgb "
                                              "\"#969696\""},
          std::pair<std::string, std::string>{"ruled",
                                              "fs transparent solid 0.5 fc rgb "
                                              "\"#fdae6b\""}}) {
      if (!std::filesystem::exists(run / (file + ".ply"))) continue;
      const std::string block = file + std::to_string(p);
      gp.data(block, polygons(readPly(run / (file + ".ply"))));
      context += "$" + block + " with polygons " + style + ", ";
    }
    const bool curve = t.cell(r, "k") == "1";
    gp.command("set title \"" + t.cell(r, "problem") + " (n = " + t.cell(r, "n") + ", depth " +
               t.cell(r, "depth") + ")\"");
    // Small meshes alone show their triangles; others are shaded by z only.
    gp.command(mesh.simplices.size() < 4000 && context.empty()
                   ? "set pm3d depthorder border lc rgb \"#3a6ea5\" lw 0.3"
                   : "set pm3d depthorder noborder");
    gp.command("splot " + context +
               (curve ? "$" + name + " with lines lw 2 lc rgb \"#08519c\""
                      : "$" + name + " with polygons fc palette z"));
    const bool surface = !curve;
    a.sentences.push_back(
        "`" + t.cell(r, "problem") + "` (n = " + t.cell(r, "n") + ", depth " + t.cell(r, "depth") +
        "): " + std::to_string(mesh.xyz.size()) + " vertices, " +
        std::to_string(mesh.simplices.size()) + (surface ? " triangles" : " segments") + ", " +
        t.cell(r, "mesh.components") + " component(s), Euler characteristic " +
        t.cell(r, "mesh.euler_characteristic") +
        (t.hasColumn("expect_euler_characteristic") &&
                 !t.cell(r, "expect_euler_characteristic").empty()
             ? " (expected " + t.cell(r, "expect_euler_characteristic") + ")"
             : "") +
        (surface ? ", " + t.cell(r, "mesh.boundary_edges") + " boundary and " +
                       t.cell(r, "mesh.nonmanifold_edges") + " non-manifold edges"
                 : "") +
        ", largest residual " + formatNumber(t.number(r, "accuracy.max_residual"), 2) + ", " +
        formatNumber(t.number(r, "timing_s.total"), 2) + " s.");
  }
  if (picks.size() > 1) gp.command("unset multiplot");
  a.gnuplot = gp.text();
  return a;
}

// --- any other experiment: one row per run -----------------------------------------------------

Artefact genericTable(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  Artefact a;
  a.id = id;
  a.figure = id.starts_with("fig");
  a.title = id;
  Table table;
  table.id = id;
  table.caption = "Every run of " + id + ".";
  const std::vector<std::string> wanted = {"run",
                                           "problem",
                                           "n",
                                           "k",
                                           "depth",
                                           "connection",
                                           "status",
                                           "cells.solution",
                                           "cells.abnormal",
                                           "mesh.components",
                                           "mesh.euler_characteristic",
                                           "accuracy.max_residual",
                                           "timing_s.total"};
  std::vector<std::string> present;
  for (const std::string& c : wanted)
    if (t.hasColumn(c)) present.push_back(c);
  table.columns = present;
  for (const std::string& c : present)
    table.align += c == "run" || c == "problem" || c == "status" || c == "connection" ? 'l' : 'r';
  for (std::size_t r = 0; r < t.size(); ++r) {
    std::vector<std::string> row;
    for (const std::string& c : present) {
      if (c.find('.') != std::string::npos)
        row.push_back(formatNumber(t.number(r, c), 3));
      else
        row.push_back(t.cell(r, c));
    }
    table.rows.push_back(std::move(row));
  }
  a.tables.push_back(std::move(table));
  a.sentences.push_back(std::to_string(okRows(t).size()) + " of " + std::to_string(t.size()) +
                        " runs succeeded.");
  return a;
}

}  // namespace

std::span<const std::string_view> knownArtefacts() { return knownList(); }

Artefact buildArtefact(const std::string& id, const CsvTable& csv,
                       const std::filesystem::path& dir) {
  Artefact a;
  if (id == "tab1-degeneracy")
    a = tab1Degeneracy(id, csv);
  else if (id == "fig-degeneracy-vs-n")
    a = figDegeneracyVsN(id, csv);
  else if (id == "tab-ablation-bounding")
    a = tabAblation(id, csv, "bounding");
  else if (id == "tab-ablation-subdivision")
    a = tabAblation(id, csv, "subdivision");
  else if (id == "tab-ablation-scalar")
    a = tabAblation(id, csv, "scalar");
  else if (id == "tab-connection")
    a = tabConnection(id, csv);
  else if (id == "fig-convergence")
    a = figConvergence(id, csv);
  else if (id == "fig-cells")
    a = figCells(id, csv, dir);
  else if (id.starts_with("fig-app-"))
    a = figApplication(id, csv, dir);
  else
    a = genericTable(id, csv);
  a.runs = csv.size();
  a.failures = failedRuns(csv);
  return a;
}

// --- The report --------------------------------------------------------------------------------

namespace {

/// The first string value of one of `keys` in a JSON text (a shallow, tolerant look-up for the
/// provenance record; "" when absent).
std::string jsonString(const std::string& json, std::initializer_list<std::string_view> keys) {
  for (std::string_view key : keys) {
    std::string quoted(1, '"');
    quoted.append(key);
    quoted += '"';
    std::size_t at = json.find(quoted);
    if (at == std::string::npos) continue;
    at = json.find(':', at + quoted.size());
    if (at == std::string::npos) continue;
    at = json.find_first_not_of(" \t\r\n", at + 1);
    if (at == std::string::npos || json[at] != '"') continue;
    const std::size_t end = json.find('"', at + 1);
    if (end != std::string::npos) return json.substr(at + 1, end - at - 1);
  }
  return "";
}

std::string paragraph(const std::vector<std::string>& sentences) { return join(sentences, " "); }

/// `<id>.md` of a table artefact: heading, each table with its caption, what it shows.
std::string artefactMarkdown(const Artefact& a) {
  std::string out = "# " + a.id + ": " + a.title + "\n\n";
  out += "Generated by `ndcontour report` from `" + a.id + ".csv`: do not edit.\n\n";
  for (const Table& t : a.tables) out += t.caption + "\n\n" + toMarkdown(t) + "\n";
  if (!a.sentences.empty()) out += paragraph(a.sentences) + "\n";
  return out;
}

/// The sentences as LaTeX: escaped, `code` as \texttt.
std::string sentencesLatex(const std::vector<std::string>& sentences) {
  std::string text = latexEscape(paragraph(sentences)), out;
  bool code = false;
  for (char c : text) {
    if (c == '`') {
      out += code ? "}" : "\\texttt{";
      code = !code;
    } else {
      out += c;
    }
  }
  return out + (code ? "}" : "") + "\n";
}

std::string runsLine(const Artefact& a) {
  return std::to_string(a.runs) + (a.runs == 1 ? " run, " : " runs, ") +
         std::to_string(a.failures.size()) + " failed.";
}

}  // namespace

ReportOutcome writeReport(const ReportSettings& settings, std::ostream& log) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(settings.results))
    throw InputError(settings.results.string() +
                     ": no such directory (run `ndcontour experiment` first)");
  ReportOutcome outcome;

  // The artefacts: the known ids, every config, every results/<id>/<id>.csv; known ones first
  // in report order, then application figures, then the rest, each sorted.
  std::vector<std::string> ids(knownList().begin(), knownList().end());
  std::set<std::string> others;
  std::error_code error;
  if (fs::is_directory(settings.configs, error))
    for (const auto& e : fs::directory_iterator(settings.configs, error))
      if (e.path().extension() == ".toml") others.insert(e.path().stem().string());
  for (const auto& e : fs::directory_iterator(settings.results, error))
    if (e.is_directory() && fs::exists(e.path() / (e.path().filename().string() + ".csv")))
      others.insert(e.path().filename().string());
  for (const std::string& id : others)
    if (id.starts_with("fig-app-") && std::find(ids.begin(), ids.end(), id) == ids.end())
      ids.push_back(id);
  for (const std::string& id : others)
    if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);

  const bool render = settings.render && gnuplotAvailable();
  if (settings.render && !render)
    outcome.notes.push_back(
        "gnuplot is not on PATH: the figure scripts (`<id>.gp`) are written "
        "but not rendered.");

  struct Section {
    std::string id, status, body;
    std::size_t runs = 0, failed = 0;
    bool figure = false;
  };
  std::vector<Section> sections;
  for (const std::string& id : ids) {
    Section section;
    section.id = id;
    section.figure = id.starts_with("fig");
    const fs::path dir = settings.results / id;
    const fs::path csvPath = dir / (id + ".csv");
    const bool hasConfig = fs::exists(settings.configs / (id + ".toml"));
    if (!fs::exists(csvPath)) {
      outcome.missing.push_back(id);
      section.status = "missing";
      section.body =
          "**Missing**: there is no `" + csvPath.string() + "`" +
          (hasConfig ? " (run `ndcontour experiment " +
                           (settings.configs / (id + ".toml")).string() + "`)."
                     : " and no config `" + (settings.configs / (id + ".toml")).string() + "`.") +
          "\n";
      log << "report: " << id << ": missing (" << csvPath.string() << ")\n";
      sections.push_back(std::move(section));
      continue;
    }
    try {
      const CsvTable csv = readCsv(csvPath);
      const Artefact a = buildArtefact(id, csv, dir);
      section.runs = a.runs;
      section.failed = a.failures.size();
      outcome.failedRuns += a.failures.size();
      std::string body;
      std::string render_note;
      // The sentences for the paper, beside the table or figure.
      writeAtomically(dir / (id + "-summary.tex"), sentencesLatex(a.sentences));
      if (!a.figure) {
        writeAtomically(dir / (id + ".md"), artefactMarkdown(a));
        writeAtomically(dir / (id + ".tex"), toLatex(a.tables.front()));
        for (std::size_t i = 0; i < a.tables.size(); ++i)
          body += a.tables[i].caption + "\n\n" + toMarkdown(a.tables[i]) + "\n";
        body += paragraph(a.sentences) + "\n\n";
      } else {
        if (!a.gnuplot.empty()) {
          writeAtomically(dir / (id + ".gp"), a.gnuplot);
          if (render) {
            const std::string problem = renderGnuplot(dir, id);
            if (!problem.empty()) {
              outcome.errors.push_back(id + ": " + problem);
              render_note = "**Not rendered**: " + problem + ".";
            }
          } else {
            render_note = "*Not rendered (gnuplot is not on PATH)*; script: [" + id + ".gp](" + id +
                          "/" + id + ".gp).";
          }
          if (render_note.empty() || fs::exists(dir / (id + ".png")))
            body += "![" + id + "](" + id + "/" + id + ".png)\n\n";
          if (!render_note.empty()) body += render_note + "\n\n";
        }
        // Application figures: also each run rendered by the application's own script
        // (experiments/gnuplot/<application>.gp, `gnuplot -e "dir='RUN'"` writes
        // RUN/<application>.png), when there is one.
        fs::path configs = settings.configs;
        if (!configs.has_filename()) configs = configs.parent_path();
        const std::string application = id.starts_with("fig-app-") ? id.substr(8) : "";
        const fs::path script = configs.parent_path() / "gnuplot" / (application + ".gp");
        if (render && !application.empty() && fs::exists(script)) {
          std::vector<std::string> failedScripts;
          for (const std::string& run : a.shownRuns) {
            const fs::path runDir = fs::absolute(dir / "runs" / run);
            const std::string command =
                "gnuplot -e \"dir='" + runDir.string() + "'\" " +
                shellQuote(fs::absolute(script).string()) + " > " +
                shellQuote((runDir / (application + ".gnuplot.log")).string()) + " 2>&1";
            if (std::system(command.c_str()) == 0 && fs::exists(runDir / (application + ".png")))
              body += "![" + run + "](" + id + "/runs/" + run + "/" + application + ".png)\n\n";
            else
              failedScripts.push_back(run);
          }
          if (!failedScripts.empty())
            body += "The script " + script.string() + " failed on " + join(failedScripts, ", ") +
                    " (see `runs/<run>/" + application + ".gnuplot.log`).\n\n";
        }
        body += paragraph(a.sentences) + "\n\n";
        for (const Table& t : a.tables)
          if (!t.rows.empty()) body += t.caption + "\n\n" + toMarkdown(t) + "\n";
      }
      body += runsLine(a);
      if (!a.failures.empty()) {
        body += " Failed runs:\n\n";
        for (const std::string& f : a.failures) body += "- " + f + "\n";
      }
      body += "\n";
      std::vector<std::string> files = {"[CSV](" + id + "/" + id + ".csv)"};
      if (!a.figure) {
        files.push_back("[Markdown](" + id + "/" + id + ".md)");
        files.push_back("[LaTeX](" + id + "/" + id + ".tex)");
      } else if (!a.gnuplot.empty()) {
        files.push_back("[gnuplot](" + id + "/" + id + ".gp)");
        if (fs::exists(dir / (id + ".pdf"))) files.push_back("[PDF](" + id + "/" + id + ".pdf)");
      }
      const fs::path provenance = dir / "provenance.json";
      std::string origin;
      if (fs::exists(provenance)) {
        files.push_back("[provenance](" + id + "/provenance.json)");
        std::ifstream in(provenance);
        std::ostringstream read;
        read << in.rdbuf();
        const std::string text = read.str();
        // Which code made the results, in which mode, when (provenance.json of the runner).
        const std::string revision =
            jsonString(text, {"git_revision", "revision", "commit", "git"});
        const std::string date = jsonString(text, {"date"});
        if (!revision.empty()) {
          origin += "; code revision `";
          origin += revision.substr(0, 12);
          origin += '`';
          if (text.find("\"dirty\": true") != std::string::npos)
            origin += " with uncommitted changes";
        }
        if (text.find("\"quick\": true") != std::string::npos) origin += ", quick grid";
        if (text.find("\"quick\": false") != std::string::npos) origin += ", full grid";
        if (!date.empty()) origin += ", run " + date;
      }
      body += "\nFiles: " + join(files, ", ") + origin + ".\n";
      section.body = std::move(body);
      section.status = !render_note.empty() && render ? "not rendered"
                       : a.failures.empty()           ? "ok"
                                            : std::to_string(a.failures.size()) + " failed";
      section.figure = a.figure;
      section.body = "*" + a.title + ".*\n\n" + section.body;
      outcome.written.push_back(id);
      log << "report: " << id << ": " << a.runs << " runs, " << a.failures.size() << " failed\n";
      sections.push_back(std::move(section));
    } catch (const std::exception& e) {  // InputError, or a value the builder cannot use
      outcome.errors.push_back(e.what());
      section.status = "error";
      section.body = "**Could not be made**: " + std::string(e.what()) +
                     " (previous outputs, if any, are left as they were).\n";
      log << "report: " << id << ": error: " << e.what() << "\n";
      sections.push_back(std::move(section));
    }
  }

  // results/report.md: overview, notes, then every artefact.
  std::string report = "# ndcontour: experiments report\n\n";
  report +=
      "Generated by `ndcontour report` from `" + settings.results.string() + "/<id>/<id>.csv`, " +
      (settings.quick ? "**quick mode** (`ndcontour experiment --quick`: reduced depths "
                        "and seeds; `scripts/run.sh --full` runs the full grids)"
                      : "full mode") +
      ". Every artefact has one id, the same in its config (`experiments/configs/<id>.toml`), "
      "its result files (`results/<id>/`) and the paper (`paper/ndcontour.tex`).\n\n";
  Table overview;
  overview.columns = {"artefact", "kind", "runs", "failed", "status"};
  overview.align = "llrrl";
  for (const Section& s : sections)
    overview.rows.push_back(
        {"[" + s.id + "](#" + s.id + ")", s.figure ? "figure" : "table",
         s.status == "missing" || s.status == "error" ? std::string(kDash) : std::to_string(s.runs),
         s.status == "missing" || s.status == "error" ? std::string(kDash)
                                                      : std::to_string(s.failed),
         s.status});
  report += toMarkdown(overview) + "\n";
  if (!outcome.missing.empty())
    report += "Missing experiments: " + join(outcome.missing, ", ") + ".\n\n";
  report += "Failed runs over all experiments: " + std::to_string(outcome.failedRuns) +
            " (each is named in its section).\n\n";
  for (const std::string& note : outcome.notes) report += "Note: " + note + "\n\n";
  for (const std::string& e : outcome.errors) report += "Error: " + e + "\n\n";
  for (const Section& s : sections) report += "## " + s.id + "\n\n" + s.body + "\n";
  writeAtomically(settings.results / "report.md", report);

  // results/applications.tex: one figure per application for the paper (it cannot know the
  // application ids in advance); paper/ndcontour.tex defines \artefactfigure.
  std::string applications =
      "% Generated by `ndcontour report`: one figure per fig-app-* artefact; do not edit.\n";
  for (const std::string& id : outcome.written)
    if (id.starts_with("fig-app-"))
      applications += "\\artefactfigure{" + id + "}{" + latexEscape(id.substr(8)) + " (" +
                      latexEscape(id) + "): the mesh in R\\textsuperscript{3}.}\n";
  writeAtomically(settings.results / "applications.tex", applications);
  log << "report: wrote " << (settings.results / "report.md").string() << "\n";

  bool badInput = false;
  for (const Section& s : sections) badInput |= s.status == "error";
  outcome.status = badInput ? 2
                   : (!outcome.missing.empty() || outcome.failedRuns || !outcome.errors.empty())
                       ? 1
                       : 0;
  return outcome;
}

}  // namespace ndc::report
