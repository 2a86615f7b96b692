/// \file json.hpp
/// Reading numbers out of JSON text (the summary.json of a run, docs/contracts.md 4.3): a small
/// recursive-descent reader that keeps the numeric fields (or every leaf) with their dotted paths.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ndc {

/// The numeric fields of a JSON document (numbers and null), in document order, named by
/// their dotted paths (`cells.visited`); the number text is kept as written, null is "".
/// Throws std::runtime_error on malformed JSON.
std::vector<std::pair<std::string, std::string>> flattenJsonNumbers(std::string_view json);

/// The dotted paths of every leaf of a JSON document, in document order: strings, numbers,
/// booleans, null, and empty objects and arrays (array elements are numbered from 0). Throws
/// std::runtime_error on malformed JSON.
std::vector<std::string> jsonLeafPaths(std::string_view json);

/// The kind of a JSON leaf.
enum class JsonKind { number, string, boolean, null, empty };

/// One leaf of a JSON document: its dotted path, its text (a number as written, a string
/// unescaped, `true` or `false`; empty for null and for an empty object or array) and its kind.
struct JsonLeaf {
  std::string path;
  std::string text;
  JsonKind kind = JsonKind::null;
};

/// Every leaf of a JSON document with its value, in document order (a summary.json read back:
/// the pieces of a split solve, docs/split.md). Throws std::runtime_error on malformed JSON.
std::vector<JsonLeaf> jsonLeaves(std::string_view json);

}  // namespace ndc
