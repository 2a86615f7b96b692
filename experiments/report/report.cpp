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

#include <toml++/toml.h>

#include "experiments/view/view.hpp"
#include "framework/core/problem.hpp"
#include "framework/core/toml_reader.hpp"

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

/// A LaTeX column title: escaped, on two lines (split at the space nearest its middle) in wide
/// tables, so that they fit the text at a readable size.
std::string latexColumnTitle(const std::string& title, bool wide) {
  std::size_t split = std::string::npos;
  for (std::size_t i = 0; i < title.size(); ++i)
    if (title[i] == ' ' && (split == std::string::npos || std::abs(2.0 * i - title.size()) <
                                                              std::abs(2.0 * split - title.size())))
      split = i;
  if (!wide || split == std::string::npos) return latexEscape(title);
  return "\\begin{tabular}[b]{@{}c@{}}" + latexEscape(title.substr(0, split)) + "\\\\" +
         latexEscape(title.substr(split + 1)) + "\\end{tabular}";
}

std::string toLatex(const Table& table) {
  std::string align;
  for (std::size_t c = 0; c < table.columns.size(); ++c)
    align += c < table.align.size() ? table.align[c] : 'l';
  std::string out = "% Generated by `ndcontour report` from results/" + table.id + "/" + table.id +
                    ".csv: do not edit.\n";
  out += "\\begin{table}[htbp]\n  \\centering\n  \\caption{" + latexEscape(table.caption) +
         "}\n  \\label{" + table.id + "}\n";
  // A readable size; shrink a table still wider than the text to the text width, never enlarge
  // it (graphicx).
  out += "  \\small\\setlength{\\tabcolsep}{4pt}\n";
  out += "  \\resizebox{\\ifdim\\width>\\linewidth\\linewidth\\else\\width\\fi}{!}{%\n";
  out += "  \\begin{tabular}{" + align + "}\n    \\toprule\n    ";
  const bool wide = table.columns.size() > 8;
  for (std::size_t c = 0; c < table.columns.size(); ++c)
    out += (c ? " & " : "") + latexColumnTitle(table.columns[c], wide);
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
  // Wide canvases are shrunk to the text width in the paper: a larger font keeps them readable.
  const int pdfFont = static_cast<int>(std::lround(8 * std::max(1.0, width_ / 1000.0)));
  out += "    set terminal pdfcairo size " + std::string(size) + " enhanced font \"Sans," +
         std::to_string(pdfFont) + "\"\n  }\n";
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

// --- Artefacts ---------------------------------------------------------------------------------

namespace {

/// Run settings that may vary within an experiment (jitter seeds are averaged over instead).
const std::vector<std::string> kSettingColumns = {"depth",      "bounding",       "subdivision",
                                                  "projection", "classification", "connection",
                                                  "scalar",     "precision_bits"};

std::string join(const std::vector<std::string>& parts, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i)
    out += (i ? std::string(separator) : "") + parts[i];
  return out;
}

std::string percent(double value) { return formatFixed(value, 1) + "%"; }

/// `prefix` and `sentence` as one sentence: "Table 1: our abnormal share ...".
std::string prefixed(const std::string& prefix, std::string sentence) {
  if (!sentence.empty() && std::isupper(static_cast<unsigned char>(sentence[0])) &&
      !(sentence.size() > 1 && std::isupper(static_cast<unsigned char>(sentence[1]))))
    sentence[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(sentence[0])));
  return prefix + ": " + sentence;
}

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

