/// \file report.hpp
/// Tables and figures from experiment results (issue 6): reads the combined CSV that
/// `ndcontour experiment` writes for each experiment (`results/<id>/<id>.csv`, one row per run),
/// aggregates it, and writes each artefact under the same id as its config: tables as Markdown
/// (`<id>.md`) and LaTeX (`<id>.tex`), figures as gnuplot scripts (`<id>.gp`) rendered to
/// `<id>.png` and `<id>.pdf`, the sentences computed from the data as `<id>-summary.tex`, one
/// `results/applications.tex` listing the application figures, and one `results/report.md`
/// with every artefact. The paper (`paper/ndcontour.tex`) includes only these files.
///
/// The numbers of the paper (Seong, Elber and Kim 2005) that the artefacts set beside ours are
/// data, not code: they are read at run time from the reference directory, by default the
/// sibling `reference/` of the configs directory (`experiments/reference/` for the default
/// `experiments/configs`; see referenceDir). `table1.toml` holds the paper's Table 1 (used by
/// `tab1-degeneracy` and `fig-degeneracy-vs-n`). A missing or malformed reference file makes
/// that artefact fail with a one-line ndc::InputError naming the file.
///
/// Each known artefact id has one builder, registered in one table in report.cpp (kBuilders).
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "framework/core/io.hpp"

namespace ndc::report {

// --- CSV ---------------------------------------------------------------------------------------

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

// --- Aggregation -------------------------------------------------------------------------------

/// Summary statistics of a sample; NaN values are ignored (count says how many were used).
struct Stats {
  std::size_t count = 0;                                     ///< finite values used
  double mean = std::numeric_limits<double>::quiet_NaN();    ///< arithmetic mean
  double stddev = std::numeric_limits<double>::quiet_NaN();  ///< sample standard deviation (n-1); 0
                                                             ///< for one value
  double min = std::numeric_limits<double>::quiet_NaN();     ///< smallest value
  double max = std::numeric_limits<double>::quiet_NaN();     ///< largest value
  double median =
      std::numeric_limits<double>::quiet_NaN();  ///< middle value (mean of the two middle ones)
};

/// Statistics of the finite values of `values`.
Stats summarize(std::span<const double> values);

/// Rows sharing the same values in the grouping columns, in order of first appearance.
struct Group {
  std::vector<std::string> key;   ///< the grouping columns' values
  std::vector<std::size_t> rows;  ///< indices into the table's rows
};

/// Groups `rows` (all rows when empty) by the values of `columns`, keeping the order in which
/// each key first appears. Throws InputError for a missing column.
std::vector<Group> groupBy(const CsvTable& table, std::span<const std::string> columns,
                           std::span<const std::size_t> rows = {});

/// The values of a numeric column at `rows` (NaN for empty cells).
std::vector<double> values(const CsvTable& table, std::span<const std::size_t> rows,
                           std::string_view column);

/// The columns among `candidates` that exist and take more than one value over the table.
std::vector<std::string> varyingColumns(const CsvTable& table,
                                        std::span<const std::string> candidates);

/// Least-squares slope of log(y) against log(x) over the pairs where both are positive and
/// finite; NaN with fewer than two such pairs.
double logLogSlope(std::span<const double> x, std::span<const double> y);

// --- Formatting --------------------------------------------------------------------------------

/// A number with `significant` significant digits, in fixed notation for 1e-3 <= |v| < 1e6
/// and scientific (`1.2e-14`) otherwise; integers print without a decimal point; NaN is "–"
/// (an en dash, "--" in LaTeX).
std::string formatNumber(double value, int significant = 3);
/// `value` with `decimals` digits after the point; NaN is "–".
std::string formatFixed(double value, int decimals);

// --- Tables ------------------------------------------------------------------------------------

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

// --- Figures -----------------------------------------------------------------------------------

/// A gnuplot script under construction: inline data blocks and plot commands. The finished
/// script renders the same commands twice, to `OUT.png` (pngcairo) and `OUT.pdf` (pdfcairo),
/// where `OUT` is the gnuplot variable `out` (default: the artefact id), so that the caller
/// can render to temporary names and rename them once gnuplot succeeded.
class GnuplotScript {
 public:
  /// A script for artefact `id` whose PNG is `width` x `height` pixels.
  explicit GnuplotScript(std::string id, int width = 1000, int height = 700);
  /// Adds a data block `$name` of rows of numbers; an empty row writes a blank line
  /// (a break between curves or polygons). NaN is written as `NaN`.
  void data(const std::string& name, const std::vector<std::vector<double>>& rows);
  /// Adds one line of gnuplot commands (run for each output format).
  void command(const std::string& line);
  /// The complete script text.
  std::string text() const;

