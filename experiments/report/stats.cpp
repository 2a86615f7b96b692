// Aggregation of experiment results: see stats.hpp.
#include "experiments/report/stats.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <utility>

namespace ndc::report {

Stats summarize(std::span<const double> values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  Stats s;
  s.count = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  const std::size_t m = v.size() / 2;
  s.median = v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  double sum = 0;
  for (double x : v) sum += (x - s.mean) * (x - s.mean);
  s.stddev = v.size() > 1 ? std::sqrt(sum / static_cast<double>(v.size() - 1)) : 0.0;
  return s;
}

std::vector<Group> groupBy(const CsvTable& table, std::span<const std::string> columns,
                           std::span<const std::size_t> rows) {
  std::vector<std::size_t> index;
  for (const std::string& c : columns) index.push_back(table.column(c));
  std::vector<std::size_t> all;
  if (rows.empty()) {
    all.resize(table.size());
    std::iota(all.begin(), all.end(), std::size_t{0});
    rows = all;
  }
  std::vector<Group> groups;
  std::map<std::vector<std::string>, std::size_t> position;
  for (std::size_t r : rows) {
    std::vector<std::string> key;
    for (std::size_t c : index) key.push_back(table.rows.at(r)[c]);
    const auto [it, inserted] = position.emplace(key, groups.size());
    if (inserted) groups.push_back({std::move(key), {}});
    groups[it->second].rows.push_back(r);
  }
  return groups;
}

std::vector<double> values(const CsvTable& table, std::span<const std::size_t> rows,
                           std::string_view column) {
  std::vector<double> out;
  for (std::size_t r : rows) out.push_back(table.number(r, column));
  return out;
}

std::vector<std::string> varyingColumns(const CsvTable& table,
                                        std::span<const std::string> candidates) {
  std::vector<std::string> out;
  for (const std::string& c : candidates) {
    if (!table.hasColumn(c)) continue;
    std::set<std::string> seen;
    for (std::size_t r = 0; r < table.size(); ++r) seen.insert(table.cell(r, c));
    if (seen.size() > 1) out.push_back(c);
  }
  return out;
}

double logLogSlope(std::span<const double> x, std::span<const double> y) {
  std::vector<std::pair<double, double>> p;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i)
    if (x[i] > 0 && y[i] > 0 && std::isfinite(x[i]) && std::isfinite(y[i]))
      p.emplace_back(std::log(x[i]), std::log(y[i]));
  if (p.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  double mx = 0, my = 0;
  for (auto [a, b] : p) mx += a, my += b;
  mx /= static_cast<double>(p.size());
  my /= static_cast<double>(p.size());
  double sxy = 0, sxx = 0;
  for (auto [a, b] : p) sxy += (a - mx) * (b - my), sxx += (a - mx) * (a - mx);
  return sxx > 0 ? sxy / sxx : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace ndc::report