std::string normalised(std::string_view text) {
  std::string out;
  for (char c : text)
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// --- tab1-degeneracy: the paper's Table 1 ------------------------------------------------------

/// One example of the paper's Table 1, as read from `<reference>/table1.toml`.
struct PaperRow {
  std::string key;        ///< matched against the normalised problem name and file stem
  std::string label;      ///< the paper's example, e.g. "Bisector, Fig. 8(a)"
  std::string family;     ///< the application: bisector, sweep or blending
  std::string highlight;  ///< optional: how the sentences name a row the paper singles out
  int n = 0;
  double normal = 0, abnormal = 0, share = 0;
};

/// A string of a reference row; throws InputError naming the file, row and key.
std::string referenceString(const toml::table& row, const std::string& where, const char* key,
                            bool required) {
  const toml::node* node = row.get(key);
  if (!node && !required) return "";
  const std::optional<std::string> value = node ? node->value<std::string>() : std::nullopt;
  if (!value || value->empty())
    throw InputError(where + ": '" + key + "' must be a non-empty string");
  return *value;
}

/// A number >= 0 of a reference row; throws InputError naming the file, row and key.
double referenceNumber(const toml::table& row, const std::string& where, const char* key) {
  const toml::node* node = row.get(key);
  const std::optional<double> value = node ? node->value<double>() : std::nullopt;
  if (!value || !std::isfinite(*value) || *value < 0)
    throw InputError(where + ": '" + key + "' must be a number >= 0");
  return *value;
}

/// One `[[row]]` of table1.toml.
PaperRow paperRowFrom(const toml::node& node, const std::string& where) {
  const toml::table* row = node.as_table();
  if (!row) throw InputError(where + ": not a table");
  PaperRow p;
  p.key = normalised(referenceString(*row, where, "key", true));
  p.label = referenceString(*row, where, "label", true);
  p.family = referenceString(*row, where, "family", true);
  p.highlight = referenceString(*row, where, "highlight", false);
  const toml::node* n = row->get("n");
  const std::optional<std::int64_t> dimension = n ? n->value<std::int64_t>() : std::nullopt;
  if (!dimension || *dimension < 1 || *dimension > 1000)
    throw InputError(where + ": 'n' must be an integer 1..1000");
  p.n = static_cast<int>(*dimension);
  p.normal = referenceNumber(*row, where, "normal");
  p.abnormal = referenceNumber(*row, where, "abnormal");
  p.share = referenceNumber(*row, where, "share");
  return p;
}

/// The paper's Table 1 from `<reference>/table1.toml` (a `[[row]]` per example, in the paper's
/// order). Throws InputError (one line, naming the file) when it is missing or malformed.
std::vector<PaperRow> loadPaperTable1(const std::filesystem::path& reference) {
  const std::filesystem::path file = reference / "table1.toml";
  const std::string name = file.string();
  if (!std::filesystem::is_regular_file(file))
    throw InputError(name + ": the paper's reference figures are missing");
  const std::string text = readText(file);
  const toml::table top = parseTomlText(text, name);
  const toml::array* rows = top["row"].as_array();
  if (!rows || rows->empty()) throw InputError(name + ": no [[row]] of the paper's Table 1");
  std::vector<PaperRow> table;
  for (std::size_t i = 0; i < rows->size(); ++i) {
    table.push_back(paperRowFrom((*rows)[i], name + ": row " + std::to_string(i + 1)));
    for (std::size_t j = 0; j + 1 < table.size(); ++j)
      if (table[j].key == table.back().key)
        throw InputError(name + ": row " + std::to_string(i + 1) + ": duplicate key '" +
                         table.back().key + "'");
  }
  return table;
}

/// "sweep, Fig. 9(b)" for the label "Sweep, Fig. 9(b)": the family, then what follows the
/// label's first comma (the whole label when it has none).
std::string paperExample(const PaperRow& p) {
  const std::size_t comma = p.label.find(',');
  return comma == std::string::npos ? p.label : p.family + p.label.substr(comma);
}

/// The paper's row a result row stands in for (-1: none).
int paperRowOf(const std::vector<PaperRow>& paper, const CsvTable& t, std::size_t r) {
  const std::string name =
      normalised(t.cell(r, "problem")) + " " +
      normalised(std::filesystem::path(t.cell(r, "problem_file")).stem().string());
  // Longest key first so that "fig10a" is not taken for a shorter key.
  int best = -1;
  for (std::size_t i = 0; i < paper.size(); ++i) {
    const std::string& key = paper[i].key;
    std::size_t at = name.find(key);
    while (at != std::string::npos) {
      const std::size_t end = at + key.size();
      // "fig9" must not match "fig9x..." where a letter continues the figure label.
      const bool whole = end >= name.size() ||
                         !std::isalpha(static_cast<unsigned char>(name[end])) || key.back() >= 'a';
      if (whole && (best < 0 || key.size() > paper[best].key.size())) best = static_cast<int>(i);
      at = name.find(key, at + 1);
    }
  }
  return best;
}

/// One setting of a run: a column of the CSV and its value, e.g. bounding = bernstein.
struct Setting {
  std::string column, value;
};

/// Table 1's main columns use the paper's settings: Bernstein bounding and its connection.
const std::vector<Setting> kTable1Main = {{"bounding", "bernstein"}, {"connection", "paper"}};
/// Table 1's extra columns: the abnormal share with one of these settings instead.
const std::vector<Setting> kTable1Extra = {{"bounding", "linearized"}, {"connection", "crossing"}};

bool hasSetting(const CsvTable& t, std::span<const std::size_t> rows, const Setting& s) {
  return t.hasColumn(s.column) && std::any_of(rows.begin(), rows.end(), [&](std::size_t r) {
           return t.cell(r, s.column) == s.value;
         });
}

/// `rows` restricted to each of `settings` that some of them have (a setting no row has, e.g.
/// an old CSV without Bernstein runs, does not filter).
std::vector<std::size_t> withSettings(const CsvTable& t, std::vector<std::size_t> rows,
                                      const std::vector<Setting>& settings) {
  for (const Setting& s : settings)
    if (hasSetting(t, rows, s))
      std::erase_if(rows, [&](std::size_t r) { return t.cell(r, s.column) != s.value; });
  return rows;
}

/// The rows of Table 1's main columns: the successful runs with the paper's settings.
std::vector<std::size_t> table1MainRows(const CsvTable& t) {
  return withSettings(t, okRows(t), kTable1Main);
}

/// The extra columns Table 1 has: the extra settings that some successful run used and the
/// main columns do not.
std::vector<Setting> table1Extras(const CsvTable& t) {
  const std::vector<std::size_t> ok = okRows(t), main = table1MainRows(t);
  std::vector<Setting> extras;
  for (const Setting& s : kTable1Extra)
    if (hasSetting(t, ok, s) && !hasSetting(t, main, s)) extras.push_back(s);
  return extras;
}

/// One of our results set beside the paper's row `paper` (-1: not in the paper); `extra`: the
/// abnormal share under each of table1Extras (NaN: no such run).
struct Ours {
  std::string problem;
  int paper;
  double normal, abnormal, share, failed;
  std::vector<double> extra;
};

/// Builds tab1-degeneracy's table row by row and collects our figures for the sentences.
class Table1Rows {
 public:
  Table1Rows(const CsvTable& t, const std::vector<PaperRow>& paper,
             const std::vector<std::string>& vary, const std::vector<Setting>& extras, Table& table)
      : t_(t), paper_(paper), vary_(vary), extras_(extras), table_(table) {}

  /// Adds the row of group `g` (nullptr: the paper's example without a result of ours).
  void add(const Group* g, int paper) {
    std::vector<std::string> row;
    row.push_back(paper >= 0 ? paper_[paper].label : "(not in the paper)");
    if (g) {
      ours(*g, paper, row);
    } else {
      row.push_back("(no result)");
      row.push_back(paper >= 0 ? std::to_string(paper_[paper].n) : "");
      const std::size_t dashes = (vary_.empty() ? 4u : 5u) + extras_.size();
      for (std::size_t c = 0; c < dashes; ++c) row.push_back(std::string(kDash));
    }
    if (paper >= 0) {
      row.push_back(formatNumber(paper_[paper].normal));
      row.push_back(formatNumber(paper_[paper].abnormal));
      row.push_back(formatFixed(paper_[paper].share, 1));
    } else {
      for (int c = 0; c < 3; ++c) row.push_back(std::string(kDash));
    }
    table_.rows.push_back(std::move(row));
  }

  std::vector<Ours> results;  ///< our groups, in table order

 private:
  /// The mean abnormal share of the successful runs like `r0` (problem, depth, other varying
  /// settings) but with `extra`, preferring those that keep the main columns' other settings.
  double extraShare(std::size_t r0, const Setting& extra) const {
    std::vector<std::size_t> like;
    for (std::size_t r : okRows(t_)) {
      bool same = t_.cell(r, "problem") == t_.cell(r0, "problem") &&
                  t_.cell(r, "depth") == t_.cell(r0, "depth") &&
                  t_.cell(r, extra.column) == extra.value;
      for (const std::string& c : vary_) same = same && t_.cell(r, c) == t_.cell(r0, c);
      if (same) like.push_back(r);
    }
    std::vector<Setting> others;
    for (const Setting& s : kTable1Main)
      if (s.column != extra.column) others.push_back(s);
    like = withSettings(t_, std::move(like), others);
    return like.empty() ? kNaN
                        : abnormalShare(meanOf(t_, like, "cells.normal"),
                                        meanOf(t_, like, "cells.abnormal"));
  }

  void ours(const Group& g, int paper, std::vector<std::string>& row) {
    const std::size_t r0 = g.rows.front();
    const double normal = meanOf(t_, g.rows, "cells.normal");
    const double abnormal = meanOf(t_, g.rows, "cells.abnormal");
    Ours o{t_.cell(r0, "problem"),
           paper,
           normal,
           abnormal,
           abnormalShare(normal, abnormal),
           meanOf(t_, g.rows, "cells.failed"),
           {}};
    row.push_back(t_.cell(r0, "problem"));
    row.push_back(t_.cell(r0, "n"));
    row.push_back(t_.cell(r0, "depth"));
    if (!vary_.empty()) row.push_back(settingsLabel(t_, r0, vary_));
    row.push_back(formatNumber(std::round(normal)));
    row.push_back(formatNumber(std::round(abnormal)));
    row.push_back(formatFixed(o.share, 1));
    for (const Setting& s : extras_) {
      o.extra.push_back(extraShare(r0, s));
      row.push_back(formatFixed(o.extra.back(), 1));
    }
    results.push_back(std::move(o));
  }

  const CsvTable& t_;
  const std::vector<PaperRow>& paper_;
  const std::vector<std::string>& vary_;
  const std::vector<Setting>& extras_;
  Table& table_;
};

/// The paper's rows with the lowest and highest abnormal share (first of equals).
std::pair<const PaperRow*, const PaperRow*> paperShareRange(const std::vector<PaperRow>& paper) {
  const auto byShare = [](const PaperRow& x, const PaperRow& y) { return x.share < y.share; };
  return {&*std::min_element(paper.begin(), paper.end(), byShare),
          &*std::max_element(paper.begin(), paper.end(), byShare)};
}

/// "Mean abnormal share by application: ...", the families in order of their dimension n.
std::string familySentence(const std::vector<PaperRow>& paper, const std::vector<Ours>& ours) {
  std::vector<const PaperRow*> firsts;  // the first row of each family, by n
  for (const PaperRow& p : paper)
    if (std::none_of(firsts.begin(), firsts.end(),
                     [&](const PaperRow* f) { return f->family == p.family; }))
      firsts.push_back(&p);
  std::stable_sort(firsts.begin(), firsts.end(),
                   [](const PaperRow* x, const PaperRow* y) { return x->n < y->n; });
  std::vector<std::string> families, paperFamilies;
  for (const PaperRow* f : firsts) {
    std::vector<double> mine, theirs;
    int n = 0;
    for (const Ours& o : ours)
      if (o.paper >= 0 && paper[o.paper].family == f->family) mine.push_back(o.share);
    for (const PaperRow& p : paper)
      if (p.family == f->family) theirs.push_back(p.share), n = p.n;
    if (mine.empty()) continue;
    families.push_back(f->family + " (n = " + std::to_string(n) + ") " +
                       percent(summarize(mine).mean));
    paperFamilies.push_back(percent(summarize(theirs).mean));
  }
  if (families.empty()) return "";
  return "Mean abnormal share by application: " + join(families, ", ") +
         "; the paper: " + join(paperFamilies, ", ") + ".";
}

/// For each row the paper singles out (`highlight`, e.g. Fig. 8(b), the highest bisector
/// share): whether ours is also the highest of its family.
void highlightSentences(const std::vector<PaperRow>& paper, const std::vector<Ours>& ours,
                        std::vector<std::string>& sentences) {
  const auto shareOf = [&](std::size_t row) {
    for (const Ours& o : ours)
      if (o.paper == static_cast<int>(row)) return o.share;
    return kNaN;
  };
  for (std::size_t h = 0; h < paper.size(); ++h) {
    const double b = shareOf(h);
    if (paper[h].highlight.empty() || !std::isfinite(b)) continue;
    bool highest = true;
    for (std::size_t o = 0; o < paper.size(); ++o)
      if (o != h && paper[o].family == paper[h].family)
        highest = highest && b >= shareOf(o) - 1e-9 && !(b < shareOf(o));
    const std::size_t comma = paper[h].label.find(", ");
    const std::string figure =
        comma == std::string::npos ? paper[h].label : paper[h].label.substr(comma + 2);
    sentences.push_back("The " + paper[h].highlight + " of " + figure + " has " + percent(b) +
                        (highest
                             ? ", the highest " + paper[h].family + " share, as in the paper."
                             : ", not the highest " + paper[h].family +
                                   " share, unlike the paper (" + percent(paper[h].share) + ")."));
  }
}

/// "With linearized bounding ...": per extra column, its mean share beside the main one's.
void extraSentences(const std::vector<Setting>& extras, const std::vector<Ours>& ours,
                    std::vector<std::string>& sentences) {
  for (std::size_t e = 0; e < extras.size(); ++e) {
    std::vector<double> main, extra;
    for (const Ours& o : ours)
      if (e < o.extra.size() && std::isfinite(o.extra[e]) && std::isfinite(o.share))
        main.push_back(o.share), extra.push_back(o.extra[e]);
    if (extra.empty()) continue;
    sentences.push_back("With " + extras[e].column + " `" + extras[e].value +
                        "` instead the mean abnormal share over " + std::to_string(extra.size()) +
                        " example(s) is " + percent(summarize(extra).mean) + " (" +
                        percent(summarize(main).mean) + " in the main columns).");
  }
}

/// What tab1-degeneracy shows: our range beside the paper's, by family, the highlighted rows,
/// the extra columns, the cell count ratio and the failed cells.
std::vector<std::string> table1Sentences(const std::vector<PaperRow>& paper,
                                         const std::vector<Ours>& ours,
                                         const std::vector<Setting>& extras = {}) {
  const auto [paperLo, paperHi] = paperShareRange(paper);
  if (ours.empty())
    return {"No run succeeded, so there is nothing to set beside the paper's figures (" +
            formatFixed(paperLo->share, 1) + "% to " + percent(paperHi->share) + " abnormal)."};
  std::vector<std::string> sentences;
  // Our range beside the paper's.
  const auto byShare = [](const Ours& x, const Ours& y) { return x.share < y.share; };
  const auto lo = std::min_element(ours.begin(), ours.end(), byShare);
  const auto hi = std::max_element(ours.begin(), ours.end(), byShare);
  sentences.push_back("Our abnormal share ranges from " + percent(lo->share) + " (" + lo->problem +
                      ") to " + percent(hi->share) + " (" + hi->problem + "); the paper's from " +
                      percent(paperLo->share) + " (" + paperExample(*paperLo) + ") to " +
                      percent(paperHi->share) + " (" + paperExample(*paperHi) + ").");
  // By application, and the rows the paper singles out.
  if (std::string family = familySentence(paper, ours); !family.empty())
    sentences.push_back(std::move(family));
  highlightSentences(paper, ours, sentences);
  extraSentences(extras, ours, sentences);
  // Cell counts against the paper's.
  std::vector<std::pair<double, double>> totals;
  for (const Ours& o : ours)
    if (o.paper >= 0)
      totals.emplace_back(o.normal + o.abnormal, paper[o.paper].normal + paper[o.paper].abnormal);
  const double ratio = geometricMeanRatio(totals);
  if (std::isfinite(ratio))
    sentences.push_back(
        "Our problems are our own stand-ins for the paper's freeform surfaces "
        "and the paper gives no depth, so the cell counts differ: ours are " +
        formatFixed(ratio, 2) + " times the paper's (geometric mean).");
  // Cells left out of the shares.
  double failedCells = 0;
  for (const Ours& o : ours) failedCells += o.failed;
  if (failedCells > 0)
    sentences.push_back("Cells whose Newton projection failed (" + formatNumber(failedCells) +
                        " in all; the paper has no such class) are left out of the shares.");
  return sentences;
}

/// The settings of Table 1's main columns as used, e.g. "bounding `bernstein`, connection
/// `paper`" ("" without such columns).
std::string table1MainLabel(const CsvTable& t, std::span<const std::size_t> main) {
  std::vector<std::string> parts;
  for (const Setting& s : kTable1Main)
    if (t.hasColumn(s.column) && !main.empty())
      parts.push_back(s.column + " " + t.cell(main.front(), s.column));
  return join(parts, ", ");
}

/// tab1-degeneracy's header: the example, ours, the extra shares, the paper's.
Table table1Header(const std::string& id, const std::vector<std::string>& vary,
                   const std::vector<Setting>& extras, const std::string& mainLabel) {
  Table table;
  table.id = id;
  table.caption =
      "Normal and abnormal solution cells (paper's Table 1), ours beside the paper's; "
      "abnormal % = abnormal / (normal + abnormal)" +
      (mainLabel.empty() ? std::string() : "; ours with " + mainLabel + ", as in the paper") +
      (extras.empty() ? std::string(".")
                      : "; the extra columns: the abnormal % with one setting changed.");
  table.columns = {"example", "problem", "n", "depth"};
  table.align = vary.empty() ? "llrr" : "llrrl";
  if (!vary.empty()) table.columns.push_back("settings");
  for (std::string c : {"normal", "abnormal", "abnormal %"}) table.columns.push_back(c);
  for (const Setting& s : extras) table.columns.push_back("abnormal % " + s.value);
  for (std::string c : {"paper normal", "paper abnormal", "paper abnormal %"})
    table.columns.push_back(c);
  table.align += std::string(6 + extras.size(), 'r');
  return table;
}

/// tab1-degeneracy's bar chart: per example of the paper the abnormal share, ours (the first
/// depth of ours, main columns and the extra ones) beside the paper's.
std::string table1Chart(const std::string& id, const std::vector<PaperRow>& paper,
                        const std::vector<Ours>& ours, const std::vector<Setting>& extras) {
  std::vector<std::vector<double>> bars;
  std::vector<std::string> tics;
  for (std::size_t p = 0; p < paper.size(); ++p) {
    std::vector<double> row = {static_cast<double>(p), kNaN};
    row.resize(2 + extras.size(), kNaN);
    for (const Ours& o : ours)
      if (o.paper == static_cast<int>(p) && !std::isfinite(row[1])) {
        row[1] = o.share;
        for (std::size_t e = 0; e < extras.size() && e < o.extra.size(); ++e)
          row[2 + e] = o.extra[e];
      }
    row.push_back(paper[p].share);
    bars.push_back(std::move(row));
    const std::size_t comma = paper[p].label.find(", ");
    tics.push_back("\"" + paper[p].label.substr(0, comma) + "\\n" +
                   (comma == std::string::npos ? "" : paper[p].label.substr(comma + 2)) + "\" " +
                   std::to_string(p));
  }
  // One bar per series, side by side around each example.
  static const char* colours[] = {"#3a6ea5", "#9ecae1", "#c6dbef", "#d62728"};
  std::vector<std::string> titles = {"ours (Bernstein, paper's connection)"};
  for (const Setting& s : extras) titles.push_back("ours, " + s.column + " " + s.value);
  titles.push_back("paper (Table 1)");
  const double width = 0.8 / static_cast<double>(titles.size());
  GnuplotScript gp(id, 1100, 520);
  gp.data("bars", bars);
  gp.command("set title \"" + id + ": abnormal share per example, ours beside the paper's\"");
  gp.command("set ylabel \"abnormal share (%)\"");
  gp.command("set yrange [0:100]");
  gp.command("set xrange [-0.6:" + formatFixed(paper.size() - 0.4, 1) + "]");
  gp.command("set xtics (" + join(tics, ", ") + ") noenhanced");
  gp.command("set grid ytics");
  gp.command("set bmargin 4");
  gp.command("set key top left");
  gp.command("set style fill solid 0.9 border lc rgb \"#404040\"");
  gp.command("set boxwidth " + formatFixed(width, 3) + " absolute");
  std::vector<std::string> plots;
  for (std::size_t s = 0; s < titles.size(); ++s) {
    const double offset = (static_cast<double>(s) - 0.5 * (titles.size() - 1)) * width;
    const std::string colour =
        s + 1 == titles.size() ? colours[3] : colours[std::min<std::size_t>(s, 2)];
    plots.push_back("$bars using ($1+" + formatFixed(offset, 3) + "):" + std::to_string(s + 2) +
                    " with boxes lc rgb \"" + colour + "\" title \"" + titles[s] + "\"");
  }
  gp.command("plot " + join(plots, ", \\\n       "));
  return gp.text();
}

Artefact tab1Degeneracy(const std::string& id, const CsvTable& t,
                        const std::vector<PaperRow>& paper) {
  requireRunColumns(t);
  requireColumns(t,
                 {"problem_file", "n", "depth", "cells.normal", "cells.abnormal", "cells.failed"});
  Artefact a;
  a.id = id;
  a.title = "Table 1 reproduced: normal and abnormal solution cells";
  // The main columns: the runs with the paper's settings, one group per problem, depth and
  // other varying setting; the extra columns: one setting changed.
  const std::vector<std::size_t> main = table1MainRows(t);
  const std::vector<Setting> extras = table1Extras(t);
  const std::vector<std::string> vary =
      without(varyingColumns(t, kSettingColumns), {"depth", "bounding", "connection"});
  std::vector<std::string> keys = {"problem", "depth"};
  keys.insert(keys.end(), vary.begin(), vary.end());
  const std::vector<Group> groups = groupBy(t, keys, main);
  Table table = table1Header(id, vary, extras, table1MainLabel(t, main));

  // The paper's order, then our problems that are not in the paper.
  Table1Rows rows(t, paper, vary, extras, table);
  std::vector<bool> used(groups.size(), false);
  for (std::size_t p = 0; p < paper.size(); ++p) {
    bool any = false;
    for (std::size_t g = 0; g < groups.size(); ++g)
      if (paperRowOf(paper, t, groups[g].rows.front()) == static_cast<int>(p)) {
        rows.add(&groups[g], static_cast<int>(p));
        used[g] = any = true;
      }
    if (!any) rows.add(nullptr, static_cast<int>(p));
  }
  for (std::size_t g = 0; g < groups.size(); ++g)
    if (!used[g]) rows.add(&groups[g], -1);
  a.tables.push_back(std::move(table));

  // What it shows, and the bar chart.
  a.sentences = table1Sentences(paper, rows.results, extras);
  if (rows.results.empty()) return a;
  a.gnuplot = table1Chart(id, paper, rows.results, extras);
  // For the conclusion: the range and the families beside the paper's.
  a.conclusion.push_back(prefixed("In Table 1", a.sentences.front()));
  if (std::string family = familySentence(paper, rows.results); !family.empty())
    a.conclusion.push_back(family);
  highlightSentences(paper, rows.results, a.conclusion);
  return a;
}

// --- fig-degeneracy-vs-n -----------------------------------------------------------------------

/// The state of fig-degeneracy-vs-n while its series are added.
struct DegeneracyPlot {
  Table data;                        ///< per series and n: the share's statistics
  GnuplotScript gp;                  ///< the figure
  std::vector<std::string> plots;    ///< the plot clauses
  int nMin = 100, nMax = 0;          ///< the range of n
  std::map<int, double> sphereMean;  ///< mean share per n of the first k = 2 series
};

/// The share's statistics at one n of a series: adds the table row, the mean (with min, max,
/// sd) to `means`, every run to `points`; returns the statistics.
Stats degeneracyAtN(const CsvTable& t, const Group& series, const Group& cell,
                    const std::vector<std::string>& vary, DegeneracyPlot& plot,
                    std::vector<std::vector<double>>& means,
                    std::vector<std::vector<double>>& points) {
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
  plot.nMin = std::min(plot.nMin, n);
  plot.nMax = std::max(plot.nMax, n);
  std::vector<std::string> row = {series.key[0],
                                  cell.key[0],
                                  join({depths.begin(), depths.end()}, "/"),
                                  std::to_string(st.count),
                                  formatFixed(st.mean, 1),
                                  formatFixed(st.stddev, 1),
                                  formatFixed(st.min, 1),
                                  formatFixed(st.max, 1)};
  if (!vary.empty()) row.insert(row.begin() + 1, settingsLabel(t, series.rows[0], vary));
  plot.data.rows.push_back(std::move(row));
  return st;
}

/// What a series shows: first to last n, whether every step goes up, and the paper's claim.
void degeneracySentences(const std::string& label, const std::string& k,
                         const std::vector<std::pair<int, double>>& trend, double widest,
                         std::vector<std::string>& sentences) {
  std::string sentence =
      "For " + label + " the abnormal share " +
      (trend.back().second >= trend.front().second ? "rises" : "falls") + " from " +
      percent(trend.front().second) + " at n = " + std::to_string(trend.front().first) + " to " +
      percent(trend.back().second) + " at n = " + std::to_string(trend.back().first);
  std::vector<std::string> drops;
  for (std::size_t i = 1; i < trend.size(); ++i)
    if (trend[i].second < trend[i - 1].second)
      drops.push_back(std::to_string(trend[i - 1].first) + " to " + std::to_string(trend[i].first));
  if (trend.size() > 2)
    sentence += drops.empty() ? ", increasing at every step"
                              : ", not monotonically (it drops from n = " + join(drops, ", ") + ")";
  sentence += "; the seeds spread it by up to " + formatFixed(widest, 1) + " points.";
  sentences.push_back(sentence);
  if (trend.size() > 1)
    sentences.push_back(
        trend.back().second > trend.front().second
            ? "This agrees with the paper's observation (Sec. 5, Table 1) that degeneracies "
              "become more likely in higher dimensions (k = " +
                  k + ")."
            : "This differs from the paper's observation (Sec. 5) that degeneracies become "
              "more likely in higher dimensions (k = " +
                  k + ").");
}

/// Series `s` (one k and varying settings): its rows, curves and sentences.
void degeneracySeries(const CsvTable& t, const Group& g, std::size_t s,
                      const std::vector<std::string>& vary, DegeneracyPlot& plot,
                      std::vector<std::string>& sentences) {
  static const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};
  const std::string k = g.key[0];
  const std::string label =
      "k = " + k + (vary.empty() ? "" : ", " + settingsLabel(t, g.rows[0], vary));
  // The statistics per n, in increasing n.
  std::vector<std::vector<double>> means, points;
  std::vector<std::pair<int, double>> trend;
  std::vector<std::string> nKey = {"n"};
  std::vector<Group> byN = groupBy(t, nKey, g.rows);
  std::sort(byN.begin(), byN.end(), [](const Group& x, const Group& y) {
    return std::stoi(x.key[0]) < std::stoi(y.key[0]);
  });
  double widest = 0;
  for (const Group& cell : byN) {
    const Stats st = degeneracyAtN(t, g, cell, vary, plot, means, points);
    trend.emplace_back(std::stoi(cell.key[0]), st.mean);
    widest = std::max(widest, st.max - st.min);
  }
  if (k == "2" && plot.sphereMean.empty())
    for (const auto& [n, mean] : trend) plot.sphereMean[n] = mean;
  // The curves: means with min-max bars, and every run.
  const std::string name = "s" + std::to_string(s);
  plot.gp.data(name + "mean", means);
  plot.gp.data(name + "runs", points);
  const std::string colour = colours[s % 6];
  plot.plots.push_back("$" + name + "mean using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb \"" +
                       colour + "\" title \"" + label + ": mean, min-max\"");
  plot.plots.push_back("$" + name + "runs using ($1+0.08):2 with points pt 6 ps 0.6 lc rgb \"" +
                       colour + "\" title \"" + label + ": runs\"");
  if (!trend.empty()) degeneracySentences(label, k, trend, widest, sentences);
}

