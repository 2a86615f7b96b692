/// \file load.hpp
/// Reading problem files (docs/contracts.md 4.1): equation problems and the application problems
/// of the paper's Sec. 3, which the applications layer builds.
#pragma once

#include <filesystem>
#include <string>

#include "framework/problem/problem.hpp"

namespace ndc {

/// Reads and validates a problem file; throws InputError.
Problem loadProblem(const std::filesystem::path& file);
/// Parses and validates problem text (`file` is used in messages); throws InputError.
Problem parseProblem(const std::string& text, const std::string& file);

}  // namespace ndc
