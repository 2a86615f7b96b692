/// \file parser.hpp
/// The expression parser: text to a compiled Tape (the grammar is in parser.cpp and
/// docs/contracts.md 4.1).
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "framework/numeric/tape.hpp"

namespace ndc {

/// Parses `text` in the variables `variables` and compiles it; throws ExpressionError (with the
/// 1-based column) on any error.
Tape parseExpression(std::string_view text, std::span<const std::string> variables);

}  // namespace ndc
