// JSON numbers (json.hpp): the recursive-descent reader behind flattenJsonNumbers.
#include "framework/util/json.hpp"

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace ndc {

namespace {

/// A recursive-descent reader of the JSON that summary.json holds, collecting numbers (or, with
/// `leaves`, every leaf with an empty text).
class JsonFlattener {
 public:
  explicit JsonFlattener(std::string_view text, bool leaves = false) : s_(text), leaves_(leaves) {}

  std::vector<std::pair<std::string, std::string>> run() {
    value("", 0);
    space();
    if (i_ != s_.size()) error("text after the JSON value");
    return std::move(out_);
  }

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
        // Escapes are kept loosely: only key names and skipped strings use them.
        out += s_[i_] == 'u' ? '?' : s_[i_];
        if (s_[i_] == 'u') i_ += 4;
        ++i_;
      } else {
        out += s_[i_++];
      }
    }
    if (i_ >= s_.size()) error("unterminated string");
    ++i_;
    return out;
  }
  void value(const std::string& path, int depth) {
    if (depth > 64) error("nested too deeply");
    space();
    if (i_ >= s_.size()) error("unexpected end");
    const char c = s_[i_];
    if (c == '{') {
      ++i_;
      if (take('}')) return leaf(path);
      do {
        space();
        const std::string key = string();
        expect(':');
        value(path.empty() ? key : path + "." + key, depth + 1);
      } while (take(','));
      expect('}');
    } else if (c == '[') {
      ++i_;
      if (take(']')) return leaf(path);
      int index = 0;
      do value(path + "." + std::to_string(index++), depth + 1);
      while (take(','));
      expect(']');
    } else if (c == '"') {
      string();
      leaf(path);
    } else if (s_.substr(i_, 4) == "true") {
      i_ += 4;
      leaf(path);
    } else if (s_.substr(i_, 5) == "false") {
      i_ += 5;
      leaf(path);
    } else if (s_.substr(i_, 4) == "null") {
      i_ += 4;
      out_.emplace_back(path, "");
    } else {
      const std::size_t start = i_;
      while (i_ < s_.size() && std::strchr("+-0123456789.eE", s_[i_])) ++i_;
      const std::string number(s_.substr(start, i_ - start));
      char* end = nullptr;
      if (number.empty()) error("unexpected character");
      std::strtod(number.c_str(), &end);
      if (end != number.c_str() + number.size()) error("bad number '" + number + "'");
      out_.emplace_back(path, number);
    }
  }

  /// Records a leaf that is not a number or null (only when collecting every leaf).
  void leaf(const std::string& path) {
    if (leaves_) out_.emplace_back(path, "");
  }

  std::string_view s_;
  bool leaves_;
  std::size_t i_ = 0;
  std::vector<std::pair<std::string, std::string>> out_;
};

}  // namespace

std::vector<std::pair<std::string, std::string>> flattenJsonNumbers(std::string_view json) {
  return JsonFlattener(json).run();
}

std::vector<std::string> jsonLeafPaths(std::string_view json) {
  std::vector<std::string> paths;
  for (auto& [path, text] : JsonFlattener(json, true).run()) paths.push_back(std::move(path));
  return paths;
}

}  // namespace ndc
