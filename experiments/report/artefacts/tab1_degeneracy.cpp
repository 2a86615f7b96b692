// tab1-degeneracy: the paper's Table 1 reproduced, ours beside the paper's
// (docs/experiment-tab1-degeneracy.md).
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
                        : abnormalShare(meanOf(t_, like, "cells.normal"_column),
                                        meanOf(t_, like, "cells.abnormal"_column));
  }

  void ours(const Group& g, int paper, std::vector<std::string>& row) {
    const std::size_t r0 = g.rows.front();
    const double normal = meanOf(t_, g.rows, "cells.normal"_column);
    const double abnormal = meanOf(t_, g.rows, "cells.abnormal"_column);
    Ours o{t_.cell(r0, "problem"),
           paper,
           normal,
           abnormal,
           abnormalShare(normal, abnormal),
           meanOf(t_, g.rows, "cells.failed"_column),
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
  gp.command("set bmargin 7");                             // two-line tics, then the key
  gp.command("set key outside bottom center horizontal");  // below the bars, whatever their height
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

}  // namespace

Artefact tab1Degeneracy(const std::string& id, const CsvTable& t,
                        const std::vector<PaperRow>& paper) {
  requireRunColumns(t);
  requireColumns(t, {"problem_file", "n", "depth", "cells.normal"_column, "cells.abnormal"_column,
                     "cells.failed"_column});
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

}  // namespace ndc::report::detail
