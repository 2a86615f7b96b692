// Problem files (docs/contracts.md 4.1): reading, validation and error positions.
#include "framework/problem/problem.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "framework/numeric/scalar.hpp"
#include "framework/numeric/tape.hpp"
#include "framework/problem/expectation.hpp"
#include "framework/problem/toml_reader.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

namespace {

bool isIdentifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

/// Position in the file of byte `target` (0-based) of the decoded value of the TOML string
/// whose opening quote is at (line, column). Decodes escapes and multi-line strings so that an
/// expression column lands on the right character of the file; falls back to the quote.
std::pair<int, int> stringPosition(const std::string& text, int line, int column, int target) {
  // Find the byte offset of (line, column); toml++ counts columns in code points.
  std::size_t pos = 0;
  for (int l = 1; l < line && pos < text.size(); ++l) {
    pos = text.find('\n', pos);
    if (pos == std::string::npos) return {line, column};
    ++pos;
  }
  for (int c = 1; c < column && pos < text.size(); ++c) {
    ++pos;
    while (pos < text.size() && (static_cast<unsigned char>(text[pos]) & 0xC0) == 0x80) ++pos;
  }
  if (pos >= text.size() || (text[pos] != '"' && text[pos] != '\'')) return {line, column};

  const bool literal = text[pos] == '\'';
  const bool multi = text.compare(pos, 3, literal ? "'''" : "\"\"\"") == 0;
  int ln = line, col = column;
  auto advance = [&](std::size_t bytes) {
    for (std::size_t i = 0; i < bytes && pos < text.size(); ++i, ++pos) {
      const unsigned char c = static_cast<unsigned char>(text[pos]);
      if (c == '\n') {
        ++ln;
        col = 1;
      } else if ((c & 0xC0) != 0x80) {
        ++col;
      }
    }
  };
  advance(multi ? 3 : 1);
  // A multi-line string drops a newline right after its opening delimiter.
  if (multi && text.compare(pos, 1, "\n") == 0) advance(1);
  if (multi && text.compare(pos, 2, "\r\n") == 0) advance(2);

  int decoded = 0;
  while (pos < text.size() && decoded < target) {
    const char c = text[pos];
    if (!literal && c == '\\' && pos + 1 < text.size()) {
      const char e = text[pos + 1];
      if (e == 'u' || e == 'U') {
        // \uXXXX or \UXXXXXXXX: count the UTF-8 bytes of the code point.
        const std::size_t len = e == 'u' ? 4 : 8;
        unsigned long cp = std::strtoul(text.substr(pos + 2, len).c_str(), nullptr, 16);
        decoded += cp < 0x80 ? 1 : cp < 0x800 ? 2 : cp < 0x10000 ? 3 : 4;
        advance(2 + len);
      } else if (multi && (e == ' ' || e == '\t' || e == '\n' || e == '\r')) {
        // Line-ending backslash: it and the following whitespace decode to nothing.
        advance(1);
        while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) advance(1);
      } else {
        decoded += 1;
        advance(2);
      }
    } else {
      decoded += 1;
      advance(1);
    }
  }
  return {ln, col};
}

/// Validation of one parsed TOML document; every failure is an InputError at a position.
class Validator : public TomlReader {
 public:
  Validator(const std::string& text, const std::string& file, ApplicationBuilder applications)
      : TomlReader(text, file), applications_(applications) {}

