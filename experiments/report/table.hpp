/// \file table.hpp
/// The report's tables: numbers formatted for them, and a table as GitHub Markdown and as a
/// LaTeX `table` float.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ndc::report {

/// What a missing number prints as (an en dash; `--` in LaTeX).
inline constexpr std::string_view kDash = "\u2013";

/// A number with `significant` significant digits, in fixed notation for 1e-3 <= |v| < 1e6
/// and scientific (`1.2e-14`) otherwise; integers print without a decimal point; NaN is "–"
/// (an en dash, "--" in LaTeX).
std::string formatNumber(double value, int significant = 3);
/// `value` with `decimals` digits after the point; NaN is "–".
std::string formatFixed(double value, int decimals);

/// A generated table: its id (the artefact id), caption, column titles, alignment and cells.
struct Table {
  std::string id;                              ///< artefact id, e.g. `tab1-degeneracy`
  std::string caption;                         ///< one sentence, plain text
  std::vector<std::string> columns;            ///< column titles, plain text
  std::string align;                           ///< one of `l`, `r`, `c` per column
  std::vector<std::vector<std::string>> rows;  ///< cells, plain text
};

/// The table in GitHub Markdown: a header row, an alignment row (`---`, `--:`, `:-:`) and one
/// line per row; `|` in cells is escaped. No caption (callers write it above).
std::string toMarkdown(const Table& table);

/// The table as a LaTeX `table` float with `booktabs` rules, the caption, `\label{<id>}`, and
/// special characters escaped; "–" (NaN) becomes `--`. Needs the booktabs package.
std::string toLatex(const Table& table);

/// Escapes LaTeX special characters (`\ & % $ # _ { } ~ ^`) in plain text.
std::string latexEscape(std::string_view text);

}  // namespace ndc::report
