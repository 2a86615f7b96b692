// tab-ablation-*: the variants of one strategy family compared (docs/experiment-tab-ablation-
// bounding.md, -subdivision.md, -scalar.md).
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

/// Per variant, per problem (and other setting): mean visited, mean total time, largest
/// residual, mean solution cells.
using AblationMeasures =
    std::map<std::string, std::map<std::vector<std::string>, std::array<double, 4>>>;

/// The variants of an ablation in order of appearance, with what each measured.
struct AblationData {
  std::vector<std::string> variants;
  AblationMeasures measured;
};

/// The ablation table's header.
Table ablationTable(const std::string& id, const std::string& family, bool scalar,
                    const std::vector<std::string>& other) {
  Table table;
  table.id = id;
  table.caption = "Ablation of the " + family + (scalar ? " type" : " strategy") +
                  ": cells visited and kept, largest residual, seconds per stage (mean over "
                  "seeds).";
  table.columns = {"problem", "n", "k"};
  for (const std::string& c : other) table.columns.push_back(c);
  for (std::string c :
       {family, std::string("visited"), std::string("solution"), std::string("max residual"),
        std::string("subdivision s"), std::string("projection s"), std::string("connection s"),
        std::string("total s")})
    table.columns.push_back(c);
  table.align = "lrr" + std::string(other.size(), 'r') + "lrrrrrrr";
  return table;
}

/// The table row of variant `v` of one problem group (`rows`); records its measures.
std::vector<std::string> ablationRow(const CsvTable& t, const std::vector<std::string>& other,
                                     const Group& g, const std::string& v,
                                     const std::vector<std::size_t>& rows, AblationData& data) {
  const std::size_t r0 = rows.front();
  std::vector<std::string> row = {t.cell(r0, "problem"), t.cell(r0, "n"), t.cell(r0, "k")};
  for (const std::string& c : other) row.push_back(t.cell(r0, c));
  const double visited = meanOf(t, rows, "cells.visited"_column);
  const double residual = maxOf(t, rows, "accuracy.max_residual"_column);
  const double total = meanOf(t, rows, "timing_s.total"_column);
  const double solution = meanOf(t, rows, "cells.solution"_column);
  data.measured[v][g.key] = {visited, total, residual, solution};
  row.push_back(v);
  row.push_back(formatNumber(std::round(visited)));
  row.push_back(formatNumber(std::round(solution)));
  row.push_back(formatNumber(residual, 2));
  for (std::string_view stage :
       {"timing_s.subdivision"_column, "timing_s.projection"_column, "timing_s.connection"_column})
    row.push_back(formatNumber(meanOf(t, rows, stage), 2));
  row.push_back(formatNumber(total, 2));
  return row;
}

/// What an ablation shows: each variant against the first, and the largest residuals.
std::vector<std::string> ablationSentences(const AblationData& data) {
  std::vector<std::string> sentences;
  const std::string& base = data.variants.front();
  const auto& baseMeasures = data.measured.at(base);
  // Each variant against the first: cells, time and solution cells.
  for (std::size_t v = 1; v < data.variants.size(); ++v) {
    std::vector<std::pair<double, double>> cells, time;
    int sameSolution = 0, common = 0;
    for (const auto& [key, m] : data.measured.at(data.variants[v])) {
      const auto it = baseMeasures.find(key);
      if (it == baseMeasures.end()) continue;
      ++common;
      cells.emplace_back(m[0], it->second[0]);
      time.emplace_back(m[1], it->second[1]);
      if (m[3] == it->second[3]) ++sameSolution;
    }
    if (!common) continue;
    sentences.push_back("`" + data.variants[v] + "` visits " +
                        formatFixed(geometricMeanRatio(cells), 2) + " times the cells of `" + base +
                        "` and takes " + formatFixed(geometricMeanRatio(time), 2) +
                        " times its total time (geometric means over " + std::to_string(common) +
                        " problem settings); it keeps the same number of solution cells in " +
                        std::to_string(sameSolution) + " of them.");
  }
  // The largest residual of each variant.
  std::vector<std::string> residuals;
  for (const std::string& v : data.variants) {
    double worst = kNaN;
    for (const auto& [key, m] : data.measured.at(v))
      if (std::isfinite(m[2])) worst = std::isfinite(worst) ? std::max(worst, m[2]) : m[2];
    residuals.push_back("`" + v + "` " + formatNumber(worst, 2));
  }
  sentences.push_back("Largest residual over all problems: " + join(residuals, ", ") + ".");
  return sentences;
}

}  // namespace

Artefact tabAblation(const std::string& id, const CsvTable& t, const std::string& family) {
  requireRunColumns(t);
  requireColumns(
      t, {"n", "k", "depth", "cells.visited"_column, "cells.solution"_column,
          "accuracy.max_residual"_column, "timing_s.subdivision"_column,
          "timing_s.projection"_column, "timing_s.connection"_column, "timing_s.total"_column});
  const bool scalar = family == "scalar";
  if (scalar)
    requireColumns(t, {"scalar", "precision_bits"});
  else
    t.column(family);
  Artefact a;
  a.id = id;
  a.title = "Ablation: " + family;
  const auto variant = [&](std::size_t r) {
    if (!scalar) return t.cell(r, family);
    return t.cell(r, "scalar") == "double"
               ? std::string("double")
               : t.cell(r, "scalar") + " " + t.cell(r, "precision_bits");
  };
  // Group by problem and the other settings that vary.
  std::vector<std::string> other =
      without(varyingColumns(t, kSettingColumns), {"scalar", "precision_bits"});
  std::erase(other, family);
  std::vector<std::string> keys = {"problem"};
  keys.insert(keys.end(), other.begin(), other.end());

  // Per variant: for each problem (and other setting), mean visited, time, residual.
  Table table = ablationTable(id, family, scalar, other);
  AblationData data;
  for (const Group& g : groupBy(t, keys, okRows(t))) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<std::size_t>> byVariant;
    for (std::size_t r : g.rows) {
      if (!byVariant.count(variant(r))) order.push_back(variant(r));
      byVariant[variant(r)].push_back(r);
    }
    for (const std::string& v : order) {
      if (std::find(data.variants.begin(), data.variants.end(), v) == data.variants.end())
        data.variants.push_back(v);
      table.rows.push_back(ablationRow(t, other, g, v, byVariant[v], data));
    }
  }
  a.tables.push_back(std::move(table));

  // What it shows.
  if (data.variants.empty())
    a.sentences.push_back("No run succeeded, so there is nothing to compare.");
  else
    a.sentences = ablationSentences(data);
  if (!data.variants.empty())
    a.conclusion.push_back(prefixed("Ablation of the " + family, a.sentences.front()));
  return a;
}

}  // namespace ndc::report::detail
