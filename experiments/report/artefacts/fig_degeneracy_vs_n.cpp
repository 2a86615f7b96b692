// fig-degeneracy-vs-n and fig-degeneracy-vs-n-k3: the abnormal share against the ambient
// dimension n (docs/experiment-fig-degeneracy-vs-n.md, docs/experiment-fig-degeneracy-vs-n-k3.md).
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
    share.push_back(
        abnormalShare(t.number(r, "cells.normal"_column), t.number(r, "cells.abnormal"_column)));
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

/// What a series shows: first to last n, whether every step goes up, the runs' spread (`widest`,
/// -1 when each n has one run), and the paper's claim.
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
  sentence += widest < 0 ? std::string(" (one run at each n).")
                         : "; the seeds spread it by up to " + formatFixed(widest, 1) + " points.";
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
  double widest = -1;  // the widest spread over runs at one n; -1: one run at each n
  for (const Group& cell : byN) {
    const Stats st = degeneracyAtN(t, g, cell, vary, plot, means, points);
    trend.emplace_back(std::stoi(cell.key[0]), st.mean);
    widest = std::max(widest, st.count > 1 ? st.max - st.min : -1.0);
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

}  // namespace

Artefact figDegeneracyVsN(const std::string& id, const CsvTable& t,
                          const std::vector<PaperRow>& paper, bool depthSeries) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "depth", "cells.normal"_column, "cells.abnormal"_column});
  Artefact a;
  a.id = id;
  a.figure = true;
  a.title = depthSeries ? "Abnormal share against the ambient dimension n, per depth"
                        : "Abnormal share against the ambient dimension n";
  // One series per k and varying setting (the depth only with depthSeries: otherwise runs at
  // several depths are pooled, like seeds).
  const std::vector<std::string> vary =
      depthSeries ? varyingColumns(t, kSettingColumns)
                  : without(varyingColumns(t, kSettingColumns), {"depth"});
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
        "set key outside top center horizontal maxrows 2", "set grid", "set xtics 1",
        "set yrange [0:*]"})
    plot.gp.command(line);

  // Every series, then the paper's points.
  const std::vector<Group> series = groupBy(t, seriesKeys, okRows(t));
  for (std::size_t s = 0; s < series.size(); ++s)
    degeneracySeries(t, series[s], s, vary, plot, a.sentences);
  if (!plot.plots.empty()) {
    if (!paper.empty()) degeneracyPaper(paper, plot, a.sentences);
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

}  // namespace ndc::report::detail
