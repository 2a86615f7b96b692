/// \file gnuplot.hpp
/// The report's figures as gnuplot scripts with inline data, rendered to PNG and PDF when
/// gnuplot is on PATH.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace ndc::report {

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

/// `text` in single quotes for the shell (a quote inside becomes `'\''`).
std::string shellQuote(const std::string& text);

}  // namespace ndc::report
