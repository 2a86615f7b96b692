// The paper's reference figures: see paper_reference.hpp, and referenceDir (report.hpp).
#include "experiments/report/artefacts/paper_reference.hpp"

#include <cmath>
#include <cstdint>
#include <optional>
#include <system_error>

#include <toml++/toml.h>

#include "experiments/report/artefacts/common.hpp"
#include "framework/problem/toml_reader.hpp"

namespace ndc::report {
namespace detail {
namespace {

/// A string of a reference row; throws InputError naming the file, row and key.
std::string referenceString(const toml::table& row, const std::string& where, const char* key,
                            bool required) {
  const toml::node* node = row.get(key);
  if (!node && !required) return "";
  const std::optional<std::string> value = node ? node->value<std::string>() : std::nullopt;
  if (!value || value->empty())
    throw InputError(where + ": '" + key + "' must be a non-empty string");
  return *value;
}

/// A number >= 0 of a reference row; throws InputError naming the file, row and key.
double referenceNumber(const toml::table& row, const std::string& where, const char* key) {
  const toml::node* node = row.get(key);
  const std::optional<double> value = node ? node->value<double>() : std::nullopt;
  if (!value || !std::isfinite(*value) || *value < 0)
    throw InputError(where + ": '" + key + "' must be a number >= 0");
  return *value;
}

/// One `[[row]]` of table1.toml.
PaperRow paperRowFrom(const toml::node& node, const std::string& where) {
  const toml::table* row = node.as_table();
  if (!row) throw InputError(where + ": not a table");
  PaperRow p;
  p.key = normalised(referenceString(*row, where, "key", true));
  p.label = referenceString(*row, where, "label", true);
  p.family = referenceString(*row, where, "family", true);
  p.highlight = referenceString(*row, where, "highlight", false);
  const toml::node* n = row->get("n");
  const std::optional<std::int64_t> dimension = n ? n->value<std::int64_t>() : std::nullopt;
  if (!dimension || *dimension < 1 || *dimension > 1000)
    throw InputError(where + ": 'n' must be an integer 1..1000");
  p.n = static_cast<int>(*dimension);
  p.normal = referenceNumber(*row, where, "normal");
  p.abnormal = referenceNumber(*row, where, "abnormal");
  p.share = referenceNumber(*row, where, "share");
  return p;
}

}  // namespace

/// The paper's Table 1 from `<reference>/table1.toml` (a `[[row]]` per example, in the paper's
/// order). Throws InputError (one line, naming the file) when it is missing or malformed.
std::vector<PaperRow> loadPaperTable1(const std::filesystem::path& reference) {
  const std::filesystem::path file = reference / "table1.toml";
  const std::string name = file.string();
  if (!std::filesystem::is_regular_file(file))
    throw InputError(name + ": the paper's reference figures are missing");
  const std::string text = readText(file);
  const toml::table top = parseTomlText(text, name);
  const toml::array* rows = top["row"].as_array();
  if (!rows || rows->empty()) throw InputError(name + ": no [[row]] of the paper's Table 1");
  std::vector<PaperRow> table;
  for (std::size_t i = 0; i < rows->size(); ++i) {
    table.push_back(paperRowFrom((*rows)[i], name + ": row " + std::to_string(i + 1)));
    for (std::size_t j = 0; j + 1 < table.size(); ++j)
      if (table[j].key == table.back().key)
        throw InputError(name + ": row " + std::to_string(i + 1) + ": duplicate key '" +
                         table.back().key + "'");
  }
  return table;
}

}  // namespace detail

#ifndef NDC_SOURCE_DIR
#define NDC_SOURCE_DIR ""
#endif

std::filesystem::path referenceDir(const std::filesystem::path& configs) {
  std::filesystem::path dir = configs;
  if (!dir.has_filename()) dir = dir.parent_path();  // "experiments/configs/"
  const std::filesystem::path sibling = dir.parent_path() / "reference";
  std::error_code error;
  if (std::filesystem::is_directory(sibling, error)) return sibling;
  const std::string source = NDC_SOURCE_DIR;
  if (!source.empty()) return std::filesystem::path(source) / "experiments" / "reference";
  return sibling;
}

}  // namespace ndc::report
