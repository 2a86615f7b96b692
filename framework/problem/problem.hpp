/// \file problem.hpp
/// Problem files (docs/contracts.md 4.1): TOML with variables, a box domain and equations.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/problem/expression.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

/// Optional ground truth of a problem (`[expect]`).
struct Expectation {
  std::optional<long> components;
  std::optional<long> eulerCharacteristic;
  /// Every other integer key of `[expect]`, by name (e.g. `genus`, `boundary_edges`).
  std::map<std::string, long> other;
  /// The list keys of `[expect]` (`betti`, `betti_z2`), by name.
  std::map<std::string, std::vector<long>> lists;
  /// Whether the table has no key at all.
  bool empty() const {
    return !components && !eulerCharacteristic && other.empty() && lists.empty();
  }
};

struct ApplicationData;  // framework/problem/application.hpp

/// A validated problem: `m = n - k` polynomial constraints in n variables on a box.
struct Problem {
  std::string path;  ///< the file it came from
  std::string name;
  std::string description;
  std::vector<std::string> variables;
  Box<double> domain;
  std::vector<Expression> equations;
  Expectation expect;
  /// Application problems (paper Sec. 3): image map, input geometry; null for plain problems.
  std::shared_ptr<const ApplicationData> application;
  /// Sub-boxes of the domain on each of which every equation is one polynomial (the patches of
  /// B-spline input after Bezier extraction). Each must be a cell of the grid at `rootLevel`
  /// (2^rootLevel cells per axis). Empty: the whole domain is one patch.
  std::vector<Box<double>> roots;
  int rootLevel = 0;

  int n() const { return static_cast<int>(variables.size()); }
  int m() const { return static_cast<int>(equations.size()); }
  /// Manifold dimension k = n - m.
  int k() const { return n() - m(); }
  /// The domain in scalar S.
  template <class S>
  Box<S> domainAs() const;
};

/// Largest number of Bernstein coefficients (product of degree + 1 over the variables) an
/// equation may have; larger ones are rejected as bad input rather than exhausting memory,
/// unless the equation needs no dense form (densityFree).
inline constexpr double kMaxCoefficients = 1e6;
/// Whether the default strategies handle `equation` without its dense Bernstein form: total
/// degree at most 2 and no patch leaf (the linearized bounding and the crossing connection
/// enclose it by its quadratic form; docs/performance.md, "Without dense forms"). Such an
/// equation may exceed kMaxCoefficients; the `bernstein` bounding refuses it then.
bool densityFree(const Expression& equation);
/// The product of (degree + 1) over the variables: the size of `equation`'s dense Bernstein form.
double denseCoefficients(const Expression& equation);
/// The largest degree of an equation in one variable: building the Bernstein form of a
/// degree-d power costs about d^2 operations per coefficient, so past this a file could keep
/// the tool busy for hours within the coefficient cap (x^10000, a product of 20,000 factors).
inline constexpr int kMaxDegree = 1000;
/// The largest cost of halving an equation's Bernstein form along one axis (its coefficients
/// times its largest degree, about 10 ms): within the caps above, `(x*y)^500 - z` would cost
/// 1.3e8 operations per box, hours for a run of thousands of boxes. The examples need at most
/// 3e4.
inline constexpr double kMaxSubdivisionWork = 1e7;

/// Whether `s` is a valid problem or experiment name: `[a-z0-9._-]+` (it names files and
/// result folders).
bool isProblemName(const std::string& s);

/// The largest problem or experiment file that is read (16 MiB).
inline constexpr std::size_t kMaxFileBytes = std::size_t{16} << 20;

/// The whole content of a problem or experiment file (`what` names it in messages: "problem
/// file"); throws InputError when it cannot be read or is larger than kMaxFileBytes (so
/// `/dev/zero` is refused, not read without bound).
std::string readInputFile(const std::filesystem::path& file, const std::string& what);

/// Throws InputError at the line and column of the first byte of `text` that is not valid
/// UTF-8 (overlong forms, surrogates and code points above U+10FFFF included) or that is a
/// control character other than tab, line feed and carriage return. Run before the TOML parser
/// sees the text, and echoes no offending byte.
void checkTextEncoding(const std::string& text, const std::string& file);

/// The most dotted parts a TOML key may have (`a.b.c = 1` has 2): toml++ builds one nested
/// table per part recursively, and 50,000 of them overflowed the stack.
inline constexpr int kMaxKeyDots = 64;

/// Throws InputError at the line and column of the first dot past kMaxKeyDots in a dotted key
/// or table header (dots inside strings and comments do not count). Run before the TOML parser
/// sees the text.
void checkKeyNesting(const std::string& text, const std::string& file);

/// Everything checked before the TOML parser sees a file's text: checkTextEncoding, then
/// checkKeyNesting.
void checkTomlText(const std::string& text, const std::string& file);

// Reading a problem file (equations or an application) is loadProblem and parseProblem in
// applications/load.hpp: the applications layer builds application problems.

}  // namespace ndc
