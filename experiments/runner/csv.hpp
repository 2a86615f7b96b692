/// \file csv.hpp
/// The one CSV reader of the experiments, beside the runner that writes their CSV files: the
/// report reads the combined CSV of each experiment (`results/<id>/<id>.csv`) and a run's
/// `cells.csv` with it, the viewer (experiments/view/) a run's `uncertified.csv`.
#pragma once

#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ndc {

/// A CSV file held as text cells, addressed by column name. Malformed input and missing
/// columns throw ndc::InputError with a one-line message that names the file.
class CsvTable {
 public:
  /// Where the table came from (used in error messages).
  std::string source;
  /// Column names, from the first line.
  std::vector<std::string> header;
  /// Data rows; every row has header.size() cells.
  std::vector<std::vector<std::string>> rows;

  /// Number of data rows.
  std::size_t size() const { return rows.size(); }
  /// Whether a column of that name exists.
  bool hasColumn(std::string_view name) const;
  /// Index of a column; throws InputError `SOURCE: missing column 'NAME'` when absent.
  std::size_t column(std::string_view name) const;
  /// The text of a cell.
  const std::string& cell(std::size_t row, std::string_view name) const;
  /// A cell as a number: NaN when the cell is empty (or "nan"); throws InputError when it
  /// is neither empty nor a number.
  double number(std::size_t row, std::string_view name) const;
  /// Throws InputError naming the first of `names` that is not a column.
  void require(std::span<const std::string_view> names) const;
};

/// Parses CSV text (RFC 4180: fields separated by commas, optionally in double quotes, a
/// doubled quote inside quotes is a quote, quoted fields may hold commas and line breaks; LF
/// or CRLF line ends; empty fields allowed; a final line break is optional). The first line is
/// the header. Throws InputError (`SOURCE:LINE: message`) for an unterminated quote, text
/// after a closing quote, a row with a different number of fields, an empty or duplicate
/// column name, or no header.
CsvTable parseCsv(std::string_view text, const std::string& source);

/// Reads and parses a CSV file; throws InputError when it cannot be read or parsed.
CsvTable readCsv(const std::filesystem::path& file);

/// The bytes of a file; throws InputError `FILE: cannot read the file` when it cannot be read.
std::string readText(const std::filesystem::path& file);

}  // namespace ndc
