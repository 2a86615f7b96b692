/// \file json.hpp
/// Reading numbers out of JSON text (the summary.json of a run, docs/contracts.md 4.3): a small
/// recursive-descent reader that keeps the numeric fields with their dotted paths.
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

}  // namespace ndc
