// The one CSV reader of the experiments: see csv.hpp.
#include "experiments/runner/csv.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "framework/util/errors.hpp"

namespace ndc {

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot read the file: " + failureReason());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

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
  if (text.empty() || text == "nan" || text == "NaN" || text == "null")
    return std::numeric_limits<double>::quiet_NaN();
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

namespace {

/// A reader of CSV text, one record at a time.
class CsvReader {
 public:
  CsvReader(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  /// Whether text is left.
  bool more() const { return i_ < text_.size(); }
  /// The line the next record starts on.
  std::size_t line() const { return line_; }

  /// One record: fields separated by commas up to an unquoted line end. `quoted`: whether a
  /// field was in quotes (a record of one empty unquoted field is a blank line).
  std::vector<std::string> record(bool& quoted) {
    std::vector<std::string> fields;
    quoted = false;
    while (true) {
      // A field, quoted or not.
      if (more() && text_[i_] == '"') {
        quoted = true;
        fields.push_back(quotedField());
      } else {
        fields.push_back(plainField());
      }
      // A comma continues the record; a line end (LF or CRLF) or the end of the text ends it.
      if (more() && text_[i_] == ',') {
        ++i_;
        continue;
      }
      if (more() && text_[i_] == '\r') ++i_;
      if (more() && text_[i_] == '\n') ++i_;
      ++line_;
      return fields;
    }
  }

  /// Throws InputError `SOURCE:LINE: message`.
  [[noreturn]] void fail(std::size_t line, const std::string& message) const {
    throw InputError(source_ + ":" + std::to_string(line) + ": " + message);
  }

 private:
  bool atFieldEnd() const {
    return !more() || text_[i_] == ',' || text_[i_] == '\n' || text_[i_] == '\r';
  }

  /// A field in double quotes: a doubled quote is a quote; commas and line breaks are text.
  std::string quotedField() {
    std::string field;
    const std::size_t openLine = line_;
    ++i_;
    while (true) {
      if (!more()) fail(openLine, "unterminated quoted field");
      const char c = text_[i_++];
      if (c == '"') {
        if (more() && text_[i_] == '"') {
          field += '"';
          ++i_;
        } else {
          break;
        }
      } else {
        if (c == '\n') ++line_;
        field += c;
      }
    }
    if (!atFieldEnd()) fail(line_, "text after a closing quote");
    return field;
  }

  /// A field without quotes, up to a comma or a line end.
  std::string plainField() {
    std::string field;
    while (!atFieldEnd()) {
      if (text_[i_] == '"') fail(line_, "quote inside an unquoted field");
      field += text_[i_++];
    }
    return field;
  }

  std::string_view text_;
  const std::string& source_;
  std::size_t i_ = 0, line_ = 1;
};

/// Throws unless every column name is non-empty and unique.
void checkHeader(const CsvReader& reader, std::size_t line,
                 const std::vector<std::string>& header) {
  std::set<std::string> seen;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (header[c].empty())
      reader.fail(line, "empty column name (column " + std::to_string(c + 1) + ")");
    if (!seen.insert(header[c]).second) reader.fail(line, "duplicate column '" + header[c] + "'");
  }
}

}  // namespace

CsvTable parseCsv(std::string_view text, const std::string& source) {
  CsvTable table;
  table.source = source;
  CsvReader reader(text, source);
  bool haveHeader = false;
  while (reader.more()) {
    // One record; blank lines are skipped.
    const std::size_t recordLine = reader.line();
    bool quoted = false;
    std::vector<std::string> record = reader.record(quoted);
    if (record.size() == 1 && record[0].empty() && !quoted) continue;
    // The header, then rows of as many fields.
    if (!haveHeader) {
      checkHeader(reader, recordLine, record);
      table.header = std::move(record);
      haveHeader = true;
    } else {
      if (record.size() != table.header.size())
        reader.fail(recordLine, "row has " + std::to_string(record.size()) +
                                    " fields, the header " + std::to_string(table.header.size()));
      table.rows.push_back(std::move(record));
    }
  }
  if (!haveHeader) reader.fail(1, "no header line");
  return table;
}

CsvTable readCsv(const std::filesystem::path& file) {
  return parseCsv(readText(file), file.string());
}

}  // namespace ndc
