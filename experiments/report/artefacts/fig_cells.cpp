// fig-cells: a Figure-2-style picture of the solution cells (docs/experiment-fig-cells.md).
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
         t.cell(r, "mesh.components"_column) + " component(s)" +
         (t.hasColumn("expect_components") && !t.cell(r, "expect_components").empty()
              ? " (expected " + t.cell(r, "expect_components") + ")."
              : ".");
}

}  // namespace

Artefact figCells(const std::string& id, const CsvTable& t, const std::filesystem::path& dir) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "cells.normal"_column, "cells.abnormal"_column,
                     "mesh.components"_column});
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
  const double normal = t.number(r, "cells.normal"_column),
               abnormal = t.number(r, "cells.abnormal"_column);
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

}  // namespace ndc::report::detail
