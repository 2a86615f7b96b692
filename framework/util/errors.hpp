/// \file errors.hpp
/// The error types of ndcontour. Each is a std::runtime_error whose `what()` is one line; the
/// CLI prints it and exits with status 2 (bad input or usage, docs/contracts.md 4.2). Any other
/// exception that reaches the CLI is an internal error (status 1), which is a bug.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace ndc {

/// Bad input of any kind. `what()` is one line: `FILE:LINE:COL: message` (line and column
/// when known).
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& line) : std::runtime_error(line) {}
  /// Formats `file[:line[:column]]: message`; line/column 0 means unknown.
  static InputError at(const std::string& file, int line, int column, const std::string& message);
};

/// A syntax error in an expression, with the 1-based column where it was found (the problem
/// reader turns it into an InputError at the file position).
class ExpressionError : public std::runtime_error {
 public:
  ExpressionError(int column, const std::string& message)
      : std::runtime_error(message), column_(column) {}
  /// 1-based column in the expression text.
  int column() const { return column_; }

 private:
  int column_;
};

/// Thrown by the subdivision when the solution cells exceed their budget: the zero set has a
/// higher dimension than the problem's k (strategies/subdivision/subdivision.hpp).
struct CellBudgetExceeded : InputError {
  using InputError::InputError;
};

/// A bad command line, strategy spec or experiment option (unknown strategy or parameter, value
/// out of range). It is bad input, so a library user who catches InputError catches it too;
/// the CLI prints it as `ndcontour: what()`.
class UsageError : public InputError {
 public:
  explicit UsageError(const std::string& message) : InputError(message) {}
};

/// `text` with every line break replaced by a space, so that a message stays on one line.
std::string oneLine(std::string text);

/// Why a file operation failed, for the end of a message: `error`'s text, or (no error code)
/// the C library's for errno, e.g. "Permission denied".
std::string failureReason(const std::error_code& error = {});

/// Creates `dir` and its missing parents, or throws InputError `DIR: cannot create the WHAT:
/// REASON` (the system's reason, or that a file of that name is in the way).
void createDirectories(const std::filesystem::path& dir, std::string_view what);

/// " (did you mean 'NAME'?)" for the name in `known` nearest to `word` (edit distance at most
/// a third of its length, and at least 1; a name that starts with `word` counts too), else "".
std::string didYouMean(std::string_view word, const std::vector<std::string>& known);

}  // namespace ndc
