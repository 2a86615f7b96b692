/// \file common.hpp
/// What the artefact builders of the report share (internal to experiments/report/): the
/// settings columns, joining and phrasing sentences, the successful and failed runs of an
/// experiment's CSV, means over runs, and the columns a builder requires.
#pragma once

#include <cstddef>
#include <initializer_list>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "experiments/report/report.hpp"
#include "experiments/runner/columns.hpp"

namespace ndc::report::detail {

/// A missing number.
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Run settings that may vary within an experiment (jitter seeds are averaged over instead).
extern const std::vector<std::string> kSettingColumns;

/// `parts` with `separator` between them.
std::string join(const std::vector<std::string>& parts, std::string_view separator);

/// `value` with one decimal and a percent sign; NaN is "–%".
std::string percent(double value);

/// `prefix` and `sentence` as one sentence: "Table 1: our abnormal share ...".
std::string prefixed(const std::string& prefix, std::string sentence);

/// Whether run `r` succeeded (`status` is `ok`).
bool isOk(const CsvTable& t, std::size_t r);

/// The rows of the successful runs.
std::vector<std::size_t> okRows(const CsvTable& t);

/// One line per failed run: which run, which problem, the status, exit code and error.
std::vector<std::string> failedRuns(const CsvTable& t);

/// The mean of a numeric column over `rows` (NaN values left out).
double meanOf(const CsvTable& t, std::span<const std::size_t> rows, std::string_view column);

/// The largest value of a numeric column over `rows` (NaN values left out).
double maxOf(const CsvTable& t, std::span<const std::size_t> rows, std::string_view column);

/// `column=value` for each of `columns`, e.g. "bounding=interval, depth=6".
std::string settingsLabel(const CsvTable& t, std::size_t row,
                          const std::vector<std::string>& columns);

/// Abnormal share in percent of the classified cells, as in the paper's Table 1.
double abnormalShare(double normal, double abnormal);

/// Geometric mean of the ratios a/b over the pairs where both are positive; NaN if none.
double geometricMeanRatio(const std::vector<std::pair<double, double>>& pairs);

/// `columns` without those in `drop`.
std::vector<std::string> without(std::vector<std::string> columns,
                                 std::initializer_list<std::string_view> drop);

/// Throws InputError naming the first of `names` that is not a column of `t`.
void requireColumns(const CsvTable& t, std::initializer_list<std::string_view> names);

/// Requires the run-identifying columns every artefact needs.
void requireRunColumns(const CsvTable& t);

/// The letters and digits of `text`, in lower case.
std::string normalised(std::string_view text);

}  // namespace ndc::report::detail
