// What the artefact builders share: see common.hpp.
#include "experiments/report/artefacts/common.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace ndc::report::detail {

/// Run settings that may vary within an experiment (jitter seeds are averaged over instead).
const std::vector<std::string> kSettingColumns = {"depth",      "bounding",       "subdivision",
                                                  "projection", "classification", "connection",
                                                  "scalar",     "precision_bits"};

std::string join(const std::vector<std::string>& parts, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i)
    out += (i ? std::string(separator) : "") + parts[i];
  return out;
}

std::string percent(double value) { return formatFixed(value, 1) + "%"; }

/// `prefix` and `sentence` as one sentence: "Table 1: our abnormal share ...".
std::string prefixed(const std::string& prefix, std::string sentence) {
  if (!sentence.empty() && std::isupper(static_cast<unsigned char>(sentence[0])) &&
      !(sentence.size() > 1 && std::isupper(static_cast<unsigned char>(sentence[1]))))
    sentence[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(sentence[0])));
  return prefix + ": " + sentence;
}

bool isOk(const CsvTable& t, std::size_t r) { return t.cell(r, "status") == "ok"; }

std::vector<std::size_t> okRows(const CsvTable& t) {
  std::vector<std::size_t> rows;
  for (std::size_t r = 0; r < t.size(); ++r)
    if (isOk(t, r)) rows.push_back(r);
  return rows;
}

/// One line per failed run: which run, which problem, the status, exit code and error.
std::vector<std::string> failedRuns(const CsvTable& t) {
  std::vector<std::string> out;
  for (std::size_t r = 0; r < t.size(); ++r) {
    if (isOk(t, r)) continue;
    std::string line = "run `" + t.cell(r, "run") + "` (problem " + t.cell(r, "problem");
    if (t.hasColumn("depth") && !t.cell(r, "depth").empty())
      line += ", depth " + t.cell(r, "depth");
    line += "): " + t.cell(r, "status");
    if (t.hasColumn("exit_code") && !t.cell(r, "exit_code").empty())
      line += ", exit " + t.cell(r, "exit_code");
    if (t.hasColumn("error") && !t.cell(r, "error").empty()) line += ": " + t.cell(r, "error");
    out.push_back(line);
  }
  return out;
}

double meanOf(const CsvTable& t, std::span<const std::size_t> rows, std::string_view column) {
  return summarize(values(t, rows, column)).mean;
}

double maxOf(const CsvTable& t, std::span<const std::size_t> rows, std::string_view column) {
  return summarize(values(t, rows, column)).max;
}

/// `column=value` for each of `columns`, e.g. "bounding=interval, depth=6".
std::string settingsLabel(const CsvTable& t, std::size_t row,
                          const std::vector<std::string>& columns) {
  std::vector<std::string> parts;
  for (const std::string& c : columns) parts.push_back(c + "=" + t.cell(row, c));
  return join(parts, ", ");
}

/// Abnormal share in percent of the classified cells, as in the paper's Table 1.
double abnormalShare(double normal, double abnormal) {
  return normal + abnormal > 0 ? 100.0 * abnormal / (normal + abnormal) : kNaN;
}

/// Geometric mean of the ratios a/b over the pairs where both are positive; NaN if none.
double geometricMeanRatio(const std::vector<std::pair<double, double>>& pairs) {
  double sum = 0;
  int count = 0;
  for (auto [a, b] : pairs)
    if (a > 0 && b > 0 && std::isfinite(a) && std::isfinite(b)) sum += std::log(a / b), ++count;
  return count ? std::exp(sum / count) : kNaN;
}

std::vector<std::string> without(std::vector<std::string> columns,
                                 std::initializer_list<std::string_view> drop) {
  std::erase_if(columns, [&](const std::string& c) {
    return std::find(drop.begin(), drop.end(), c) != drop.end();
  });
  return columns;
}

void requireColumns(const CsvTable& t, std::initializer_list<std::string_view> names) {
  const std::vector<std::string_view> list(names);
  t.require(list);
}

// The run-identifying columns every artefact needs.
void requireRunColumns(const CsvTable& t) {
  requireColumns(t, {"experiment", "run", "problem", "status", "error"});
}

std::string normalised(std::string_view text) {
  std::string out;
  for (char c : text)
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace ndc::report::detail
