// fig-app-*: the mesh of each application problem in the manner of the paper's Figures 6-10
// (docs/experiment-fig-app-bisector.md, -blending.md, -convex-hull.md, -sweep-envelope.md,
// -sweep-silhouette.md).
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "experiments/report/artefacts/builders.hpp"
#include "experiments/report/artefacts/common.hpp"
#include "experiments/report/perspective.hpp"
#include "framework/problem/toml_reader.hpp"

namespace ndc::report::detail {
namespace {

/// gnuplot's view of the orthographic panels (`set view 62, 35`), degrees.
constexpr int kRotX = 62, kRotZ = 35;
/// How far the context surfaces (input, envelope) are pushed away from the viewer, as a share
/// of the input's drawn diagonal (trianglePm3d): the result is drawn in front where it touches
/// them, with no stripes.
constexpr double kPushBack = 0.01;

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
    // Behind the result, and behind the envelope, where they touch.
    const double push = kPushBack * drawnDiagonal(input.xyz, view);
    gp.data("input" + std::to_string(p), trianglePm3d(input, view, 2 * push));
    panel.plots.push_back("$input" + std::to_string(p) +
                          " with pm3d fs transparent solid 0.35 fc rgb \"#bdbdbd\" notitle");
    panel.plots.push_back(
        "keyentry with boxes fill transparent solid 0.35 lc rgb \"#bdbdbd\" title \"input\"");
    panel.box = input.xyz;
  }
  if (!view.perspective) return;
  const std::filesystem::path envelope = sameInputSurface(run);
  if (envelope.empty()) return;
  const PlyMesh shell = readPly(envelope / "mesh.ply");
  gp.data("envelope" + std::to_string(p),
          trianglePm3d(shell, view, kPushBack * drawnDiagonal(shell.xyz, view)));
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
  gp.command("set view " + std::to_string(kRotX) + ", " + std::to_string(kRotZ) + ", 1.2");
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

/// What the mesh of run `r` is: vertices, simplices, topology, residual and time.
std::string applicationSentence(const CsvTable& t, std::size_t r, const PlyMesh& mesh) {
  const bool surface = t.cell(r, "k") != "1";
  return "`" + t.cell(r, "problem") + "` (n = " + t.cell(r, "n") + ", depth " + t.cell(r, "depth") +
         "): " + std::to_string(mesh.xyz.size()) + " vertices, " +
         std::to_string(mesh.simplices.size()) + (surface ? " triangles" : " segments") + ", " +
         t.cell(r, "mesh.components"_column) + " component(s), Euler characteristic " +
         t.cell(r, "mesh.euler_characteristic"_column) +
         (t.hasColumn("expect_euler_characteristic") &&
                  !t.cell(r, "expect_euler_characteristic").empty()
              ? " (expected " + t.cell(r, "expect_euler_characteristic") + ")"
              : "") +
         (surface ? ", " + t.cell(r, "mesh.boundary_edges"_column) + " boundary and " +
                        t.cell(r, "mesh.nonmanifold_edges"_column) + " non-manifold edges"
                  : "") +
         ", largest residual " + formatNumber(t.number(r, "accuracy.max_residual"_column), 2) +
         ", " + formatNumber(t.number(r, "timing_s.total"_column), 2) + " s.";
}

/// Plots the mesh of run `r` as panel `p` in the manner of the paper's Figures 6-10: the input
/// surfaces lightly shaded, the result solid (thick curves, lit surfaces), in perspective from
/// the problem's eye point when it has one (the silhouette, Fig. 7); returns its sentence.
std::string plotApplicationRun(GnuplotScript& gp, const CsvTable& t, std::size_t r, std::size_t p,
                               const std::filesystem::path& run) {
  const PlyMesh mesh = readPly(run / "mesh.ply");
  const bool curve = t.cell(r, "k") == "1";
  // The view: through the eye point, aimed at the centre of the result.
  View view = orthographicView(kRotX, kRotZ);
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

}  // namespace

Artefact figApplication(const std::string& id, const CsvTable& t,
                        const std::filesystem::path& dir) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "mesh.vertices"_column, "mesh.components"_column,
                     "mesh.euler_characteristic"_column, "mesh.boundary_edges"_column,
                     "mesh.nonmanifold_edges"_column, "accuracy.max_residual"_column,
                     "timing_s.total"_column});
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
  gp.command("set key outside right top samplen 2");
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

}  // namespace ndc::report::detail