/// The paper's Table 1 (surfaces, k = 2, freeform inputs) at its dimensions, for reference:
/// points in the figure and, beside our first k = 2 series, a sentence.
void degeneracyPaper(const std::vector<PaperRow>& paper, DegeneracyPlot& plot,
                     std::vector<std::string>& sentences) {
  std::vector<std::vector<double>> paperPoints;
  std::map<int, std::vector<double>> paperByN;
  for (const PaperRow& p : paper) {
    paperPoints.push_back({p.n + 0.0, p.share});
    paperByN[p.n].push_back(p.share);
  }
  plot.gp.data("paper", paperPoints);
  plot.plots.push_back(
      "$paper with points pt 2 ps 1.5 lw 2 lc rgb \"black\" title \"paper, Table 1 "
      "(k = 2, freeform inputs)\"");
  if (plot.sphereMean.empty()) return;
  std::vector<std::string> ours, theirs;
  for (const auto& [n, shares] : paperByN) {
    const Stats p = summarize(shares);
    theirs.push_back(p.count > 1 ? formatFixed(p.min, 1) + "-" + formatFixed(p.max, 1) +
                                       "% at n = " + std::to_string(n)
                                 : percent(p.mean) + " at n = " + std::to_string(n));
    const auto it = plot.sphereMean.find(n);
    ours.push_back(it != plot.sphereMean.end() ? percent(it->second) : std::string("not run"));
  }
  sentences.push_back("The paper's Table 1 (surfaces from freeform inputs) has " +
                      join(theirs, ", ") + "; our rotated spheres give " + join(ours, ", ") +
                      " there.");
}

Artefact figDegeneracyVsN(const std::string& id, const CsvTable& t,
                          const std::vector<PaperRow>& paper) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "cells.normal", "cells.abnormal"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Abnormal share against the ambient dimension n";
  // One series per k and varying setting.
  const std::vector<std::string> vary = without(varyingColumns(t, kSettingColumns), {"depth"});
  std::vector<std::string> seriesKeys = {"k"};
  seriesKeys.insert(seriesKeys.end(), vary.begin(), vary.end());

  // The data table's header and the script's settings.
  DegeneracyPlot plot{Table{}, GnuplotScript(id), {}, 100, 0, {}};
  plot.data.id = id;
  plot.data.caption =
      "Abnormal share (% of classified cells) per n: mean, standard deviation, "
      "minimum and maximum over the seeds.";
  plot.data.columns = {"k", "n", "depth", "runs", "mean %", "sd", "min %", "max %"};
  plot.data.align = "rrrrrrrr";
  if (!vary.empty()) {
    plot.data.columns.insert(plot.data.columns.begin() + 1, "settings");
    plot.data.align.insert(1, "l");
  }
  for (const char* line :
       {"set xlabel \"ambient dimension n\"", "set ylabel \"abnormal cells (% of classified)\"",
        "set key top left", "set grid", "set xtics 1", "set yrange [0:*]"})
    plot.gp.command(line);

  // Every series, then the paper's points.
  const std::vector<Group> series = groupBy(t, seriesKeys, okRows(t));
  for (std::size_t s = 0; s < series.size(); ++s)
    degeneracySeries(t, series[s], s, vary, plot, a.sentences);
  if (!plot.plots.empty()) {
    degeneracyPaper(paper, plot, a.sentences);
    plot.gp.command("set xrange [" + formatFixed(plot.nMin - 0.5, 1) + ":" +
                    formatFixed(plot.nMax + 0.5, 1) + "]");
    plot.gp.command("plot " + join(plot.plots, ", \\\n       "));
    a.gnuplot = plot.gp.text();
    // For the conclusion: the trend per k.
    for (const std::string& sentence : a.sentences)
      if (sentence.starts_with("For "))
        a.conclusion.push_back(prefixed("Degeneracy against n", sentence));
  } else {
    a.sentences.push_back("No run succeeded, so there is no curve.");
  }
  a.tables.push_back(std::move(plot.data));
  return a;
}

// --- tab-ablation-*: one strategy family compared ----------------------------------------------

/// Per variant, per problem (and other setting): mean visited, mean total time, largest
/// residual, mean solution cells.
using AblationMeasures =
    std::map<std::string, std::map<std::vector<std::string>, std::array<double, 4>>>;

/// The variants of an ablation in order of appearance, with what each measured.
struct AblationData {
  std::vector<std::string> variants;
  AblationMeasures measured;
};

/// The ablation table's header.
Table ablationTable(const std::string& id, const std::string& family, bool scalar,
                    const std::vector<std::string>& other) {
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
  return table;
}

/// The table row of variant `v` of one problem group (`rows`); records its measures.
std::vector<std::string> ablationRow(const CsvTable& t, const std::vector<std::string>& other,
                                     const Group& g, const std::string& v,
                                     const std::vector<std::size_t>& rows, AblationData& data) {
  const std::size_t r0 = rows.front();
  std::vector<std::string> row = {t.cell(r0, "problem"), t.cell(r0, "n"), t.cell(r0, "k")};
  for (const std::string& c : other) row.push_back(t.cell(r0, c));
  const double visited = meanOf(t, rows, "cells.visited");
  const double residual = maxOf(t, rows, "accuracy.max_residual");
  const double total = meanOf(t, rows, "timing_s.total");
  const double solution = meanOf(t, rows, "cells.solution");
  data.measured[v][g.key] = {visited, total, residual, solution};
  row.push_back(v);
  row.push_back(formatNumber(std::round(visited)));
  row.push_back(formatNumber(std::round(solution)));
  row.push_back(formatNumber(residual, 2));
  for (std::string_view stage :
       {"timing_s.subdivision", "timing_s.projection", "timing_s.connection"})
    row.push_back(formatNumber(meanOf(t, rows, stage), 2));
  row.push_back(formatNumber(total, 2));
  return row;
}

