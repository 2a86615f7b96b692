#include "framework/util/errors.hpp"

namespace ndc {

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
