// `ndcontour info`: a readable description of a problem file.
#include <charconv>
#include <cstdint>
#include <limits>

#include "experiments/cli/commands.hpp"

namespace ndc::cli {

namespace {

/// Shortest text that reads back to the same double.
std::string number(double v) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

}  // namespace

void printInfo(const Problem& p, std::ostream& out) {
  out << "name: " << p.name << '\n';
  if (!p.description.empty()) out << "description: " << p.description << '\n';
  out << "file: " << p.path << '\n';
  out << "n: " << p.n() << '\n' << "k: " << p.k() << '\n' << "m: " << p.m() << '\n';

  out << "variables:\n";
  for (int j = 0; j < p.n(); ++j)
    out << "  " << p.variables[j] << " in [" << number(p.domain.lo[j]) << ", "
        << number(p.domain.hi[j]) << "]\n";

  out << "equations:\n";
  for (int i = 0; i < p.m(); ++i) {
    const Expression& e = p.equations[i];
    // A generated equation can be megabytes long: its head, and its length.
    constexpr std::size_t kShown = 400;
    out << "  " << i + 1 << ": ";
    if (e.text().size() <= kShown)
      out << e.text();
    else
      out << e.text().substr(0, kShown) << " ... (" << e.text().size() << " characters)";
    out << '\n';
    if (e.writtenInstructions() != e.tape().ops().size())
      out << "     program: " << e.tape().ops().size() << " instructions (like terms collected; "
          << e.writtenInstructions() << " as written)\n";
    out << "     degrees:";
    // The tensor-product Bernstein patch has prod(d_j + 1) coefficients.
    const std::vector<int> degrees = e.degrees();
    std::uint64_t count = 1;
    bool overflow = false;
    for (int j = 0; j < p.n(); ++j) {
      out << ' ' << p.variables[j] << ' ' << degrees[j];
      overflow = overflow || __builtin_mul_overflow(count, std::uint64_t(degrees[j]) + 1, &count);
    }
    out << "\n     coefficients: ";
    if (overflow)
      out << "more than " << std::numeric_limits<std::uint64_t>::max();
    else
      out << count;
    out << '\n';
  }

  const Expectation& x = p.expect;
  if (!x.empty()) {
    out << "expect:\n";
    if (x.components) out << "  components: " << *x.components << '\n';
    if (x.eulerCharacteristic) out << "  euler_characteristic: " << *x.eulerCharacteristic << '\n';
    for (const auto& [key, value] : x.other) out << "  " << key << ": " << value << '\n';
    for (const auto& [key, values] : x.lists) {
      out << "  " << key << ":";
      for (const long value : values) out << ' ' << value;
      out << '\n';
    }
  }
}

}  // namespace ndc::cli
