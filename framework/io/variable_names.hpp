/// \file variable_names.hpp
/// The problem's variable names in the output files (docs/contracts.md 4.4, "Names"): the
/// contracts name the coordinates `u0 ..` (`lo0 ..`, `c0 ..`), and a run whose problem has
/// names adds them beside those as aliases: PLY a `comment variables ...` line, VTU one more
/// point-data array per name, the CSV files one more column per name and prefix.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>
#include <string_view>
#include <vector>

#include "framework/io/result.hpp"

namespace ndc {

/// Whether `s` is a plain identifier (`[A-Za-z_][A-Za-z0-9_]*`), safe in a PLY comment, an XML
/// attribute and a CSV header without quoting.
inline bool plainIdentifier(std::string_view s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s.front()))) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

/// The problem's variable names when every output can carry them: one per coordinate, each a
/// plain identifier; empty otherwise (a run without names, or one whose names are all `u0 ..`
/// already), and the outputs then name the coordinates `u0 ..` only.
inline std::vector<std::string> variableNames(const RunResult& r) {
  const std::vector<std::string>& names = r.summary.variables;
  if (names.size() != static_cast<std::size_t>(r.n)) return {};
  bool same = true;
  for (std::size_t j = 0; j < names.size(); ++j) {
    if (!plainIdentifier(names[j])) return {};
    same = same && names[j] == "u" + std::to_string(j);
  }
  return same ? std::vector<std::string>{} : names;
}

/// The alias columns (or arrays) of a file: `prefix + name` per variable, or none when one of
/// them would repeat a name the file already has (`taken`, the contract's names) or another
/// alias, so that no reader ever sees one name twice.
inline std::vector<std::string> aliasNames(const RunResult& r, const std::string& prefix,
                                           const std::vector<std::string>& taken) {
  std::vector<std::string> aliases;
  for (const std::string& name : variableNames(r)) {
    const std::string alias = prefix + name;
    const bool clash = std::find(taken.begin(), taken.end(), alias) != taken.end() ||
                       std::find(aliases.begin(), aliases.end(), alias) != aliases.end();
    if (clash) return {};
    aliases.push_back(alias);
  }
  return aliases;
}

}  // namespace ndc