/// What an ablation shows: each variant against the first, and the largest residuals.
std::vector<std::string> ablationSentences(const AblationData& data) {
  std::vector<std::string> sentences;
  const std::string& base = data.variants.front();
  const auto& baseMeasures = data.measured.at(base);
  // Each variant against the first: cells, time and solution cells.
  for (std::size_t v = 1; v < data.variants.size(); ++v) {
    std::vector<std::pair<double, double>> cells, time;
    int sameSolution = 0, common = 0;
    for (const auto& [key, m] : data.measured.at(data.variants[v])) {
      const auto it = baseMeasures.find(key);
      if (it == baseMeasures.end()) continue;
      ++common;
      cells.emplace_back(m[0], it->second[0]);
      time.emplace_back(m[1], it->second[1]);
      if (m[3] == it->second[3]) ++sameSolution;
    }
    if (!common) continue;
    sentences.push_back("`" + data.variants[v] + "` visits " +
                        formatFixed(geometricMeanRatio(cells), 2) + " times the cells of `" + base +
                        "` and takes " + formatFixed(geometricMeanRatio(time), 2) +
                        " times its total time (geometric means over " + std::to_string(common) +
                        " problem settings); it keeps the same number of solution cells in " +
                        std::to_string(sameSolution) + " of them.");
  }
  // The largest residual of each variant.
  std::vector<std::string> residuals;
  for (const std::string& v : data.variants) {
    double worst = kNaN;
    for (const auto& [key, m] : data.measured.at(v))
      if (std::isfinite(m[2])) worst = std::isfinite(worst) ? std::max(worst, m[2]) : m[2];
    residuals.push_back("`" + v + "` " + formatNumber(worst, 2));
  }
  sentences.push_back("Largest residual over all problems: " + join(residuals, ", ") + ".");
  return sentences;
}

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
  // Group by problem and the other settings that vary.
  std::vector<std::string> other =
      without(varyingColumns(t, kSettingColumns), {"scalar", "precision_bits"});
  std::erase(other, family);
  std::vector<std::string> keys = {"problem"};
  keys.insert(keys.end(), other.begin(), other.end());

  // Per variant: for each problem (and other setting), mean visited, time, residual.
  Table table = ablationTable(id, family, scalar, other);
  AblationData data;
  for (const Group& g : groupBy(t, keys, okRows(t))) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<std::size_t>> byVariant;
    for (std::size_t r : g.rows) {
      if (!byVariant.count(variant(r))) order.push_back(variant(r));
      byVariant[variant(r)].push_back(r);
    }
    for (const std::string& v : order) {
      if (std::find(data.variants.begin(), data.variants.end(), v) == data.variants.end())
        data.variants.push_back(v);
      table.rows.push_back(ablationRow(t, other, g, v, byVariant[v], data));
    }
  }
  a.tables.push_back(std::move(table));

  // What it shows.
  if (data.variants.empty())
    a.sentences.push_back("No run succeeded, so there is nothing to compare.");
  else
    a.sentences = ablationSentences(data);
  if (!data.variants.empty())
    a.conclusion.push_back(prefixed("Ablation of the " + family, a.sentences.front()));
  return a;
}

// --- tab-connection ----------------------------------------------------------------------------

/// A run's topology against the problem's expectation (`expect_components`,
/// `expect_euler_characteristic`).
struct TopologyCheck {
  const CsvTable& t;
  /// The expected `what` (components or euler_characteristic); NaN when not given.
  double expected(std::size_t r, const char* what) const {
    return t.number(r, std::string("expect_") + what);
  }
  /// Whether run `r` succeeded and got `what` as expected.
  bool right(std::size_t r, const char* what) const {
    const double e = expected(r, what);
    return isOk(t, r) && std::isfinite(e) && t.number(r, std::string("mesh.") + what) == e;
  }
  /// Whether the problem of run `r` has an expected topology.
  bool hasExpect(std::size_t r) const {
    return std::isfinite(expected(r, "components")) ||
           std::isfinite(expected(r, "euler_characteristic"));
  }
};

/// One connection's (and other varying settings') totals over the corpus.
struct ConnectionScore {
  std::string label;
  int runs = 0, withExpect = 0, components = 0, euler = 0, both = 0;
  /// Runs with that value expected (the denominators), and runs of problems without any
  /// expectation (not comparable: counted apart, never as wrong).
  int withComponents = 0, withEuler = 0, withBoth = 0, notComparable = 0;
  double boundary = 0, nonmanifold = 0, openEnds = 0;
};

/// The score table's row of group `g`; adds its score to `scores`.
std::vector<std::string> connectionScoreRow(const TopologyCheck& check, const Group& g,
                                            std::vector<ConnectionScore>& scores) {
  const CsvTable& t = check.t;
  ConnectionScore s;
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
    if (!check.hasExpect(r)) {
      ++s.notComparable;
      continue;
    }
    ++s.withExpect;
    // Each value over the runs that expect it: a problem that states only its components is
    // not wrong about its Euler characteristic.
    const bool hasC = std::isfinite(check.expected(r, "components"));
    const bool hasE = std::isfinite(check.expected(r, "euler_characteristic"));
    const bool c = check.right(r, "components"), e = check.right(r, "euler_characteristic");
    s.withComponents += hasC, s.components += hasC && c;
    s.withEuler += hasE, s.euler += hasE && e;
    s.withBoth += hasC && hasE, s.both += hasC && hasE && c && e;
  }
  const Stats chord = summarize(values(t, ok, "accuracy.max_chord_error"));
  const auto share = [&](int count, int of) {
    return of ? std::to_string(count) + "/" + std::to_string(of) + " (" +
                    formatFixed(100.0 * count / of, 0) + "%)"
              : std::string(kDash);
  };
  std::vector<std::string> row = g.key;
  for (const std::string& cell :
       {std::to_string(s.runs), std::to_string(failed), std::to_string(s.notComparable),
        share(s.components, s.withComponents), share(s.euler, s.withEuler),
        share(s.both, s.withBoth), formatNumber(s.openEnds), formatNumber(s.boundary),
        formatNumber(s.nonmanifold), formatNumber(chord.median, 2), formatNumber(chord.max, 2)})
    row.push_back(cell);
  scores.push_back(s);
  return row;
}

/// The score table: one row per connection (and other varying settings).
Table connectionScoreTable(const std::string& id, const TopologyCheck& check,
                           const std::vector<std::string>& keys,
                           std::vector<ConnectionScore>& scores) {
  Table table;
  table.id = id;
  table.caption =
      "Connections over the corpus: runs (failed; not comparable: the problem states no "
      "topology), share of the runs that expect the components, the Euler characteristic "
      "and both that get them right (a failed run counts as wrong), total open ends, "
      "boundary and non-manifold edges, median and largest chord error.";
  table.columns = keys;
  for (std::string c : {"runs", "failed", "not comparable", "components right", "Euler right",
                        "both right", "open ends", "boundary edges", "non-manifold edges",
                        "median chord error", "max chord error"})
    table.columns.push_back(c);
  table.align = std::string(keys.size(), 'l') + "rrrrrrrrrrr";
  for (const Group& g : groupBy(check.t, keys))
    table.rows.push_back(connectionScoreRow(check, g, scores));
  return table;
}

/// A cell of the detail table: components / Euler characteristic of `runs` (the runs of one
/// problem with one connection), with b(oundary) and nm (non-manifold) edges and `*` when wrong.
std::string connectionCell(const TopologyCheck& check, const std::vector<std::size_t>& runs) {
  const CsvTable& t = check.t;
  if (runs.empty()) return std::string(kDash);
  const std::size_t r = runs.front();
  std::string text;
  if (!isOk(t, r)) {
    text = t.cell(r, "status");
  } else {
    text = formatNumber(t.number(r, "mesh.components")) + " / " +
           formatNumber(t.number(r, "mesh.euler_characteristic"));
    const double b = t.number(r, "mesh.boundary_edges"), nm = t.number(r, "mesh.nonmanifold_edges");
    if (b > 0) text += " b" + formatNumber(b);
    if (nm > 0) text += " nm" + formatNumber(nm);
    const bool wrong =
        (std::isfinite(check.expected(r, "components")) && !check.right(r, "components")) ||
        (std::isfinite(check.expected(r, "euler_characteristic")) &&
         !check.right(r, "euler_characteristic"));
    if (check.hasExpect(r) && wrong) text += " *";
  }
  if (runs.size() > 1) {
    int good = 0;
    for (std::size_t x : runs)
      good += check.right(x, "components") && check.right(x, "euler_characteristic");
    text += " (" + std::to_string(good) + "/" + std::to_string(runs.size()) + " right)";
  }
  return text;
}

/// Per problem: components / Euler characteristic of each connection beside the expectation.
Table connectionDetailTable(const std::string& id, const TopologyCheck& check,
                            const std::vector<std::string>& other) {
  const CsvTable& t = check.t;
  // The connections in order of appearance, one column each.
  std::vector<std::string> connections;
  for (std::size_t r = 0; r < t.size(); ++r)
    if (std::find(connections.begin(), connections.end(), t.cell(r, "connection")) ==
        connections.end())
      connections.push_back(t.cell(r, "connection"));
  std::vector<std::string> rowKeys = {"problem"};
  rowKeys.insert(rowKeys.end(), other.begin(), other.end());
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
  // One row per problem (and other varying settings).
  const auto show = [](double v) { return std::isfinite(v) ? formatNumber(v) : std::string("?"); };
  for (const Group& g : groupBy(t, rowKeys)) {
    const std::size_t r0 = g.rows.front();
    std::vector<std::string> row = {g.key[0], t.cell(r0, "n"), t.cell(r0, "k"),
                                    show(check.expected(r0, "components")) + " / " +
                                        show(check.expected(r0, "euler_characteristic"))};
    for (std::size_t i = 1; i < g.key.size(); ++i) row.push_back(g.key[i]);
    for (const std::string& c : connections) {
      std::vector<std::size_t> runs;
      for (std::size_t r : g.rows)
        if (t.cell(r, "connection") == c) runs.push_back(r);
      row.push_back(connectionCell(check, runs));
    }
    detail.rows.push_back(std::move(row));
  }
  return detail;
}

/// What tab-connection shows: right topologies and defects per connection.
std::vector<std::string> connectionSentences(const std::vector<ConnectionScore>& scores) {
  std::vector<std::string> sentences;
  std::vector<std::string> parts;
  for (const ConnectionScore& s : scores)
    if (s.withBoth)
      parts.push_back("`" + s.label + "` " + std::to_string(s.both) + " of " +
                      std::to_string(s.withBoth));
  if (!parts.empty())
    sentences.push_back("Runs with both the components and the Euler characteristic right: " +
                        join(parts, ", ") + ".");
  parts.clear();
  for (const ConnectionScore& s : scores)
    parts.push_back("`" + s.label + "` " + formatNumber(s.boundary) + " boundary and " +
                    formatNumber(s.nonmanifold) + " non-manifold edges, " +
                    formatNumber(s.openEnds) + " open ends");
  if (!parts.empty())
    sentences.push_back("In total " + join(parts, "; ") +
                        ". The paper's connection (Sec. 4) keeps holes in surfaces, which "
                        "shows as boundary edges where the expected surface is closed.");
  return sentences;
}

Artefact tabConnection(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "connection", "expect_components", "expect_euler_characteristic",
                     "mesh.components", "mesh.euler_characteristic", "mesh.open_ends",
                     "mesh.boundary_edges", "mesh.nonmanifold_edges", "accuracy.max_chord_error"});
  Artefact a;
  a.id = id;
  a.title = "Connection strategies over the problem corpus";
  // Group by connection and the other settings that vary.
  const std::vector<std::string> other =
      without(varyingColumns(t, kSettingColumns), {"connection"});
  std::vector<std::string> keys = {"connection"};
  keys.insert(keys.end(), other.begin(), other.end());
  // The tables and what they show.
  const TopologyCheck check{t};
  std::vector<ConnectionScore> scores;
  a.tables.push_back(connectionScoreTable(id, check, keys, scores));
  a.tables.push_back(connectionDetailTable(id, check, other));
  a.sentences = connectionSentences(scores);
  if (!a.sentences.empty())
    a.conclusion.push_back(prefixed("Connection strategies", a.sentences.front()));
  return a;
}

// --- fig-convergence ---------------------------------------------------------------------------

/// The reference slopes of fig-convergence: two points each, through the finest point of the
/// first series of their kind.
struct ConvergenceGuides {
  std::vector<std::vector<double>> chord, cells1, cells2;
};

/// fig-convergence's gnuplot script: a 2x2 multiplot, log-log.
GnuplotScript convergenceScript(const std::string& id) {
  GnuplotScript gp(id, 1100, 850);
  gp.command("set multiplot layout 2,2 title \"" + id +
             ": convergence with the cell size h = 2^{-depth}\"");
  gp.command("set logscale xy");
  gp.command("set format y \"10^{%L}\"");
  gp.command("set xlabel \"h (relative cell size)\"");
  gp.command("set grid");
  gp.command("set key bottom right font \",8\"");
  return gp;
}