  Problem run(const toml::table& root) {
    Problem p;
    p.path = file();

    // Application problems (paper, Sec. 3) have their own tables.
    if (const toml::node* application = root.get("application")) {
      if (!applications_) fail(*application, "application problems are not available here");
      return applications_(root, *this);
    }

    // Every top-level key must be known: a typo must not silently drop data.
    static const std::set<std::string> kKnown = {"name",   "description", "variables",
                                                 "domain", "equations",   "expect"};
    for (auto&& [key, node] : root)
      if (!kKnown.count(std::string(key.str())))
        fail(key.source(), "unknown key '" + std::string(key.str()) + "'" +
                               didYouMean(key.str(), {kKnown.begin(), kKnown.end()}) +
                               " (known: name, description, variables, domain, equations, "
                               "expect)");

    // name: required, [a-z0-9._-]+ so that it can name files and result ids.
    const toml::node& name = require(root, "name");
    p.name = stringOf(name, "name");
    if (!isProblemName(p.name)) fail(name, "name '" + p.name + "' must match [a-z0-9._-]+");
    setProblem(p.name);

    if (const toml::node* description = root.get("description"))
      p.description = stringOf(*description, "description");

    // variables: n >= 2 distinct identifiers.
    const toml::node& variables = require(root, "variables");
    const toml::array& vars = arrayOf(variables, "variables");
    std::set<std::string> seen;
    for (std::size_t i = 0; i < vars.size(); ++i) {
      const std::string v = stringOf(vars[i], "variables[" + std::to_string(i) + "]");
      if (!isIdentifier(v))
        fail(vars[i], "variable '" + v + "' is not an identifier ([A-Za-z_][A-Za-z0-9_]*)");
      if (!seen.insert(v).second) fail(vars[i], "variable '" + v + "' is listed twice");
      p.variables.push_back(v);
    }
    if (p.variables.size() < 2)
      fail(variables,
           "a problem needs at least 2 variables, got " + std::to_string(p.variables.size()));
    const int n = p.n();

    // domain: one finite [lo, hi] per variable with lo < hi.
    const toml::node& domain = require(root, "domain");
    const toml::array& ranges = arrayOf(domain, "domain");
    if (static_cast<int>(ranges.size()) != n)
      fail(domain, "domain has " + std::to_string(ranges.size()) + " intervals but there are " +
                       std::to_string(n) + " variables");
    for (int j = 0; j < n; ++j) {
      const std::string what = "domain of '" + p.variables[j] + "'";
      const toml::array* r = ranges[j].as_array();
      if (!r || r->size() != 2) fail(ranges[j], what + " must be an array [lo, hi] of 2 numbers");
      const double lo = numberOf((*r)[0], what + ": lo");
      const double hi = numberOf((*r)[1], what + ": hi");
      if (!(lo < hi))
        fail(ranges[j], what + " is empty or inverted: lo = " + format(lo) +
                            " is not less than hi = " + format(hi));
      if (!std::isfinite(hi - lo))
        fail(ranges[j], what + " is too wide: hi - lo = " + format(hi) + " - " + format(lo) +
                            " overflows a double");
      p.domain.lo.push_back(lo);
      p.domain.hi.push_back(hi);
    }

    // equations: 1 <= m <= n-1 polynomial expressions in the variables.
    const toml::node& equations = require(root, "equations");
    const toml::array& eqs = arrayOf(equations, "equations");
    const int m = static_cast<int>(eqs.size());
    if (m < 1 || m > n - 1)
      fail(equations, "there must be between 1 and n-1 = " + std::to_string(n - 1) +
                          " equations for n = " + std::to_string(n) + " variables, got " +
                          std::to_string(m));
    for (int i = 0; i < m; ++i) p.equations.push_back(parseEquation(eqs[i], i, p.variables));

    if (const toml::node* expect = root.get("expect")) p.expect = expectOf(*expect);
    return p;
  }

