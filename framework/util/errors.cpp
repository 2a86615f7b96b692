#include "framework/util/errors.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

namespace ndc {

namespace {

/// Edit distance between a and b counting a swap of neighbours as one edit (optimal string
/// alignment), case-insensitive; both are short (option and key names).
std::size_t editDistance(std::string_view a, std::string_view b) {
  const auto same = [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) ==
           std::tolower(static_cast<unsigned char>(y));
  };
  const std::size_t w = b.size() + 1;
  std::vector<std::size_t> d((a.size() + 1) * w);
  for (std::size_t i = 0; i <= a.size(); ++i) d[i * w] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t& here = d[i * w + j];
      here = std::min({d[(i - 1) * w + j] + 1, d[i * w + j - 1] + 1,
                       d[(i - 1) * w + j - 1] + (same(a[i - 1], b[j - 1]) ? 0 : 1)});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
        here = std::min(here, d[(i - 2) * w + j - 2] + 1);
    }
  }
  return d.back();
}

}  // namespace

std::string failureReason(const std::error_code& error) {
  if (error) return error.message();
  return errno != 0 ? std::strerror(errno) : "unknown reason";
}

void createDirectories(const std::filesystem::path& dir, std::string_view what) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (!error && std::filesystem::is_directory(dir, error)) return;
  const std::string reason = error ? error.message() : "a file of that name is in the way";
  throw InputError(
      oneLine(dir.string() + ": cannot create the " + std::string(what) + ": " + reason));
}

std::string didYouMean(std::string_view word, const std::vector<std::string>& known) {
  // Compared without leading dashes, so that "-depth" finds "--depth".
  const auto bare = [](std::string_view s) {
    return s.substr(std::min(s.find_first_not_of('-'), s.size()));
  };
  const std::string_view w = bare(word);
  if (w.empty()) return "";
  const std::size_t limit = std::max<std::size_t>(1, w.size() / 3);
  const std::string* best = nullptr;
  std::size_t bestDistance = limit + 1;
  for (const std::string& name : known) {
    const std::string_view n = bare(name);
    const std::size_t d = n.starts_with(w) && w.size() >= 3 ? 1 : editDistance(w, n);
    if (d < bestDistance) best = &name, bestDistance = d;
  }
  return best ? " (did you mean '" + *best + "'?)" : "";
}

std::string oneLine(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

InputError InputError::at(const std::string& file, int line, int column,
                          const std::string& message) {
  // Appends piecewise (GCC 12 warns falsely on `":" + std::to_string(...)`).
  std::string text = file;
  if (line > 0) {
    text.append(":").append(std::to_string(line));
    if (column > 0) text.append(":").append(std::to_string(column));
  }
  text.append(": ").append(message);
  return InputError(oneLine(std::move(text)));
}

}  // namespace ndc