/// Sets `ref` (when still empty) to a guide of `slope` over the depths `h`, half a decade below
/// the finest point of `y`, so that the guide does not hide the curve.
void convergenceGuide(std::vector<std::vector<double>>& ref, const std::vector<double>& h,
                      const std::vector<double>& y, double slope) {
  if (!ref.empty() || h.size() < 2 || !(y.back() > 0)) return;
  const double h1 = h.back(), h0 = h.front();
  const double y1 = 0.3 * y.back();
  ref = {{h0, y1 * std::pow(h0 / h1, slope)}, {h1, y1}};
}

/// One series (problem and varying settings) of fig-convergence: its table rows, its data
/// block `s<s>` and curves in the four panels, its guides and its sentence.
void convergenceSeries(const CsvTable& t, const Group& g, std::size_t s,
                       const std::vector<std::string>& vary, Table& data, GnuplotScript& gp,
                       std::array<std::vector<std::string>, 4>& panels, ConvergenceGuides& guides,
                       std::vector<std::string>& sentences) {
  static const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                  "#ff7f0e", "#8c564b", "#e377c2", "#7f7f7f"};
  const std::size_t r0 = g.rows.front();
  const std::string label =
      t.cell(r0, "problem") + (vary.empty() ? "" : " " + settingsLabel(t, r0, vary));
  const int k = static_cast<int>(t.number(r0, "k"));
  std::vector<Group> byDepth = groupBy(t, std::vector<std::string>{"depth"}, g.rows);
  std::sort(byDepth.begin(), byDepth.end(), [](const Group& x, const Group& y) {
    return std::stoi(x.key[0]) < std::stoi(y.key[0]);
  });
  // The means per depth, as table rows and data.
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
  // The curves.
  const std::string name = "s" + std::to_string(s);
  gp.data(name, rows);
  const std::string style = " with linespoints pt 7 ps 0.7 lc rgb \"" +
                            std::string(colours[s % 8]) + "\" title \"" + label + "\"";
  for (int p = 0; p < 4; ++p)
    panels[p].push_back("$" + name + " using 1:($" + std::to_string(p + 2) + ">0?$" +
                        std::to_string(p + 2) + ":NaN)" + style);
  // Reference slopes through the finest point of the first series of their kind.
  convergenceGuide(guides.chord, h, chord, 2.0);
  convergenceGuide(k == 1 ? guides.cells1 : guides.cells2, h, cells, -static_cast<double>(k));
  if (h.size() < 2) return;
  // What it shows: the fitted slopes.
  const double chordSlope = logLogSlope(h, chord), cellSlope = logLogSlope(h, cells),
               timeSlope = logLogSlope(h, time);
  const Stats res = summarize(residual);
  sentences.push_back(label + " (k = " + std::to_string(k) + ", depths " + byDepth.front().key[0] +
                      " to " + byDepth.back().key[0] + "): the chord error falls as h^" +
                      formatFixed(chordSlope, 2) +
                      " (expected h^2), the solution cells grow as h^" + formatFixed(cellSlope, 2) +
                      " (expected h^-" + std::to_string(k) + "), the time as h^" +
                      formatFixed(timeSlope, 2) + "; the residual stays between " +
                      formatNumber(res.min, 2) + " and " + formatNumber(res.max, 2) + ".");
}

/// The x range of fig-convergence from the data: the smallest to the largest h of the successful
/// runs, a little beyond (log autoscaling would run on to the next power of ten, e.g. 1).
void convergenceRange(GnuplotScript& gp, const CsvTable& t) {
  const std::vector<std::size_t> ok = okRows(t);
  const Stats depth = summarize(values(t, ok, "depth"));
  if (depth.count == 0) return;
  const double hMin = std::ldexp(1.0, -static_cast<int>(depth.max)),
               hMax = std::ldexp(1.0, -static_cast<int>(depth.min));
  gp.command("set xrange [" + formatNumber(hMin / 1.25, 4) + ":" + formatNumber(hMax * 1.25, 4) +
             "]");
  // A tic at every depth: h = 2^-depth.
  std::vector<std::string> tics;
  for (int d = static_cast<int>(depth.min); d <= static_cast<int>(depth.max); ++d)
    tics.push_back("\"2^{-" + std::to_string(d) + "}\" " + formatNumber(std::ldexp(1.0, -d), 6));
  gp.command("set xtics (" + join(tics, ", ") + ")");
}

/// The conclusion of fig-convergence: the range of the fitted orders of the chord error and of
/// the cell counts over the series with two depths or more.
std::vector<std::string> convergenceConclusion(const CsvTable& t,
                                               const std::vector<Group>& series) {
  std::vector<double> chord, cells1, cells2;
  for (const Group& g : series) {
    std::vector<double> h, e, c;
    for (const Group& d : groupBy(t, std::vector<std::string>{"depth"}, g.rows)) {
      h.push_back(std::ldexp(1.0, -std::stoi(d.key[0])));
      e.push_back(meanOf(t, d.rows, "accuracy.max_chord_error"));
      c.push_back(meanOf(t, d.rows, "cells.solution"));
    }
    if (h.size() < 2) continue;
    chord.push_back(logLogSlope(h, e));
    (t.cell(g.rows.front(), "k") == "1" ? cells1 : cells2).push_back(-logLogSlope(h, c));
  }
  if (chord.empty()) return {};
  const auto range = [](const std::vector<double>& v) {
    const Stats s = summarize(v);
    return formatFixed(s.min, 2) + (s.max - s.min > 0.005 ? " to " + formatFixed(s.max, 2) : "");
  };
  std::string sentence = "Convergence: over " + std::to_string(chord.size()) +
                         " series the chord error falls with order " + range(chord) +
                         " in h (expected 2)";
  if (!cells1.empty())
    sentence += ", the cells of curves grow with order " + range(cells1) + " (expected 1)";
  if (!cells2.empty())
    sentence += ", those of surfaces with order " + range(cells2) + " (expected 2)";
  return {sentence + "."};
}

/// Adds the guides and plots the four panels of fig-convergence.
void convergencePanels(GnuplotScript& gp, std::array<std::vector<std::string>, 4>& panels,
                       const ConvergenceGuides& guides) {
  const std::string refStyle = " with lines dt 2 lw 2 lc rgb \"black\"";
  if (!guides.chord.empty()) {
    gp.data("refchord", guides.chord);
    panels[0].push_back("$refchord" + refStyle + " title \"O(h^2)\"");
  }
  if (!guides.cells1.empty()) {
    gp.data("refcells1", guides.cells1);
    panels[2].push_back("$refcells1" + refStyle + " title \"O(h^{-1})\"");
  }
  if (!guides.cells2.empty()) {
    gp.data("refcells2", guides.cells2);
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
}

Artefact figConvergence(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "accuracy.max_chord_error", "accuracy.max_residual",
                     "cells.solution", "timing_s.total"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Convergence with the depth";
  // One series per problem and varying setting.
  const std::vector<std::string> vary = without(varyingColumns(t, kSettingColumns), {"depth"});
  std::vector<std::string> keys = {"problem"};
  keys.insert(keys.end(), vary.begin(), vary.end());

  // The data table's header.
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
  // Every series, then the panels.
  GnuplotScript gp = convergenceScript(id);
  std::array<std::vector<std::string>, 4> panels;
  ConvergenceGuides guides;
  const std::vector<Group> series = groupBy(t, keys, okRows(t));
  for (std::size_t s = 0; s < series.size(); ++s)
    convergenceSeries(t, series[s], s, vary, data, gp, panels, guides, a.sentences);
  if (series.empty()) {
    a.sentences.push_back("No run succeeded, so there is no curve.");
    a.tables.push_back(std::move(data));
    return a;
  }
  convergenceRange(gp, t);
  convergencePanels(gp, panels, guides);
  a.conclusion = convergenceConclusion(t, series);
  a.gnuplot = gp.text();
  a.tables.push_back(std::move(data));
  return a;
}

// --- fig-cells: a Figure-2-style picture of the solution cells ---------------------------------

/// The first 2-D problem with a successful run that has a cells.csv, at its largest depth.
std::optional<std::size_t> cellsRun(const CsvTable& t, const std::filesystem::path& dir) {
  std::optional<std::size_t> pick;
  for (std::size_t r : okRows(t))
    if (t.cell(r, "n") == "2" &&
        std::filesystem::exists(dir / "runs" / t.cell(r, "run") / "cells.csv") &&
        (!pick || (t.cell(r, "problem") == t.cell(*pick, "problem") &&
                   t.number(r, "depth") > t.number(*pick, "depth"))))
      pick = r;
  return pick;
}

/// Half the cell size per axis, from two cells with different indices on that axis.
std::array<double, 2> cellHalfSizes(const CsvTable& cells) {
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
  return half;
}

/// The height over the width of the cells' bounding box, clamped to 0.3..1.5 (1 without cells).
double cellsAspect(const CsvTable& cells, const std::array<double, 2>& half) {
  double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
  for (std::size_t x = 0; x < cells.size(); ++x)
    for (int j = 0; j < 2; ++j) {
      const double c = cells.number(x, j ? "c1" : "c0");
      lo[j] = std::min(lo[j], c - half[j]);
      hi[j] = std::max(hi[j], c + half[j]);
    }
  return cells.size() ? std::clamp((hi[1] - lo[1]) / (hi[0] - lo[0]), 0.3, 1.5) : 1.0;
}

/// One data block of boxes per cell class, coloured by class; adds their plots.
void plotCellBoxes(GnuplotScript& gp, const CsvTable& cells, const std::array<double, 2>& half,
                   std::vector<std::string>& plots) {
  std::map<std::string, std::vector<std::vector<double>>> byClass;
  for (std::size_t x = 0; x < cells.size(); ++x)
    byClass[cells.cell(x, "class")].push_back(
        {cells.number(x, "c0"), cells.number(x, "c1"), half[0], half[1]});
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
}

/// Plots the run's mesh.ply as a polyline in the first two coordinates; returns the sentence
/// about it ("" without a mesh.ply).
std::string plotPolyline(GnuplotScript& gp, const CsvTable& t, std::size_t r,
                         const std::filesystem::path& run, std::vector<std::string>& plots) {
  const std::filesystem::path ply = run / "mesh.ply";
  if (!std::filesystem::exists(ply)) return "";
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
  return " The polyline has " + std::to_string(mesh.xyz.size()) + " vertices and " +
         t.cell(r, "mesh.components") + " component(s)" +
         (t.hasColumn("expect_components") && !t.cell(r, "expect_components").empty()
              ? " (expected " + t.cell(r, "expect_components") + ")."
              : ".");
}

Artefact figCells(const std::string& id, const CsvTable& t, const std::filesystem::path& dir) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "cells.normal", "cells.abnormal", "mesh.components"});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = "Solution cells of a 2-D problem (cf. the paper's Figures 2 and 3)";
  // The first 2-D problem with a successful run, at its largest depth.
  const std::optional<std::size_t> pick = cellsRun(t, dir);
  if (!pick) {
    a.sentences.push_back("No successful 2-D run with a cells.csv, so there is no picture.");
    return a;
  }
  const std::size_t r = *pick;
  const std::filesystem::path run = dir / "runs" / t.cell(r, "run");
  const CsvTable cells = readCsv(run / "cells.csv");
  requireColumns(cells, {"i0", "i1", "c0", "c1", "class", "p0", "p1"});
  const std::array<double, 2> half = cellHalfSizes(cells);
  // A canvas of the cells' aspect ratio (the plot keeps x and y to scale).
  GnuplotScript gp(id, 1000, static_cast<int>(150 + 850 * cellsAspect(cells, half)));
  gp.command("set size ratio -1");
  gp.command("set title \"" + t.cell(r, "problem") + ", depth " + t.cell(r, "depth") +
             ": solution cells and the polyline\"");
  gp.command("set xlabel \"x_0\"");
  gp.command("set ylabel \"x_1\"");
  gp.command("set key outside bottom center horizontal");
  // The cells, the polyline and the solution points.
  std::vector<std::string> plots;
  plotCellBoxes(gp, cells, half, plots);
  const std::string meshNote = plotPolyline(gp, t, r, run, plots);
  std::vector<std::vector<double>> points;
  for (std::size_t x = 0; x < cells.size(); ++x)
    points.push_back({cells.number(x, "p0"), cells.number(x, "p1")});
  gp.data("points", points);
  plots.push_back("$points with points pt 7 ps 0.5 lc rgb \"#08306b\" title \"solution points\"");
  gp.command("plot " + join(plots, ", \\\n       "));
  a.gnuplot = gp.text();
  // What it shows.
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

