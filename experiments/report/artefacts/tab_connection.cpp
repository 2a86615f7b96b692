// tab-connection: the connection strategies over the problem corpus
// (docs/experiment-tab-connection.md).
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

/// A topological quantity: the column of its expected value and the column of the mesh's.
struct Quantity {
  std::string_view expected, got;
};
/// The components and the Euler characteristic.
constexpr Quantity kComponents = {"expect_components"_column, "mesh.components"_column};
constexpr Quantity kEuler = {"expect_euler_characteristic"_column,
                             "mesh.euler_characteristic"_column};

/// A run's topology against the problem's expectation (`expect_components`,
/// `expect_euler_characteristic`).
struct TopologyCheck {
  const CsvTable& t;
  /// The expected value of `q`; NaN when not given.
  double expected(std::size_t r, const Quantity& q) const { return t.number(r, q.expected); }
  /// Whether run `r` succeeded and got `q` as expected.
  bool right(std::size_t r, const Quantity& q) const {
    const double e = expected(r, q);
    return isOk(t, r) && std::isfinite(e) && t.number(r, q.got) == e;
  }
  /// Whether the problem of run `r` has an expected topology.
  bool hasExpect(std::size_t r) const {
    return std::isfinite(expected(r, kComponents)) || std::isfinite(expected(r, kEuler));
  }
};

/// One connection's (and other varying settings') totals over the corpus.
struct ConnectionScore {
  std::string label;
  int runs = 0, components = 0, euler = 0, both = 0;
  /// Runs with that value expected (the denominators); the other runs are not comparable,
  /// counted apart and never as wrong.
  int withComponents = 0, withEuler = 0, withBoth = 0;
  double boundary = 0, nonmanifold = 0, openEnds = 0;
};

/// "23/24 (96%), 4 not comparable": `count` right of the `of` runs that expect the value, and
/// the other runs of `runs`, whose problem does not state it, apart (never counted as wrong).
std::string rightShare(int count, int of, int runs) {
  std::string text = of ? std::to_string(count) + "/" + std::to_string(of) + " (" +
                              formatFixed(100.0 * count / of, 0) + "%)"
                        : std::string(kDash);
  if (runs > of) text += ", " + std::to_string(runs - of) + " not comparable";
  return text;
}

/// The score table's row of group `g`; adds its score to `scores`.
std::vector<std::string> connectionScoreRow(const TopologyCheck& check, const Group& g,
                                            std::vector<ConnectionScore>& scores) {
  const CsvTable& t = check.t;
  ConnectionScore s;
  s.label = join(g.key, ", ");
  int failed = 0;
  std::vector<std::size_t> ok;
  for (std::size_t r : g.rows) {
    ++s.runs;
    if (!isOk(t, r)) {
      ++failed;
    } else {
      ok.push_back(r);
      s.openEnds += t.number(r, "mesh.open_ends"_column);
      s.boundary += t.number(r, "mesh.boundary_edges"_column);
      s.nonmanifold += t.number(r, "mesh.nonmanifold_edges"_column);
    }
    if (!check.hasExpect(r)) continue;  // not comparable
    // Each value over the runs that expect it: a problem that states only its components is
    // not wrong about its Euler characteristic.
    const bool hasC = std::isfinite(check.expected(r, kComponents));
    const bool hasE = std::isfinite(check.expected(r, kEuler));
    const bool c = check.right(r, kComponents), e = check.right(r, kEuler);
    s.withComponents += hasC, s.components += hasC && c;
    s.withEuler += hasE, s.euler += hasE && e;
    s.withBoth += hasC && hasE, s.both += hasC && hasE && c && e;
  }
  const Stats chord = summarize(values(t, ok, "accuracy.max_chord_error"_column));
  std::vector<std::string> row = g.key;
  for (const std::string& cell :
       {std::to_string(s.runs), std::to_string(failed),
        rightShare(s.components, s.withComponents, s.runs),
        rightShare(s.euler, s.withEuler, s.runs), rightShare(s.both, s.withBoth, s.runs),
        formatNumber(s.openEnds), formatNumber(s.boundary), formatNumber(s.nonmanifold),
        formatNumber(chord.median, 2), formatNumber(chord.max, 2)})
    row.push_back(cell);
  scores.push_back(s);
  return row;
}

/// The score table: one row per connection (and other varying settings).
Table connectionScoreTable(const std::string& id, const TopologyCheck& check,
                           const std::vector<std::string>& keys,
                           std::vector<ConnectionScore>& scores) {
  Table table;
  table.id = id;
  table.caption =
      "Connections over the corpus: runs (failed), share of the runs that expect the "
      "components, the Euler characteristic and both that get them right (a failed run counts "
      "as wrong; runs whose problem does not state the value are not comparable and counted "
      "apart), total open ends, boundary and non-manifold edges, median and largest chord "
      "error.";
  table.columns = keys;
  for (std::string c :
       {"runs", "failed", "components right", "Euler right", "both right", "open ends",
        "boundary edges", "non-manifold edges", "median chord error", "max chord error"})
    table.columns.push_back(c);
  table.align = std::string(keys.size(), 'l') + "rrrrrrrrrr";
  for (const Group& g : groupBy(check.t, keys))
    table.rows.push_back(connectionScoreRow(check, g, scores));
  return table;
}

