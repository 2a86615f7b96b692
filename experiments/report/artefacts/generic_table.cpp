// Any experiment without a builder of its own: a table with one row per run.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "experiments/report/artefacts/builders.hpp"
#include "experiments/report/artefacts/common.hpp"

namespace ndc::report::detail {

Artefact genericTable(const std::string& id, const CsvTable& t) {
  requireRunColumns(t);
  Artefact a;
  a.id = id;
  a.figure = id.starts_with("fig");
  a.title = id;
  Table table;
  table.id = id;
  table.caption = "Every run of " + id + ".";
  const std::vector<std::string_view> wanted = {"run"_column,
                                                "problem"_column,
                                                "n"_column,
                                                "k"_column,
                                                "depth"_column,
                                                "connection"_column,
                                                "status"_column,
                                                "cells.solution"_column,
                                                "cells.abnormal"_column,
                                                "mesh.components"_column,
                                                "mesh.euler_characteristic"_column,
                                                "accuracy.max_residual"_column,
                                                "timing_s.total"_column};
  std::vector<std::string> present;
  for (const std::string_view c : wanted)
    if (t.hasColumn(c)) present.emplace_back(c);
  table.columns = present;
  for (const std::string& c : present)
    table.align += c == "run" || c == "problem" || c == "status" || c == "connection" ? 'l' : 'r';
  for (std::size_t r = 0; r < t.size(); ++r) {
    std::vector<std::string> row;
    for (const std::string& c : present) {
      if (c.find('.') != std::string::npos)
        row.push_back(formatNumber(t.number(r, c), 3));
      else
        row.push_back(t.cell(r, c));
    }
    table.rows.push_back(std::move(row));
  }
  a.tables.push_back(std::move(table));
  a.sentences.push_back(std::to_string(okRows(t).size()) + " of " + std::to_string(t.size()) +
                        " runs succeeded.");
  return a;
}

}  // namespace ndc::report::detail
