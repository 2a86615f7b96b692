/// \file toml_reader.hpp
/// Typed access to a parsed TOML problem file where every failure is an InputError at the
/// node's line and column (used by plain and application problem files alike).
#pragma once
#include <toml++/toml.h>

#include <string>

#include "framework/problem/problem.hpp"

namespace ndc {

/// A human name for the type of a TOML node, for "wrong type" messages.
std::string tomlTypeName(const toml::node& node);

/// Reads values out of one TOML document; `fail` throws InputError at a node's position,
/// prefixed with "problem 'NAME': " once setProblem has been called.
class TomlReader {
 public:
  /// `file` names the document in messages; both must outlive the reader.
  TomlReader(const std::string& text, const std::string& file) : text_(text), file_(file) {}

  [[noreturn]] void fail(const toml::source_region& where, const std::string& message) const;
  [[noreturn]] void fail(const toml::node& node, const std::string& message) const;
  /// Fails at no position (e.g. a missing key).
  [[noreturn]] void fail(const std::string& message) const;
  /// Names the problem in later messages.
  void setProblem(std::string name) { problem_ = std::move(name); }

  const toml::node& require(const toml::table& table, const std::string& key) const;
  std::string stringOf(const toml::node& node, const std::string& what) const;
  const toml::array& arrayOf(const toml::node& node, const std::string& what) const;
  const toml::table& tableOf(const toml::node& node, const std::string& what) const;
  /// A finite number (integer or float).
  double numberOf(const toml::node& node, const std::string& what) const;
  /// An integer in [lo, hi].
  long integerOf(const toml::node& node, const std::string& what, long lo, long hi) const;
  /// Fails on the first key of `table` not in `known` (a comma-separated list for the message).
  void onlyKeys(const toml::table& table, std::initializer_list<const char*> known,
                const std::string& what) const;
  /// The `[expect]` table.
  Expectation expectOf(const toml::node& node) const;
  /// The value of a list key of `[expect]` (`betti`): non-negative integers.
  std::vector<long> expectList(const std::string& key, const toml::node& value) const;
  /// Shortest round-trip text of a double.
  static std::string format(double v);

  const std::string& text() const { return text_; }
  /// "problem 'NAME': " once the name is known, else empty.
  std::string prefix() const { return problem_.empty() ? "" : "problem '" + problem_ + "': "; }
  const std::string& file() const { return file_; }

 private:
  const std::string& text_;
  const std::string& file_;
  std::string problem_;
};

/// Builds an application problem (paper Sec. 3; `application = "NAME"` in the file) from its
/// parsed document; throws InputError. The applications layer supplies it
/// (applications/load.hpp).
using ApplicationBuilder = Problem (*)(const toml::table& root, TomlReader& reader);

/// Parses TOML text (`file` names it in messages); a syntax error is an InputError at its line
/// and column. The problem reader, the experiment runner and the report share it.
toml::table parseTomlText(const std::string& text, const std::string& file);

/// Parses and validates problem text (`file` is used in messages); throws InputError. A file
/// with an `application` key is built by `applications`; without one (null) it is refused.
Problem parseProblemWith(const std::string& text, const std::string& file,
                         ApplicationBuilder applications);

}  // namespace ndc