/// A cell of the detail table: components / Euler characteristic of `runs` (the runs of one
/// problem with one connection), with b(oundary) and nm (non-manifold) edges and `*` when wrong.
std::string connectionCell(const TopologyCheck& check, const std::vector<std::size_t>& runs) {
  const CsvTable& t = check.t;
  if (runs.empty()) return std::string(kDash);
  const std::size_t r = runs.front();
  std::string text;
  if (!isOk(t, r)) {
    text = t.cell(r, "status");
  } else {
    text = formatNumber(t.number(r, "mesh.components"_column)) + " / " +
           formatNumber(t.number(r, "mesh.euler_characteristic"_column));
    const double b = t.number(r, "mesh.boundary_edges"_column),
                 nm = t.number(r, "mesh.nonmanifold_edges"_column);
    if (b > 0) text += " b" + formatNumber(b);
    if (nm > 0) text += " nm" + formatNumber(nm);
    const bool wrong =
        (std::isfinite(check.expected(r, kComponents)) && !check.right(r, kComponents)) ||
        (std::isfinite(check.expected(r, kEuler)) && !check.right(r, kEuler));
    if (check.hasExpect(r) && wrong) text += " *";
  }
  if (runs.size() > 1 && !check.hasExpect(r)) {
    text += " (" + std::to_string(runs.size()) + " not comparable)";
  } else if (runs.size() > 1) {
    int good = 0;
    for (std::size_t x : runs) good += check.right(x, kComponents) && check.right(x, kEuler);
    text += " (" + std::to_string(good) + "/" + std::to_string(runs.size()) + " right)";
  }
  return text;
}

/// Per problem: components / Euler characteristic of each connection beside the expectation.
Table connectionDetailTable(const std::string& id, const TopologyCheck& check,
                            const std::vector<std::string>& other) {
  const CsvTable& t = check.t;
  // The connections in order of appearance, one column each.
  std::vector<std::string> connections;
  for (std::size_t r = 0; r < t.size(); ++r)
    if (std::find(connections.begin(), connections.end(), t.cell(r, "connection")) ==
        connections.end())
      connections.push_back(t.cell(r, "connection"));
  std::vector<std::string> rowKeys = {"problem"};
  rowKeys.insert(rowKeys.end(), other.begin(), other.end());
  Table detail;
  detail.id = id;
  detail.caption =
      "Per problem: components / Euler characteristic of each connection (b: "
      "boundary edges, nm: non-manifold edges when not 0; * marks a wrong "
      "topology; runs over several seeds show how many were right; expected ?: the problem "
      "does not state it, not comparable).";
  detail.columns = rowKeys;
  detail.columns.insert(detail.columns.begin() + 1, {"n", "k", "expected"});
  for (const std::string& c : connections) detail.columns.push_back(c);
  detail.align = "l" + std::string("rrl") + std::string(rowKeys.size() - 1, 'l') +
                 std::string(connections.size(), 'l');
  // One row per problem (and other varying settings).
  const auto show = [](double v) { return std::isfinite(v) ? formatNumber(v) : std::string("?"); };
  for (const Group& g : groupBy(t, rowKeys)) {
    const std::size_t r0 = g.rows.front();
    std::vector<std::string> row = {
        g.key[0], t.cell(r0, "n"), t.cell(r0, "k"),
        show(check.expected(r0, kComponents)) + " / " + show(check.expected(r0, kEuler))};
    for (std::size_t i = 1; i < g.key.size(); ++i) row.push_back(g.key[i]);
    for (const std::string& c : connections) {
      std::vector<std::size_t> runs;
      for (std::size_t r : g.rows)
        if (t.cell(r, "connection") == c) runs.push_back(r);
      row.push_back(connectionCell(check, runs));
    }
    detail.rows.push_back(std::move(row));
  }
  return detail;
}

/// What tab-connection shows: right topologies and defects per connection.
std::vector<std::string> connectionSentences(const std::vector<ConnectionScore>& scores) {
  std::vector<std::string> sentences;
  std::vector<std::string> parts;
  for (const ConnectionScore& s : scores)
    if (s.withBoth)
      parts.push_back(
          "`" + s.label + "` " + std::to_string(s.both) + " of " + std::to_string(s.withBoth) +
          (s.runs > s.withBoth ? " (" + std::to_string(s.runs - s.withBoth) + " not comparable)"
                               : ""));
  if (!parts.empty())
    sentences.push_back("Runs with both the components and the Euler characteristic right: " +
                        join(parts, ", ") + ".");
  parts.clear();
  for (const ConnectionScore& s : scores)
    parts.push_back("`" + s.label + "` " + formatNumber(s.boundary) + " boundary and " +
                    formatNumber(s.nonmanifold) + " non-manifold edges, " +
                    formatNumber(s.openEnds) + " open ends");
  if (!parts.empty())
    sentences.push_back("In total " + join(parts, "; ") +
                        ". The paper's connection (Sec. 4) keeps holes in surfaces, which "
                        "shows as boundary edges where the expected surface is closed.");
  return sentences;
}

}  // namespace

Artefact tabConnection(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  requireColumns(t, {"n", "k", "connection", "expect_components", "expect_euler_characteristic",
                     "mesh.components"_column, "mesh.euler_characteristic"_column,
                     "mesh.open_ends"_column, "mesh.boundary_edges"_column,
                     "mesh.nonmanifold_edges"_column, "accuracy.max_chord_error"_column});
  Artefact a;
  a.id = id;
  a.title = "Connection strategies over the problem corpus";
  // Group by connection and the other settings that vary.
  const std::vector<std::string> other =
      without(varyingColumns(t, kSettingColumns), {"connection"});
  std::vector<std::string> keys = {"connection"};
  keys.insert(keys.end(), other.begin(), other.end());
  // The tables and what they show.
  const TopologyCheck check{t};
  std::vector<ConnectionScore> scores;
  a.tables.push_back(connectionScoreTable(id, check, keys, scores));
  a.tables.push_back(connectionDetailTable(id, check, other));
  a.sentences = connectionSentences(scores);
  if (!a.sentences.empty())
    a.conclusion.push_back(prefixed("Connection strategies", a.sentences.front()));
  return a;
}

}  // namespace ndc::report::detail
