/// \file stats.hpp
/// Aggregation of experiment results for the report: summary statistics, groups of rows that
/// share settings, and log-log slopes.
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/runner/csv.hpp"

namespace ndc::report {

/// Summary statistics of a sample; NaN values are ignored (count says how many were used).
struct Stats {
  std::size_t count = 0;                                     ///< finite values used
  double mean = std::numeric_limits<double>::quiet_NaN();    ///< arithmetic mean
  double stddev = std::numeric_limits<double>::quiet_NaN();  ///< sample standard deviation (n-1); 0
                                                             ///< for one value
  double min = std::numeric_limits<double>::quiet_NaN();     ///< smallest value
  double max = std::numeric_limits<double>::quiet_NaN();     ///< largest value
  double median =
      std::numeric_limits<double>::quiet_NaN();  ///< middle value (mean of the two middle ones)
};

/// Statistics of the finite values of `values`.
Stats summarize(std::span<const double> values);

/// Rows sharing the same values in the grouping columns, in order of first appearance.
struct Group {
  std::vector<std::string> key;   ///< the grouping columns' values
  std::vector<std::size_t> rows;  ///< indices into the table's rows
};

/// Groups `rows` (all rows when empty) by the values of `columns`, keeping the order in which
/// each key first appears. Throws InputError for a missing column.
std::vector<Group> groupBy(const CsvTable& table, std::span<const std::string> columns,
                           std::span<const std::size_t> rows = {});

/// The values of a numeric column at `rows` (NaN for empty cells).
std::vector<double> values(const CsvTable& table, std::span<const std::size_t> rows,
                           std::string_view column);

/// The columns among `candidates` that exist and take more than one value over the table.
std::vector<std::string> varyingColumns(const CsvTable& table,
                                        std::span<const std::string> candidates);

/// Least-squares slope of log(y) against log(x) over the pairs where both are positive and
/// finite; NaN with fewer than two such pairs.
double logLogSlope(std::span<const double> x, std::span<const double> y);

}  // namespace ndc::report
