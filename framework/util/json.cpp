// JSON numbers (json.hpp): the recursive-descent reader behind flattenJsonNumbers.
#include "framework/util/json.hpp"

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace ndc {

namespace {

/// What a JsonFlattener keeps.
enum class Keep { numbers, paths, values };

/// A recursive-descent reader of the JSON that summary.json holds, collecting numbers
/// (Keep::numbers), every leaf with an empty text (Keep::paths) or every leaf with its value
/// (Keep::values).
class JsonFlattener {
 public:
  explicit JsonFlattener(std::string_view text, Keep keep = Keep::numbers)
      : s_(text), keep_(keep) {}

  std::vector<std::pair<std::string, std::string>> run() {
    value("", 0);
    space();
    if (i_ != s_.size()) error("text after the JSON value");
    return std::move(out_);
  }

  /// The kind of each leaf of run(), in order (Keep::values only).
  std::vector<JsonKind> kinds() const { return kinds_; }

 private:
  [[noreturn]] void error(const std::string& what) const {
    throw std::runtime_error("malformed JSON at byte " + std::to_string(i_) + ": " + what);
  }
  void space() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\r' || s_[i_] == '\t'))
      ++i_;
  }
  bool take(char c) {
    space();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!take(c)) error(std::string("expected '") + c + "'");
  }
  std::string string() {
    expect('"');
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') {
        if (++i_ >= s_.size()) break;
        escape(out);
      } else {
        out += s_[i_++];
      }
    }
    if (i_ >= s_.size()) error("unterminated string");
    ++i_;
    return out;
  }
  /// One escape after its backslash: the character it stands for, in UTF-8.
  void escape(std::string& out) {
    const char c = s_[i_++];
    switch (c) {
      case 'n':
        out += '\n';
        return;
      case 't':
        out += '\t';
        return;
      case 'r':
        out += '\r';
        return;
      case 'b':
        out += '\b';
        return;
      case 'f':
        out += '\f';
        return;
      case 'u':
        break;
      default:
        out += c;
        return;
    }
    if (i_ + 4 > s_.size()) error("bad \\u escape");
    const unsigned long code = std::strtoul(std::string(s_.substr(i_, 4)).c_str(), nullptr, 16);
    i_ += 4;
    // Code points of the Basic Multilingual Plane (a surrogate stays as it is read).
    if (code < 0x80) {
      out += static_cast<char>(code);
    } else if (code < 0x800) {
      out += static_cast<char>(0xC0 | (code >> 6));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
      out += static_cast<char>(0xE0 | (code >> 12));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    }
  }

  void value(const std::string& path, int depth) {
    if (depth > 64) error("nested too deeply");
    space();
    if (i_ >= s_.size()) error("unexpected end");
    const char c = s_[i_];
    if (c == '{') {
      ++i_;
      if (take('}')) return leaf(path, JsonKind::empty);
      do {
        space();
        const std::string key = string();
        expect(':');
        value(path.empty() ? key : path + "." + key, depth + 1);
      } while (take(','));
      expect('}');
    } else if (c == '[') {
      ++i_;
      if (take(']')) return leaf(path, JsonKind::empty);
      int index = 0;
      do value(path + "." + std::to_string(index++), depth + 1);
      while (take(','));
      expect(']');
    } else if (c == '"') {
      leaf(path, JsonKind::string, string());
    } else if (s_.substr(i_, 4) == "true") {
      i_ += 4;
      leaf(path, JsonKind::boolean, "true");
    } else if (s_.substr(i_, 5) == "false") {
      i_ += 5;
      leaf(path, JsonKind::boolean, "false");
    } else if (s_.substr(i_, 4) == "null") {
      i_ += 4;
      if (keep_ == Keep::values) return leaf(path, JsonKind::null);
      out_.emplace_back(path, "");
    } else {
      const std::size_t start = i_;
      while (i_ < s_.size() && std::strchr("+-0123456789.eE", s_[i_])) ++i_;
      const std::string number(s_.substr(start, i_ - start));
      char* end = nullptr;
      if (number.empty()) error("unexpected character");
      std::strtod(number.c_str(), &end);
      if (end != number.c_str() + number.size()) error("bad number '" + number + "'");
      if (keep_ == Keep::values) return leaf(path, JsonKind::number, number);
      out_.emplace_back(path, number);
    }
  }

  /// Records a leaf that is not a number or null (kept with Keep::paths and Keep::values).
  void leaf(const std::string& path, JsonKind kind, std::string text = {}) {
    if (keep_ == Keep::numbers) return;
    out_.emplace_back(path, keep_ == Keep::values ? std::move(text) : std::string());
    if (keep_ == Keep::values) kinds_.push_back(kind);
  }

  std::string_view s_;
  Keep keep_;
  std::vector<JsonKind> kinds_;
  std::size_t i_ = 0;
  std::vector<std::pair<std::string, std::string>> out_;
};

}  // namespace

std::vector<std::pair<std::string, std::string>> flattenJsonNumbers(std::string_view json) {
  return JsonFlattener(json).run();
}

std::vector<std::string> jsonLeafPaths(std::string_view json) {
  std::vector<std::string> paths;
  for (auto& [path, text] : JsonFlattener(json, Keep::paths).run())
    paths.push_back(std::move(path));
  return paths;
}

std::vector<JsonLeaf> jsonLeaves(std::string_view json) {
  JsonFlattener reader(json, Keep::values);
  auto leaves = reader.run();
  const std::vector<JsonKind> kinds = reader.kinds();
  std::vector<JsonLeaf> out;
  out.reserve(leaves.size());
  for (std::size_t i = 0; i < leaves.size(); ++i)
    out.push_back({std::move(leaves[i].first), std::move(leaves[i].second), kinds[i]});
  return out;
}

}  // namespace ndc