/// Per problem the successful run at the largest depth, when it has a mesh.ply.
std::vector<std::size_t> applicationRuns(const CsvTable& t, const std::filesystem::path& dir) {
  std::vector<std::size_t> picks;
  for (const Group& g : groupBy(t, std::vector<std::string>{"problem"}, okRows(t))) {
    std::size_t best = g.rows.front();
    for (std::size_t r : g.rows)
      if (t.number(r, "depth") > t.number(best, "depth")) best = r;
    if (std::filesystem::exists(dir / "runs" / t.cell(best, "run") / "mesh.ply"))
      picks.push_back(best);
  }
  return picks;
}

}  // namespace

std::vector<std::vector<int>> chainSegments(const std::vector<std::vector<int>>& segments) {
  // Which segments meet at each vertex.
  std::map<int, std::vector<std::size_t>> at;
  for (std::size_t s = 0; s < segments.size(); ++s)
    if (segments[s].size() == 2)
      for (int v : segments[s]) at[v].push_back(s);
  std::vector<bool> used(segments.size(), false);
  std::vector<std::vector<int>> lines;
  // Walks from `start` along unused segments until it ends or closes.
  const auto walk = [&](int start) {
    std::vector<int> line = {start};
    for (int v = start;;) {
      const auto next =
          std::find_if(at[v].begin(), at[v].end(), [&](std::size_t s) { return !used[s]; });
      if (next == at[v].end()) break;
      used[*next] = true;
      v = segments[*next][0] == v ? segments[*next][1] : segments[*next][0];
      line.push_back(v);
    }
    if (line.size() > 1) lines.push_back(std::move(line));
  };
  // Open ends and branch points first, then the closed loops.
  for (const auto& [v, touching] : at)
    if (touching.size() != 2)
      while (std::any_of(touching.begin(), touching.end(), [&](std::size_t s) { return !used[s]; }))
        walk(v);
  for (std::size_t s = 0; s < segments.size(); ++s)
    if (!used[s] && segments[s].size() == 2) walk(segments[s][0]);
  return lines;
}

std::vector<std::vector<double>> polylineRows(const std::vector<std::vector<int>>& lines,
                                              const std::vector<std::array<double, 3>>& points) {
  std::vector<std::vector<double>> rows;
  for (const std::vector<int>& line : lines) {
    for (int v : line) rows.push_back({points[v][0], points[v][1], points[v][2]});
    // Two blank lines: a new data set, so that splot draws no line to the next polyline.
    rows.push_back({});
    rows.push_back({});
  }
  return rows;
}

namespace {

/// Where a 3-D point is drawn: unchanged (gnuplot's own orthographic view), or projected
/// through an eye point (x, y: the perspective image, z: minus the distance along the view
/// direction, so that `set view 0,0` shows the perspective picture and pm3d sorts by depth).
struct View {
  bool perspective = false;
  std::array<double, 3> eye{}, right{}, up{}, forward{};

  std::array<double, 3> operator()(const std::array<double, 3>& p) const {
    if (!perspective) return p;
    const std::array<double, 3> d = {p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]};
    const auto dot = [&](const std::array<double, 3>& a) {
      return a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
    };
    const double depth = std::max(dot(forward), 1e-9);
    return {dot(right) / depth, dot(up) / depth, -depth};
  }
};

std::array<double, 3> normalize(std::array<double, 3> a) {
  const double length = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (double& x : a) x = length > 0 ? x / length : 0;
  return a;
}

std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// The perspective view from `eye` towards `target`, world z up.
View perspectiveView(const std::array<double, 3>& eye, const std::array<double, 3>& target) {
  View v;
  v.perspective = true;
  v.eye = eye;
  v.forward = normalize({target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]});
  v.right = normalize(cross(v.forward, {0, 0, 1}));
  if (v.right == std::array<double, 3>{0, 0, 0}) v.right = {1, 0, 0};  // looking straight down
  v.up = cross(v.right, v.forward);
  return v;
}

/// The eye point of the run's problem file (`eye = [x, y, z]`, the sweep silhouette's), if any.
std::optional<std::array<double, 3>> problemEye(const CsvTable& t, std::size_t r) {
  const std::filesystem::path file = t.cell(r, "problem_file");
  std::error_code error;
  if (file.empty() || !std::filesystem::is_regular_file(file, error)) return std::nullopt;
  const toml::table top = parseTomlText(readText(file), file.string());
  const toml::array* eye = top["eye"].as_array();
  if (!eye || eye->size() != 3) return std::nullopt;
  std::array<double, 3> p{};
  for (std::size_t i = 0; i < 3; ++i) {
    const std::optional<double> x = (*eye)[i].value<double>();
    if (!x) return std::nullopt;
    p[i] = *x;
  }
  return p;
}

/// A mesh's vertices through `view`.
std::vector<std::array<double, 3>> viewed(const std::vector<std::array<double, 3>>& xyz,
                                          const View& view) {
  std::vector<std::array<double, 3>> out;
  out.reserve(xyz.size());
  for (const auto& p : xyz) out.push_back(view(p));
  return out;
}

/// A mesh's triangles for `with pm3d` (shaded, lit): each a 2 x 2 grid a b / c c, a blank line
/// inside and two after it.
std::vector<std::vector<double>> trianglePm3d(const PlyMesh& m, const View& view) {
  const std::vector<std::array<double, 3>> p = viewed(m.xyz, view);
  std::vector<std::vector<double>> rows;
  for (const auto& s : m.simplices) {
    if (s.size() != 3) continue;
    const auto row = [&](int v) { return std::vector<double>{p[v][0], p[v][1], p[v][2]}; };
    rows.insert(rows.end(), {row(s[0]), row(s[1]), {}, row(s[2]), row(s[2]), {}, {}});
  }
  return rows;
}

/// The bounding box of points: {min, max} per axis.
std::array<std::array<double, 2>, 3> boundingBox(const std::vector<std::array<double, 3>>& points) {
  std::array<std::array<double, 2>, 3> box;
  for (auto& b : box) b = {HUGE_VAL, -HUGE_VAL};
  for (const auto& p : points)
    for (int j = 0; j < 3; ++j)
      if (std::isfinite(p[j])) box[j] = {std::min(box[j][0], p[j]), std::max(box[j][1], p[j])};
  return box;
}

/// The surface result of another application run over the same input (identical input.ply),
/// e.g. the envelope of the sweep a silhouette run looks at; empty when there is none.
std::filesystem::path sameInputSurface(const std::filesystem::path& run) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::exists(run / "input.ply")) return {};
  const std::string input = readText(run / "input.ply");
  const fs::path results = run.parent_path().parent_path().parent_path();
  std::vector<fs::path> candidates;
  for (const auto& e : fs::directory_iterator(results, error))
    if (e.path().filename().string().starts_with("fig-app-") && fs::is_directory(e.path() / "runs"))
      for (const auto& other : fs::directory_iterator(e.path() / "runs", error))
        if (other.path() != run && fs::exists(other.path() / "mesh.ply") &&
            fs::file_size(other.path() / "input.ply", error) == input.size())
          candidates.push_back(other.path());
  std::sort(candidates.begin(), candidates.end());
  for (const fs::path& c : candidates)
    if (readText(c / "input.ply") == input && readPly(c / "mesh.ply").simplices.size() &&
        readPly(c / "mesh.ply").simplices.front().size() == 3)
      return c;
  return {};
}

/// What a panel of fig-app-* draws: the data blocks' plot clauses, back to front, and the
/// points that set the view box.
struct Panel {
  std::vector<std::string> plots;
  std::vector<std::array<double, 3>> box;  ///< input points (the view box when there are any)
};

/// The input surfaces (input.ply) lightly shaded, and the envelope of a sweep over the same
/// input when the run is a silhouette, in a light blue.
void plotContext(GnuplotScript& gp, const std::filesystem::path& run, std::size_t p,
                 const View& view, Panel& panel) {
  if (std::filesystem::exists(run / "input.ply")) {
    const PlyMesh input = readPly(run / "input.ply");
    gp.data("input" + std::to_string(p), trianglePm3d(input, view));
    panel.plots.push_back("$input" + std::to_string(p) +
                          " with pm3d fs transparent solid 0.35 fc rgb \"#bdbdbd\" notitle");
    panel.plots.push_back(
        "keyentry with boxes fill transparent solid 0.35 lc rgb \"#bdbdbd\" title \"input\"");
    panel.box = input.xyz;
  }
  if (!view.perspective) return;
  const std::filesystem::path envelope = sameInputSurface(run);
  if (envelope.empty()) return;
  gp.data("envelope" + std::to_string(p), trianglePm3d(readPly(envelope / "mesh.ply"), view));
  panel.plots.push_back("$envelope" + std::to_string(p) +
                        " with pm3d fs transparent solid 0.6 fc rgb \"#9ecae1\" notitle");
  panel.plots.push_back(
      "keyentry with boxes fill transparent solid 0.6 lc rgb \"#9ecae1\" title \"envelope (" +
      envelope.filename().string().substr(0, envelope.filename().string().find('.')) + ")\"");
}

/// The convex hull's ruled surface (ruled.ply: the first contact points, then the second): the
/// second contact curve in bold and every few bitangent segments in light lines, as in Fig. 6.
void plotRuled(GnuplotScript& gp, const PlyMesh& mesh, const std::filesystem::path& run,
               std::size_t p, const View& view, Panel& panel) {
  if (!std::filesystem::exists(run / "ruled.ply")) return;
  const PlyMesh ruled = readPly(run / "ruled.ply");
  const std::size_t count = mesh.xyz.size();
  if (ruled.xyz.size() != 2 * count || count == 0) return;
  const std::vector<std::array<double, 3>> points = viewed(ruled.xyz, view);
  std::vector<std::vector<int>> segments, second;
  const std::size_t every = std::max<std::size_t>(1, count / 80);
  for (std::size_t v = 0; v < count; v += every)
    segments.push_back({static_cast<int>(v), static_cast<int>(v + count)});
  for (const auto& s : mesh.simplices)
    if (s.size() == 2)
      second.push_back({s[0] + static_cast<int>(count), s[1] + static_cast<int>(count)});
  gp.data("rulings" + std::to_string(p), polylineRows(segments, points));
  gp.data("second" + std::to_string(p), polylineRows(chainSegments(second), points));
  panel.plots.push_back("$rulings" + std::to_string(p) +
                        " with lines lw 0.8 lc rgb \"#6baed6\" title \"bitangent segments\"");
  panel.plots.push_back("$second" + std::to_string(p) +
                        " with lines lw 3 lc rgb \"#a50f15\" notitle");
}

/// The result: a curve in thick lines (chained into polylines), a surface solid and lit.
void plotResult(GnuplotScript& gp, const PlyMesh& mesh, std::size_t p, bool curve, const View& view,
                Panel& panel) {
  const std::string name = "mesh" + std::to_string(p);
  if (curve) {
    gp.data(name, polylineRows(chainSegments(mesh.simplices), viewed(mesh.xyz, view)));
    panel.plots.push_back("$" + name + " with lines lw 3 lc rgb \"#a50f15\" title \"result\"");
  } else {
    gp.data(name, trianglePm3d(mesh, view));
    panel.plots.push_back("$" + name + " with pm3d fc rgb \"#3a6ea5\" notitle");
    panel.plots.push_back("keyentry with boxes fill solid 1.0 lc rgb \"#3a6ea5\" title \"result\"");
  }
}

/// The axes of an orthographic panel: a box with tics, the view box from the input surfaces
/// (grown by 15% of their diagonal; farther parts of the result, e.g. of an untrimmed
/// bisector, are clipped) or from everything when there is no input.
void orthographicAxes(GnuplotScript& gp, const Panel& panel) {
  gp.command("set view 62, 35, 1.2");
  gp.command("set view equal xyz");
  gp.command("set border 4095 lw 0.5 lc rgb \"#808080\"");
  gp.command("set xtics; set ytics; set ztics");
  gp.command("set xlabel \"x\"; set ylabel \"y\"; set zlabel \"z\"");
  if (panel.box.empty()) {
    gp.command("set autoscale");
    return;
  }
  const auto box = boundingBox(panel.box);
  const double grow =
      0.15 * std::sqrt(std::pow(box[0][1] - box[0][0], 2) + std::pow(box[1][1] - box[1][0], 2) +
                       std::pow(box[2][1] - box[2][0], 2));
  const char* axes[] = {"x", "y", "z"};
  for (int j = 0; j < 3; ++j)
    gp.command(std::string("set ") + axes[j] + "range [" + formatNumber(box[j][0] - grow, 6) + ":" +
               formatNumber(box[j][1] + grow, 6) + "]");
}