 private:
  std::string id_;
  int width_, height_;
  std::string data_;
  std::string commands_;
};

/// Segments (pairs of vertex indices; other simplices are skipped) chained into polylines of
/// vertex indices: open chains from their ends (and branch points) first, then closed loops,
/// which repeat their first vertex at the end.
std::vector<std::vector<int>> chainSegments(const std::vector<std::vector<int>>& segments);

/// Rows for GnuplotScript::data of polylines (vertex indices into `points`) for
/// `splot ... with lines`: two blank lines after each polyline, so that each is its own data
/// set (one blank line makes splot join blocks of equal length as a grid, drawing zigzags and
/// chords between separate polylines).
std::vector<std::vector<double>> polylineRows(const std::vector<std::vector<int>>& lines,
                                              const std::vector<std::array<double, 3>>& points);

/// Whether `gnuplot` is on PATH.
bool gnuplotAvailable();

/// Runs gnuplot on `ID.gp` in `dir` with the output base `ID.tmp` (log in `ID.gnuplot.log`)
/// and, on success, renames `ID.tmp.png` and `ID.tmp.pdf` to `ID.png` and `ID.pdf`, where ID is
/// `id`. Returns an empty string on success, otherwise the reason (the last line of the log).
std::string renderGnuplot(const std::filesystem::path& dir, const std::string& id);

// --- Reading run outputs -----------------------------------------------------------------------

/// The PLY reader lives in core beside the writer (framework/core/io.hpp); these names keep
/// `ndc::report::PlyMesh` and `ndc::report::readPly` working.
using ndc::PlyMesh;
using ndc::readPly;

// --- The report --------------------------------------------------------------------------------

/// One artefact made from one experiment's CSV.
struct Artefact {
  std::string id;                      ///< the experiment and artefact id
  bool figure = false;                 ///< `fig-*` ids are figures, others tables
  std::string title;                   ///< a heading for the report
  std::vector<Table> tables;           ///< tables[0] is `<id>.md`/`<id>.tex`; figures: data tables
  std::string gnuplot;                 ///< figures: the script `<id>.gp`
  std::vector<std::string> sentences;  ///< what it shows, computed from the data
  std::size_t runs = 0;                ///< rows of the CSV
  std::vector<std::string> failures;   ///< one line per failed run: run, problem, status, error
  std::vector<std::string> shownRuns;  ///< figures: the runs (`runs/<run>/`) the figure shows
  /// What the paper's conclusion takes from this artefact (computed from the data; may be empty).
  std::vector<std::string> conclusion;
};

/// The directory of the paper's reference figures (`table1.toml`, ...) for the configs
/// directory `configs`: its sibling `../reference` (e.g. `experiments/reference` for
/// `experiments/configs`) when that is a directory; otherwise `experiments/reference` of the
/// source tree this program was built from (configs outside the repository, e.g. in tests).
std::filesystem::path referenceDir(const std::filesystem::path& configs = "experiments/configs");

/// Builds the artefact of experiment `id` from its CSV; `dir` is `results/<id>/` (for the
/// per-run files a figure may read: `runs/<run>/cells.csv`, `runs/<run>/mesh.ply`) and
/// `reference` the directory of the paper's reference figures (see referenceDir). Known ids
/// (`tab1-degeneracy`, `fig-degeneracy-vs-n`, `tab-ablation-*`, `tab-connection`,
/// `fig-convergence`, `fig-cells`, `fig-app-*`) get their own tables, figures and sentences;
/// any other id a table with one row per run. Throws InputError for a missing column or a
/// missing or malformed reference file.
Artefact buildArtefact(const std::string& id, const CsvTable& csv, const std::filesystem::path& dir,
                       const std::filesystem::path& reference = referenceDir());

/// Settings of writeReport.
struct ReportSettings {
  std::filesystem::path results = "results";              ///< `<id>/<id>.csv` per experiment
  std::filesystem::path configs = "experiments/configs";  ///< `<id>.toml`: the expected ids
  bool quick = false;                                     ///< said so in the report
  bool render = true;  ///< run gnuplot for figures when it is on PATH
  /// The paper's reference figures (`table1.toml`); empty: referenceDir(configs).
  std::filesystem::path reference;
};

/// What writeReport did.
struct ReportOutcome {
  std::vector<std::string> written;  ///< artefact ids written
  std::vector<std::string> missing;  ///< expected ids without a CSV
  std::vector<std::string> errors;   ///< one line per artefact that could not be made
  std::size_t failedRuns = 0;        ///< failed runs over all experiments
  std::vector<std::string> notes;    ///< e.g. "gnuplot not found: figures not rendered"
  /// 0: all fine; 1: failed runs, missing experiments or unrendered figures; 2: an
  /// experiment's CSV was bad input.
  int status = 0;
};

/// Writes every artefact whose CSV exists under `settings.results`, `results/report.md` (which
/// ends with the conclusion) and `results/conclusion.tex`, the paper's conclusion computed from
/// the results: runs, failed and certified runs over all experiments, then each artefact's
/// Artefact::conclusion in report order,
/// each file atomically (a failed artefact leaves its previous files alone). Progress lines go
/// to `log`. Throws InputError when `settings.results` is not a directory.
ReportOutcome writeReport(const ReportSettings& settings, std::ostream& log);

/// The artefact ids the report knows, in report order (application figures `fig-app-*` are
/// found in the configs and results directories).
std::span<const std::string_view> knownArtefacts();

}  // namespace ndc::report
