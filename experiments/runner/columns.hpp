/// \file columns.hpp
/// The columns of an experiment's combined CSV `<id>.csv` (docs/experiments.md): the run's
/// identity and settings (kExperimentRunColumns), then the numeric fields of its summary.json
/// (kExperimentSummaryColumns, taken from the summary schema, framework/io/summary_schema.hpp),
/// then any other numeric summary field, sorted by name. The report names the columns it reads
/// with `_column`, which checks them against these lists when it is compiled.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string_view>

#include "framework/io/summary_schema.hpp"

namespace ndc {

/// The leading columns of the combined CSV `<id>.csv`, one row per run.
/// `expect_ok` and `expect_notes` record the comparison of the run's mesh with the problem's
/// `[expect]` (checkExpectation, expectation.hpp).
inline constexpr std::array<std::string_view, 22> kExperimentRunColumns = {
    "experiment",
    "run",
    "problem",
    "problem_file",
    "n",
    "k",
    "depth",
    "seed",
    "scalar",
    "precision_bits",
    "bounding",
    "subdivision",
    "projection",
    "classification",
    "connection",
    "status",
    "exit_code",
    "error",
    "expect_components",
    "expect_euler_characteristic",
    "expect_ok",
    "expect_notes"};

/// The summary.json fields (docs/contracts.md 4.3, and the counts of 4.5) that follow, flattened
/// with dotted names: the fields of kSummaryFields with a SummaryField::csvColumn, in that order.
/// Numeric fields a later summary schema adds come after these, sorted by name; list elements
/// (singular points, the perturbation level) and `expect` (see `expect_ok`) are left out.
inline constexpr auto kExperimentSummaryColumns = [] {
  constexpr std::size_t count = static_cast<std::size_t>(
      std::count_if(std::begin(kSummaryFields), std::end(kSummaryFields),
                    [](const SummaryField& f) { return f.csvColumn > 0; }));
  std::array<std::string_view, count> columns{};
  for (const SummaryField& f : kSummaryFields)
    if (f.csvColumn > 0) columns.at(static_cast<std::size_t>(f.csvColumn - 1)) = f.path;
  return columns;
}();
static_assert(std::none_of(kExperimentSummaryColumns.begin(), kExperimentSummaryColumns.end(),
                           [](std::string_view c) { return c.empty(); }),
              "SummaryField::csvColumn: the places 1, 2, ... each once");

/// Whether `name` is a column the runner writes (a run column or a summary column).
constexpr bool isExperimentColumn(std::string_view name) {
  return std::find(kExperimentRunColumns.begin(), kExperimentRunColumns.end(), name) !=
             kExperimentRunColumns.end() ||
         std::find(kExperimentSummaryColumns.begin(), kExperimentSummaryColumns.end(), name) !=
             kExperimentSummaryColumns.end();
}

inline namespace column_literals {

/// A column of the combined CSV, checked when compiled: `"cells.normal"_column` does not compile
/// when the runner writes no such column.
consteval std::string_view operator""_column(const char* text, std::size_t size) {
  const std::string_view name(text, size);
  if (!isExperimentColumn(name)) throw "not a column of the experiment CSV (columns.hpp)";
  return name;
}

}  // namespace column_literals

}  // namespace ndc