 private:
  Expression parseEquation(const toml::node& node, int i,
                           const std::vector<std::string>& variables) const {
    const std::string what = "equation " + std::to_string(i + 1);
    const std::string source = stringOf(node, what);
    try {
      Expression e = Expression::parse(source, variables);
      // A constant equation is either everywhere or nowhere zero: never a manifold.
      bool constant = true;
      for (int d : e.degrees()) constant = constant && d == 0;
      if (constant) fail(node, what + " is constant (it uses no variable): '" + source + "'");
      // The Bernstein form has prod (d_j + 1) coefficients per box and level: refuse sizes that
      // would exhaust memory instead of allocating without bound. An equation of total degree
      // at most 2 needs no dense form (densityFree): the default strategies enclose it by its
      // quadratic form, in time polynomial in n.
      const double coefficients = denseCoefficients(e);
      if (coefficients > kMaxCoefficients && !densityFree(e)) {
        std::ostringstream message;
        message << what << " needs " << coefficients << " Bernstein coefficients (the product of "
                << "its degrees + 1); at most " << kMaxCoefficients << " are supported";
        fail(node, message.str());
      }
      const std::vector<int> degrees = e.degrees();
      for (std::size_t j = 0; j < degrees.size(); ++j) {
        if (degrees[j] > kMaxDegree)
          fail(node, what + " has degree " + std::to_string(degrees[j]) + " in '" + variables[j] +
                         "'; at most " + std::to_string(kMaxDegree) + " is supported");
      }
      // Halving a box costs about (coefficients x degree) operations per equation along an axis
      // (de Casteljau), and a run halves thousands of boxes: bound the time as well as memory.
      const double work = coefficients * *std::max_element(degrees.begin(), degrees.end());
      if (work > kMaxSubdivisionWork && !densityFree(e)) {
        std::ostringstream message;
        message << what << " costs about " << work << " operations per subdivision step ("
                << coefficients << " Bernstein coefficients times its largest degree); at most "
                << kMaxSubdivisionWork << " are supported";
        fail(node, message.str());
      }
      return e;
    } catch (const ExpressionError& error) {
      // Map the expression column to the file through the string's source position.
      const auto [line, column] = stringPosition(text(), static_cast<int>(node.source().begin.line),
                                                 static_cast<int>(node.source().begin.column),
                                                 std::max(0, error.column() - 1));
      throw InputError::at(file(), line, column, prefix() + what + ": " + error.what());
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& error) {
      fail(node, what + ": " + error.what());
    }
  }

  ApplicationBuilder applications_;
};

}  // namespace

/// A human name for the type of a TOML node, for "wrong type" messages.
std::string tomlTypeName(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    default:
      return "nothing";
  }
}

void TomlReader::fail(const toml::source_region& where, const std::string& message) const {
  throw InputError::at(file_, static_cast<int>(where.begin.line),
                       static_cast<int>(where.begin.column), prefix() + message);
}
void TomlReader::fail(const toml::node& node, const std::string& message) const {
  fail(node.source(), message);
}
void TomlReader::fail(const std::string& message) const {
  throw InputError::at(file_, 0, 0, prefix() + message);
}

const toml::node& TomlReader::require(const toml::table& table, const std::string& key) const {
  const toml::node* node = table.get(key);
  if (!node) fail("missing required key '" + key + "'");
  return *node;
}

std::string TomlReader::stringOf(const toml::node& node, const std::string& what) const {
  if (const auto* s = node.as_string()) return s->get();
  fail(node, what + " must be a string, not " + tomlTypeName(node));
}

const toml::array& TomlReader::arrayOf(const toml::node& node, const std::string& what) const {
  if (const auto* a = node.as_array()) return *a;
  fail(node, what + " must be an array, not " + tomlTypeName(node));
}

const toml::table& TomlReader::tableOf(const toml::node& node, const std::string& what) const {
  if (const auto* t = node.as_table()) return *t;
  fail(node, what + " must be a table, not " + tomlTypeName(node));
}

double TomlReader::numberOf(const toml::node& node, const std::string& what) const {
  double v;
  if (const auto* i = node.as_integer())
    v = static_cast<double>(i->get());
  else if (const auto* f = node.as_floating_point())
    v = f->get();
  else
    fail(node, what + " must be a number, not " + tomlTypeName(node));
  // TOML allows inf and nan; geometry and domains need finite values.
  if (!std::isfinite(v)) fail(node, what + " must be finite, not " + format(v));
  return v;
}

long TomlReader::integerOf(const toml::node& node, const std::string& what, long lo,
                           long hi) const {
  const auto* i = node.as_integer();
  if (!i) fail(node, what + " must be an integer, not " + tomlTypeName(node));
  if (i->get() < lo || i->get() > hi)
    fail(node, what + " must be between " + std::to_string(lo) + " and " + std::to_string(hi) +
                   ", got " + std::to_string(i->get()));
  return static_cast<long>(i->get());
}