/// The axes of a perspective panel: the world axes x, y, z drawn from the data's lowest corner
/// through the eye, labelled with their end values (gnuplot's own axes would be the image's).
void perspectiveAxes(GnuplotScript& gp, const View& view,
                     const std::array<std::array<double, 2>, 3>& box, std::size_t p) {
  gp.command("set view 0, 0, 2.4");
  gp.command("set view equal xy");
  gp.command("unset border; unset xtics; unset ytics; unset ztics");
  gp.command("unset xlabel; unset ylabel; unset zlabel");
  // Fit the picture exactly (autoscaling would extend the ranges to tic values).
  gp.command("set autoscale fix");
  const std::array<double, 3> origin = {box[0][0], box[1][0], box[2][0]};
  std::vector<std::vector<double>> rows;
  gp.command("unset label");
  const char* names[] = {"x", "y", "z"};
  for (int j = 0; j < 3; ++j) {
    std::array<double, 3> end = origin;
    end[j] = box[j][1];
    const auto a = view(origin), b = view(end);
    rows.push_back({a[0], a[1], a[2]});
    rows.push_back({b[0], b[1], b[2]});
    rows.push_back({});
    rows.push_back({});
    gp.command("set label " + std::to_string(j + 1) + " \"" + names[j] + " = " +
               formatNumber(box[j][1], 2) + "\" at " + formatNumber(b[0], 6) + "," +
               formatNumber(b[1], 6) + "," + formatNumber(b[2], 6) + " front");
  }
  gp.data("axes" + std::to_string(p), rows);
}

/// What the mesh of run `r` is: vertices, simplices, topology, residual and time.
std::string applicationSentence(const CsvTable& t, std::size_t r, const PlyMesh& mesh) {
  const bool surface = t.cell(r, "k") != "1";
  return "`" + t.cell(r, "problem") + "` (n = " + t.cell(r, "n") + ", depth " + t.cell(r, "depth") +
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
         formatNumber(t.number(r, "timing_s.total"), 2) + " s.";
}

/// Plots the mesh of run `r` as panel `p` in the manner of the paper's Figures 6-10: the input
/// surfaces lightly shaded, the result solid (thick curves, lit surfaces), in perspective from
/// the problem's eye point when it has one (the silhouette, Fig. 7); returns its sentence.
std::string plotApplicationRun(GnuplotScript& gp, const CsvTable& t, std::size_t r, std::size_t p,
                               const std::filesystem::path& run) {
  const PlyMesh mesh = readPly(run / "mesh.ply");
  const bool curve = t.cell(r, "k") == "1";
  // The view: through the eye point, aimed at the centre of the result.
  View view;
  const std::optional<std::array<double, 3>> eye = problemEye(t, r);
  const auto resultBox = boundingBox(mesh.xyz);
  if (eye && !mesh.xyz.empty())
    view = perspectiveView(
        *eye, {0.5 * (resultBox[0][0] + resultBox[0][1]), 0.5 * (resultBox[1][0] + resultBox[1][1]),
               0.5 * (resultBox[2][0] + resultBox[2][1])});
  // Back to front: the input (and envelope), the rulings, the result.
  Panel panel;
  plotContext(gp, run, p, view, panel);
  plotRuled(gp, mesh, run, p, view, panel);
  plotResult(gp, mesh, p, curve, view, panel);
  gp.command("set title \"" + t.cell(r, "problem") + " (n = " + t.cell(r, "n") + ", depth " +
             t.cell(r, "depth") + (view.perspective ? ", perspective from the eye" : "") +
             ")\" noenhanced");
  if (view.perspective) {
    std::vector<std::array<double, 3>> all = panel.box.empty() ? mesh.xyz : panel.box;
    perspectiveAxes(gp, view, boundingBox(all), p);
    panel.plots.push_back("$axes" + std::to_string(p) +
                          " with lines lw 1 lc rgb \"#404040\" notitle");
  } else {
    gp.command("unset label");
    orthographicAxes(gp, panel);
  }
  gp.command("splot " + join(panel.plots, ", \\\n        "));
  return applicationSentence(t, r, mesh);
}

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
  const std::vector<std::size_t> picks = applicationRuns(t, dir);
  if (picks.empty()) {
    a.sentences.push_back("No successful run with a mesh.ply, so there is no picture.");
    return a;
  }
  // The canvas: up to two large panels per row; one per row for perspective views, whose
  // pictures are wide and flat.
  const bool perspective = std::any_of(picks.begin(), picks.end(),
                                       [&](std::size_t r) { return problemEye(t, r).has_value(); });
  const int columns = perspective ? 1 : static_cast<int>(std::min<std::size_t>(picks.size(), 2));
  const int rowsCount = static_cast<int>((picks.size() + columns - 1) / columns);
  GnuplotScript gp(id, perspective ? 1400 : 800 * columns, (perspective ? 560 : 700) * rowsCount);
  if (picks.size() > 1)
    gp.command("set multiplot layout " + std::to_string(rowsCount) + "," + std::to_string(columns) +
               " title \"" + id + "\" noenhanced");
  gp.command("set xyplane relative 0");
  gp.command("set pm3d depthorder noborder clip z");
  gp.command("set pm3d lighting primary 0.5 specular 0.2");
  gp.command("unset colorbox");
  gp.command("set key top right samplen 2");
  // One panel per run.
  for (std::size_t p = 0; p < picks.size(); ++p) {
    const std::size_t r = picks[p];
    a.shownRuns.push_back(t.cell(r, "run"));
    a.sentences.push_back(plotApplicationRun(gp, t, r, p, dir / "runs" / t.cell(r, "run")));
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

/// What a builder gets: the experiment id and CSV, its results folder `results/<id>/`, and the
/// directory of the paper's reference figures.
struct BuildInput {
  const std::string& id;
  const CsvTable& csv;
  const std::filesystem::path& dir;
  const std::filesystem::path& reference;
};

/// The builder of one artefact id (or, with `prefix`, of every id that starts with it).
struct Builder {
  std::string_view id;
  bool prefix;
  Artefact (*build)(const BuildInput&);
};

/// Every artefact the report knows, in report order: the one place that maps ids to builders.
/// Ids without a builder get genericTable.
constexpr std::array<Builder, 9> kBuilders = {{
    {"tab1-degeneracy", false,
     [](const BuildInput& in) {
       return tab1Degeneracy(in.id, in.csv, loadPaperTable1(in.reference));
     }},
    {"fig-degeneracy-vs-n", false,
     [](const BuildInput& in) {
       return figDegeneracyVsN(in.id, in.csv, loadPaperTable1(in.reference));
     }},
    {"tab-ablation-bounding", false,
     [](const BuildInput& in) { return tabAblation(in.id, in.csv, "bounding"); }},
    {"tab-ablation-subdivision", false,
     [](const BuildInput& in) { return tabAblation(in.id, in.csv, "subdivision"); }},
    {"tab-ablation-scalar", false,
     [](const BuildInput& in) { return tabAblation(in.id, in.csv, "scalar"); }},
    {"tab-connection", false, [](const BuildInput& in) { return tabConnection(in.id, in.csv); }},
    {"fig-convergence", false, [](const BuildInput& in) { return figConvergence(in.id, in.csv); }},
    {"fig-cells", false, [](const BuildInput& in) { return figCells(in.id, in.csv, in.dir); }},
    {"fig-app-", true, [](const BuildInput& in) { return figApplication(in.id, in.csv, in.dir); }},
}};

/// The ids of kBuilders that name one artefact (not a prefix), in report order.
constexpr auto kKnownArtefacts = [] {
  constexpr std::size_t count = static_cast<std::size_t>(std::count_if(
      kBuilders.begin(), kBuilders.end(), [](const Builder& b) { return !b.prefix; }));
  std::array<std::string_view, count> ids{};
  std::size_t i = 0;
  for (const Builder& b : kBuilders)
    if (!b.prefix) ids[i++] = b.id;
  return ids;
}();

/// The builder registered for `id`; nullptr when there is none.
const Builder* builderOf(std::string_view id) {
  for (const Builder& b : kBuilders)
    if (b.prefix ? id.starts_with(b.id) : id == b.id) return &b;
  return nullptr;
}

}  // namespace

std::span<const std::string_view> knownArtefacts() { return kKnownArtefacts; }

#ifndef NDC_SOURCE_DIR
#define NDC_SOURCE_DIR ""
#endif

std::filesystem::path referenceDir(const std::filesystem::path& configs) {
  std::filesystem::path dir = configs;
  if (!dir.has_filename()) dir = dir.parent_path();  // "experiments/configs/"
  const std::filesystem::path sibling = dir.parent_path() / "reference";
  std::error_code error;
  if (std::filesystem::is_directory(sibling, error)) return sibling;
  const std::string source = NDC_SOURCE_DIR;
  if (!source.empty()) return std::filesystem::path(source) / "experiments" / "reference";
  return sibling;
}

