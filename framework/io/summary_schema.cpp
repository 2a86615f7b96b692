// The summary.json schema table: see summary_schema.hpp (the writer is ndc::toJson, io.cpp).
#include "framework/io/summary_schema.hpp"

#include <algorithm>
#include <string>

namespace ndc {

const SummaryField* summaryFieldOf(std::string_view path) {
  // Walk the path's parts from the top: below a list a part (an index) is its element `[]`,
  // below a map a part (a key) is its value `*`; below a list of numbers or strings or JSON
  // text the field ends.
  std::string pattern;
  const SummaryField* field = nullptr;
  std::size_t at = 0;
  while (at <= path.size()) {
    if (field &&
        (field->type == SummaryType::numberList || field->type == SummaryType::integerList ||
         field->type == SummaryType::integerOrList || field->type == SummaryType::stringList ||
         field->type == SummaryType::json))
      return field;
    const std::size_t dot = std::min(path.find('.', at), path.size());
    const std::string_view part = path.substr(at, dot - at);
    if (field && field->type == SummaryType::list)
      pattern += "[]";
    else
      pattern += (pattern.empty() ? "" : ".") +
                 std::string(field && field->type == SummaryType::map ? "*" : part);
    // The field of that pattern.
    field = nullptr;
    for (const SummaryField& f : kSummaryFields)
      if (f.path == pattern) field = &f;
    if (!field) return nullptr;
    at = dot + 1;
  }
  return field;
}

}  // namespace ndc
