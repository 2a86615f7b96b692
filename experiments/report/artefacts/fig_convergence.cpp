// fig-convergence: convergence with the depth (docs/experiment-fig-convergence.md).
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "experiments/report/artefacts/builders.hpp"
#include "experiments/report/artefacts/common.hpp"

namespace ndc::report::detail {
namespace {

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
  gp.command("set key outside right center vertical font \",8\"");  // beside the panel
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
    chord.push_back(meanOf(t, d.rows, "accuracy.max_chord_error"_column));
    residual.push_back(meanOf(t, d.rows, "accuracy.max_residual"_column));
    cells.push_back(meanOf(t, d.rows, "cells.solution"_column));
    time.push_back(meanOf(t, d.rows, "timing_s.total"_column));
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
      e.push_back(meanOf(t, d.rows, "accuracy.max_chord_error"_column));
      c.push_back(meanOf(t, d.rows, "cells.solution"_column));
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

}  // namespace

Artefact figConvergence(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(
      t, {"n", "k", "depth", "accuracy.max_chord_error"_column, "accuracy.max_residual"_column,
          "cells.solution"_column, "timing_s.total"_column});
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

}  // namespace ndc::report::detail