Artefact buildArtefact(const std::string& id, const CsvTable& csv, const std::filesystem::path& dir,
                       const std::filesystem::path& reference) {
  const Builder* builder = builderOf(id);
  Artefact a = builder ? builder->build({id, csv, dir, reference}) : genericTable(id, csv);
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

/// The artefact ids in report order: the known ids, then the application figures, then every
/// other id that has a config (`<configs>/<id>.toml`) or a CSV (`results/<id>/<id>.csv`), each
/// group sorted.
std::vector<std::string> artefactIds(const ReportSettings& settings) {
  namespace fs = std::filesystem;
  std::vector<std::string> ids(kKnownArtefacts.begin(), kKnownArtefacts.end());
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
  return ids;
}

/// One artefact's section of results/report.md.
struct Section {
  std::string id, status, body;
  std::size_t runs = 0, failed = 0;
  bool figure = false;
  std::vector<std::string> conclusion;  ///< the artefact's sentences for the conclusion
  std::size_t certified = 0;            ///< runs whose every cell is certified
  std::size_t withCertificate = 0;      ///< runs that attempted the topology certificate
};

/// What writeReport shares between the artefacts.
struct ReportRun {
  const ReportSettings& settings;
  std::filesystem::path reference;  ///< the paper's reference figures
  bool render = false;              ///< gnuplot runs
  ReportOutcome& outcome;
  std::ostream& log;
};

/// Writes `<id>.gp` of an artefact with a chart and renders it; returns its report.md lines.
/// `renderNote` says why the chart was not rendered (empty when it was).
std::string writeGnuplotFiles(const ReportRun& run, const Artefact& a,
                              const std::filesystem::path& dir, std::string& renderNote) {
  const std::string& id = a.id;
  if (a.gnuplot.empty()) return "";
  std::string body;
  writeAtomically(dir / (id + ".gp"), a.gnuplot);
  if (run.render) {
    const std::string problem = renderGnuplot(dir, id);
    if (!problem.empty()) {
      run.outcome.errors.push_back(id + ": " + problem);
      renderNote = "**Not rendered**: " + problem + ".";
    }
  } else {
    renderNote = "*Not rendered (gnuplot is not on PATH)*; script: [" + id + ".gp](" + id + "/" +
                 id + ".gp).";
  }
  if (renderNote.empty() || std::filesystem::exists(dir / (id + ".png")))
    body += "![" + id + "](" + id + "/" + id + ".png)\n\n";
  if (!renderNote.empty()) body += renderNote + "\n\n";
  return body;
}

/// Writes `<id>.md` and `<id>.tex` of a table artefact, and its chart when it has one;
/// returns its report.md body.
std::string writeTableFiles(const ReportRun& run, const Artefact& a,
                            const std::filesystem::path& dir, std::string& renderNote) {
  writeAtomically(dir / (a.id + ".md"), artefactMarkdown(a));
  writeAtomically(dir / (a.id + ".tex"), toLatex(a.tables.front()));
  std::string body;
  for (const Table& t : a.tables) body += t.caption + "\n\n" + toMarkdown(t) + "\n";
  body += writeGnuplotFiles(run, a, dir, renderNote);
  return body + paragraph(a.sentences) + "\n\n";
}

/// Application figures: each shown run rendered by the application's own script
/// (experiments/gnuplot/<application>.gp, `gnuplot -e "dir='RUN'"` writes
/// RUN/<application>.png), when there is one; returns the report.md lines.
std::string applicationRunImages(const ReportRun& run, const Artefact& a,
                                 const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  const std::string& id = a.id;
  fs::path configs = run.settings.configs;
  if (!configs.has_filename()) configs = configs.parent_path();
  const std::string application = id.starts_with("fig-app-") ? id.substr(8) : "";
  const fs::path script = configs.parent_path() / "gnuplot" / (application + ".gp");
  if (!run.render || application.empty() || !fs::exists(script)) return "";
  std::string body;
  std::vector<std::string> failedScripts;
  for (const std::string& shown : a.shownRuns) {
    const fs::path runDir = fs::absolute(dir / "runs" / shown);
    const std::string command = "gnuplot -e \"dir='" + runDir.string() + "'\" " +
                                shellQuote(fs::absolute(script).string()) + " > " +
                                shellQuote((runDir / (application + ".gnuplot.log")).string()) +
                                " 2>&1";
    if (std::system(command.c_str()) == 0 && fs::exists(runDir / (application + ".png")))
      body += "![" + shown + "](" + id + "/runs/" + shown + "/" + application + ".png)\n\n";
    else
      failedScripts.push_back(shown);
  }
  if (!failedScripts.empty())
    body += "The script " + script.string() + " failed on " + join(failedScripts, ", ") +
            " (see `runs/<run>/" + application + ".gnuplot.log`).\n\n";
  return body;
}

/// Writes `<id>.gp` of a figure and renders it; returns its report.md body. `renderNote` says
/// why the figure was not rendered (empty when it was).
std::string writeFigureFiles(const ReportRun& run, const Artefact& a,
                             const std::filesystem::path& dir, std::string& renderNote) {
  // The script, rendered when gnuplot is there.
  std::string body = writeGnuplotFiles(run, a, dir, renderNote);
  // The application's own pictures, what it shows, and the data tables.
  body += applicationRunImages(run, a, dir);
  body += paragraph(a.sentences) + "\n\n";
  for (const Table& t : a.tables)
    if (!t.rows.empty()) body += t.caption + "\n\n" + toMarkdown(t) + "\n";
  return body;
}

/// "; code revision `abc`, quick grid, run DATE" from `provenance.json` of the runner: which
/// code made the results, in which mode, when.
std::string provenanceOrigin(const std::filesystem::path& provenance) {
  std::ifstream in(provenance);
  std::ostringstream read;
  read << in.rdbuf();
  const std::string text = read.str();
  const std::string revision = jsonString(text, {"git_revision", "revision", "commit", "git"});
  const std::string date = jsonString(text, {"date"});
  std::string origin;
  if (!revision.empty()) {
    origin += "; code revision `";
    origin += revision.substr(0, 12);
    origin += '`';
    if (text.find("\"dirty\": true") != std::string::npos) origin += " with uncommitted changes";
  }
  if (text.find("\"quick\": true") != std::string::npos) origin += ", quick grid";
  if (text.find("\"quick\": false") != std::string::npos) origin += ", full grid";
  if (!date.empty()) origin += ", run " + date;
  return origin;
}

/// The "Files: ..." line of an artefact's section: links to its files and their provenance.
std::string filesLine(const Artefact& a, const std::filesystem::path& dir) {
  const std::string& id = a.id;
  std::vector<std::string> files = {"[CSV](" + id + "/" + id + ".csv)"};
  if (!a.figure) {
    files.push_back("[Markdown](" + id + "/" + id + ".md)");
    files.push_back("[LaTeX](" + id + "/" + id + ".tex)");
  }
  if (!a.gnuplot.empty()) {
    files.push_back("[gnuplot](" + id + "/" + id + ".gp)");
    if (std::filesystem::exists(dir / (id + ".pdf")))
      files.push_back("[PDF](" + id + "/" + id + ".pdf)");
  }
  const std::filesystem::path provenance = dir / "provenance.json";
  std::string origin;
  if (std::filesystem::exists(provenance)) {
    files.push_back("[provenance](" + id + "/provenance.json)");
    origin = provenanceOrigin(provenance);
  }
  return "\nFiles: " + join(files, ", ") + origin + ".\n";
}

/// The section of an expected artefact without a CSV.
Section missingSection(const ReportRun& run, const std::string& id,
                       const std::filesystem::path& csvPath) {
  const std::filesystem::path config = run.settings.configs / (id + ".toml");
  Section section;
  section.id = id;
  section.figure = id.starts_with("fig");
  run.outcome.missing.push_back(id);
  section.status = "missing";
  section.body =
      "**Missing**: there is no `" + csvPath.string() + "`" +
      (std::filesystem::exists(config) ? " (run `ndcontour experiment " + config.string() + "`)."
                                       : " and no config `" + config.string() + "`.") +
      "\n";
  run.log << "report: " << id << ": missing (" << csvPath.string() << ")\n";
  return section;
}

/// Counts the successful runs that attempted the topology certificate (some cells certified or
/// not) and those that certified every cell.
void countCertified(const CsvTable& csv, Section& section) {
  if (!csv.hasColumn("topology.certified_cells") || !csv.hasColumn("topology.uncertified_cells"))
    return;
  for (std::size_t r : okRows(csv)) {
    const double certified = csv.number(r, "topology.certified_cells"),
                 uncertified = csv.number(r, "topology.uncertified_cells");
    if (!(certified + uncertified > 0)) continue;
    ++section.withCertificate;
    section.certified += uncertified == 0;
  }
}

/// Builds one artefact from its CSV and writes its files; returns its section. Throws what
/// reading, building or writing throws.
Section artefactSection(const ReportRun& run, const std::string& id,
                        const std::filesystem::path& dir, const std::filesystem::path& csvPath) {
  // Build the artefact.
  const CsvTable csv = readCsv(csvPath);
  const Artefact a = buildArtefact(id, csv, dir, run.reference);
  Section section;
  section.id = id;
  section.runs = a.runs;
  section.failed = a.failures.size();
  section.conclusion = a.conclusion;
  countCertified(csv, section);
  run.outcome.failedRuns += a.failures.size();
  // Its files: the sentences for the paper, then the table or figure.
  writeAtomically(dir / (id + "-summary.tex"), sentencesLatex(a.sentences));
  std::string renderNote;
  std::string body = a.figure ? writeFigureFiles(run, a, dir, renderNote)
                              : writeTableFiles(run, a, dir, renderNote);
  // The runs, failures and file links.
  body += runsLine(a);
  if (!a.failures.empty()) {
    body += " Failed runs:\n\n";
    for (const std::string& f : a.failures) body += "- " + f + "\n";
  }
  body += ndc::view::writeRunViewers(dir / "runs", id + "/runs/");  // a page per run with a mesh
  body += "\n" + filesLine(a, dir);
  section.status = !renderNote.empty() && run.render ? "not rendered"
                   : a.failures.empty()              ? "ok"
                                        : std::to_string(a.failures.size()) + " failed";
  section.figure = a.figure;
  section.body = "*" + a.title + ".*\n\n" + body;
  run.outcome.written.push_back(id);
  run.log << "report: " << id << ": " << a.runs << " runs, " << a.failures.size() << " failed\n";
  return section;
}

/// The section of artefact `id`: missing, written, or an error (previous outputs kept).
Section reportSection(const ReportRun& run, const std::string& id) {
  const std::filesystem::path dir = run.settings.results / id;
  const std::filesystem::path csvPath = dir / (id + ".csv");
  if (!std::filesystem::exists(csvPath)) return missingSection(run, id, csvPath);
  try {
    return artefactSection(run, id, dir, csvPath);
  } catch (const std::exception& e) {  // InputError, or a value the builder cannot use
    run.outcome.errors.push_back(e.what());
    Section section;
    section.id = id;
    section.figure = id.starts_with("fig");
    section.status = "error";
    section.body = "**Could not be made**: " + std::string(e.what()) +
                   " (previous outputs, if any, are left as they were).\n";
    run.log << "report: " << id << ": error: " << e.what() << "\n";
    return section;
  }
}

/// results/report.md: overview, notes, then every artefact.
std::string reportMarkdown(const ReportSettings& settings, const std::vector<Section>& sections,
                           const ReportOutcome& outcome) {
  // The introduction.
  std::string report = "# ndcontour: experiments report\n\n";
  report +=
      "Generated by `ndcontour report` from `" + settings.results.string() + "/<id>/<id>.csv`, " +
      (settings.quick ? "**quick mode** (`ndcontour experiment --quick`: reduced depths "
                        "and seeds; `scripts/run.sh --full` runs the full grids)"
                      : "full mode") +
      ". Every artefact has one id, the same in its config (`experiments/configs/<id>.toml`), "
      "its result files (`results/<id>/`) and the paper (`paper/ndcontour.tex`).\n\n";
  // The overview table.
  Table overview;
  overview.columns = {"artefact", "kind", "runs", "failed", "status"};
  overview.align = "llrrl";
  for (const Section& s : sections) {
    const bool none = s.status == "missing" || s.status == "error";
    overview.rows.push_back({"[" + s.id + "](#" + s.id + ")", s.figure ? "figure" : "table",
                             none ? std::string(kDash) : std::to_string(s.runs),
                             none ? std::string(kDash) : std::to_string(s.failed), s.status});
  }
  report += toMarkdown(overview) + "\n";
  // Missing experiments, failed runs, notes and errors.
  if (!outcome.missing.empty())
    report += "Missing experiments: " + join(outcome.missing, ", ") + ".\n\n";
  report += "Failed runs over all experiments: " + std::to_string(outcome.failedRuns) +
            " (each is named in its section).\n\n";
  for (const std::string& note : outcome.notes) report += "Note: " + note + "\n\n";
  for (const std::string& e : outcome.errors) report += "Error: " + e + "\n\n";
  // Every artefact.
  for (const Section& s : sections) report += "## " + s.id + "\n\n" + s.body + "\n";
  return report;
}

/// The conclusion computed from the results: runs, failed and certified runs over all
/// experiments, the application figures, then each artefact's conclusion in report order.
std::vector<std::string> conclusionSentences(const std::vector<Section>& sections) {
  std::size_t runs = 0, failed = 0, certified = 0, withCertificate = 0, applications = 0,
              artefacts = 0;
  for (const Section& s : sections) {
    if (s.status == "missing" || s.status == "error") continue;
    ++artefacts;
    runs += s.runs, failed += s.failed;
    certified += s.certified, withCertificate += s.withCertificate;
    applications += s.id.starts_with("fig-app-") ? s.runs - s.failed : 0;
  }
  std::vector<std::string> sentences = {
      "We ran " + std::to_string(runs) + (runs == 1 ? " run in " : " runs in ") +
      std::to_string(artefacts) + (artefacts == 1 ? " experiment" : " experiments") +
      ", of which " + std::to_string(failed) + " failed" +
      (withCertificate
           ? "; " + std::to_string(certified) + " of " + std::to_string(withCertificate) +
                 " runs that attempted the topology certificate certified every "
                 "cell"
           : "") +
      (applications ? "; " + std::to_string(applications) +
                          " application runs contour the paper's Sec. 3 problems"
                    : "") +
      "."};
  for (const Section& s : sections)
    sentences.insert(sentences.end(), s.conclusion.begin(), s.conclusion.end());
  return sentences;
}

/// results/applications.tex: one figure per application for the paper (it cannot know the
/// application ids in advance); paper/ndcontour.tex defines \artefactfigure.
std::string applicationsLatex(const ReportOutcome& outcome) {
  std::string applications =
      "% Generated by `ndcontour report`: one figure per fig-app-* artefact; do not edit.\n";
  for (const std::string& id : outcome.written)
    if (id.starts_with("fig-app-"))
      applications += "\\artefactfigure{" + id + "}{" + latexEscape(id.substr(8)) + " (" +
                      latexEscape(id) + "): the mesh in R\\textsuperscript{3}.}\n";
  return applications;
}

}  // namespace

ReportOutcome writeReport(const ReportSettings& settings, std::ostream& log) {
  if (!std::filesystem::is_directory(settings.results))
    throw InputError(settings.results.string() +
                     ": no such directory (run `ndcontour experiment` first)");
  ReportOutcome outcome;
  // Whether gnuplot renders the figures.
  ReportRun run{settings,
                settings.reference.empty() ? referenceDir(settings.configs) : settings.reference,
                settings.render && gnuplotAvailable(), outcome, log};
  if (settings.render && !run.render)
    outcome.notes.push_back(
        "gnuplot is not on PATH: the figure scripts (`<id>.gp`) are written "
        "but not rendered.");

  // Every artefact, then the report and the applications' figure list.
  std::vector<Section> sections;
  for (const std::string& id : artefactIds(settings)) sections.push_back(reportSection(run, id));
  const std::vector<std::string> conclusion = conclusionSentences(sections);
  writeAtomically(settings.results / "report.md", reportMarkdown(settings, sections, outcome) +
                                                      "## Conclusion\n\n" + paragraph(conclusion) +
                                                      "\n");
  writeAtomically(settings.results / "conclusion.tex",
                  "% Generated by `ndcontour report` from the results: do not edit.\n" +
                      sentencesLatex(conclusion));
  writeAtomically(settings.results / "applications.tex", applicationsLatex(outcome));
  log << "report: wrote " << (settings.results / "report.md").string() << "\n";

  // The exit status.
  bool badInput = false;
  for (const Section& s : sections) badInput |= s.status == "error";
  outcome.status = badInput ? 2
                   : (!outcome.missing.empty() || outcome.failedRuns || !outcome.errors.empty())
                       ? 1
                       : 0;
  return outcome;
}

}  // namespace ndc::report