void TomlReader::onlyKeys(const toml::table& table, std::initializer_list<const char*> known,
                          const std::string& what) const {
  for (auto&& [key, node] : table) {
    bool ok = false;
    for (const char* k : known) ok = ok || key.str() == k;
    if (ok) continue;
    std::string list;
    for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    fail(key.source(), "unknown key '" + std::string(key.str()) + "' in " + what +
                           didYouMean(key.str(), {known.begin(), known.end()}) +
                           " (known: " + list + ")");
  }
}

std::string TomlReader::format(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::vector<long> TomlReader::expectList(const std::string& key, const toml::node& value) const {
  // A list key (`betti`): an array of non-negative integers, one per dimension 0 .. k.
  const toml::array* array = value.as_array();
  if (!array || array->empty())
    fail(value,
         "expect." + key + " must be a non-empty array of integers, not " + tomlTypeName(value));
  std::vector<long> list;
  for (const toml::node& element : *array) {
    const auto* i = element.as_integer();
    if (!i || i->get() < 0)
      fail(element, "expect." + key + " must hold non-negative integers (b_0 .. b_k)");
    list.push_back(static_cast<long>(i->get()));
  }
  return list;
}

Expectation TomlReader::expectOf(const toml::node& node) const {
  const toml::table* table = node.as_table();
  if (!table) fail(node, "expect must be a table, not " + tomlTypeName(node));
  Expectation expect;
  for (auto&& [key, value] : *table) {
    const std::string k(key.str());
    // An unknown key is an error, as at the top level: a misspelt expectation would otherwise
    // never be checked.
    if (std::find(kExpectKeys.begin(), kExpectKeys.end(), k) == kExpectKeys.end()) {
      std::string known;
      for (std::string_view name : kExpectKeys)
        known += (known.empty() ? "" : ", ") + std::string(name);
      fail(key.source(), "unknown key '" + k + "' in expect" +
                             didYouMean(k, {kExpectKeys.begin(), kExpectKeys.end()}) +
                             " (known: " + known + ")");
    }
    if (std::find(kExpectListKeys.begin(), kExpectListKeys.end(), k) != kExpectListKeys.end()) {
      expect.lists[k] = expectList(k, value);
      continue;
    }
    const auto* i = value.as_integer();
    if (!i) fail(value, "expect." + k + " must be an integer, not " + tomlTypeName(value));
    if (k == "components")
      expect.components = i->get();
    else if (k == "euler_characteristic")
      expect.eulerCharacteristic = i->get();
    else
      expect.other[k] = i->get();
  }
  return expect;
}

bool densityFree(const Expression& equation) {
  return equation.tape().totalDegree(3) <= 2 && equation.tape().leaves().empty();
}

double denseCoefficients(const Expression& equation) {
  double coefficients = 1;
  for (int d : equation.degrees()) coefficients *= d + 1.0;
  return coefficients;
}

bool isProblemName(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-'))
      return false;
  return true;
}

void checkTextEncoding(const std::string& text, const std::string& file) {
  int line = 1, column = 1;
  const auto bad = [&](const std::string& what) {
    throw InputError::at(file, line, column, what + " (the file must be UTF-8 text)");
  };
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t size = text.size();
  for (std::size_t i = 0; i < size;) {
    const unsigned char c = s[i];
    if (c < 0x80) {
      if (c < 0x20 && c != '\t' && c != '\n' && c != '\r') {
        char code[8];
        std::snprintf(code, sizeof code, "0x%02x", static_cast<unsigned>(c));
        bad(std::string("control character ") + code);
      }
      if (c == 0x7f) bad("control character 0x7f");
      ++i;
      if (c == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
      continue;
    }
    // A multi-byte sequence: its length, the smallest code point it may encode, the value.
    const int length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc0 ? 2 : 0;
    if (length == 0 || c > 0xf4) bad("invalid UTF-8 byte");
    if (i + length > size) bad("truncated UTF-8 sequence");
    std::uint32_t value = c & (0x7f >> length);
    for (int b = 1; b < length; ++b) {
      if ((s[i + b] & 0xc0) != 0x80) bad("invalid UTF-8 sequence");
      value = (value << 6) | (s[i + b] & 0x3f);
    }
    const std::uint32_t smallest = length == 2 ? 0x80 : length == 3 ? 0x800 : 0x10000;
    if (value < smallest) bad("overlong UTF-8 sequence");
    if (value > 0x10ffff || (value >= 0xd800 && value <= 0xdfff))
      bad("UTF-8 sequence of an invalid code point");
    if (value >= 0x80 && value < 0xa0) bad("control character (C1)");
    i += static_cast<std::size_t>(length);
    ++column;
  }
}

std::string readInputFile(const std::filesystem::path& file, const std::string& what) {
  const std::string name = file.string();
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw InputError::at(name, 0, 0, "cannot read the " + what + ": it is a directory");
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw InputError::at(name, 0, 0, "cannot read the " + what + ": " + std::strerror(errno));
  // In chunks, stopping one byte past the limit, so that an endless file (/dev/zero) ends here.
  std::string text;
  char chunk[1 << 16];
  while (text.size() <= kMaxFileBytes && in.read(chunk, sizeof chunk).gcount() > 0)
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw InputError::at(name, 0, 0, "cannot read the " + what + ": read error");
  if (text.size() > kMaxFileBytes)
    throw InputError::at(
        name, 0, 0,
        "the " + what + " is larger than " + std::to_string(kMaxFileBytes >> 20) + " MiB");
  return text;
}

void checkKeyNesting(const std::string& text, const std::string& file) {
  enum class State { kCode, kComment, kBasic, kLiteral, kMultiBasic, kMultiLiteral };
  State state = State::kCode;
  int line = 1, column = 0, dots = 0;
  const auto at = [&](std::size_t i, const char* s) { return text.compare(i, 3, s) == 0; };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      column = 0;
    } else if ((static_cast<unsigned char>(c) & 0xC0) != 0x80) {
      ++column;  // a character, not a UTF-8 continuation byte
    }
    switch (state) {
      case State::kComment:
        if (c == '\n') state = State::kCode;
        break;
      case State::kBasic:
        if (c == '\\') ++i;
        if (c == '"' || c == '\n') state = State::kCode;
        break;
      case State::kLiteral:
        if (c == '\'' || c == '\n') state = State::kCode;
        break;
      case State::kMultiBasic:
        if (c == '\\') ++i;
        if (at(i, "\"\"\"")) state = State::kCode, i += 2;
        break;
      case State::kMultiLiteral:
        if (at(i, "'''")) state = State::kCode, i += 2;
        break;
      case State::kCode:
        // A chain of bare or quoted keys joined by dots is one dotted key: count its dots. A
        // value has at most one dot outside strings (1.5); anything else ends the chain.
        if (c == '.') {
          if (++dots > kMaxKeyDots)
            throw InputError::at(file, line, column,
                                 "key nested too deeply: more than " + std::to_string(kMaxKeyDots) +
                                     " dotted parts");
        } else if (at(i, "\"\"\"")) {
          state = State::kMultiBasic, i += 2;
        } else if (at(i, "'''")) {
          state = State::kMultiLiteral, i += 2;
        } else if (c == '"') {
          state = State::kBasic;
        } else if (c == '\'') {
          state = State::kLiteral;
        } else if (c == '#') {
          state = State::kComment, dots = 0;
        } else if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ||
                     c == ' ' || c == '\t')) {
          dots = 0;
        }
        break;
    }
  }
}

void checkTomlText(const std::string& text, const std::string& file) {
  checkTextEncoding(text, file);
  checkKeyNesting(text, file);
}

Problem parseProblemWith(const std::string& text, const std::string& file,
                         ApplicationBuilder applications) {
  checkTomlText(text, file);
  return Validator(text, file, applications).run(parseTomlText(text, file));
}

toml::table parseTomlText(const std::string& text, const std::string& file) {
  try {
    return toml::parse(text, std::string_view(file));
  } catch (const toml::parse_error& error) {
    throw InputError::at(file, static_cast<int>(error.source().begin.line),
                         static_cast<int>(error.source().begin.column),
                         "TOML syntax error: " + std::string(error.description()));
  }
}

template <class S>
Box<S> Problem::domainAs() const {
  return toScalar<S>(domain);
}

template Box<double> Problem::domainAs<double>() const;
template Box<Mpfr> Problem::domainAs<Mpfr>() const;

}  // namespace ndc
