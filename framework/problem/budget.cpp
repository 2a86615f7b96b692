#include "framework/problem/budget.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string_view>

#if defined(__SANITIZE_ADDRESS__)
#define NDC_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NDC_ADDRESS_SANITIZER 1
#endif
#endif

namespace ndc {
namespace {

/// The control group's memory limit (cgroup v2 `memory.max`, v1 `memory.limit_in_bytes`), if
/// there is one.
std::optional<std::uint64_t> cgroupLimit() {
  for (const char* file :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(file);
    std::string text;
    if (!(in >> text) || text == "max") continue;
    try {
      const unsigned long long value = std::stoull(text);
      // v1 reports "no limit" as a huge number.
      if (value > 0 && value < (1ull << 60)) return value;
    } catch (const std::exception&) {
    }
  }
  return std::nullopt;
}

}  // namespace

std::uint64_t defaultMemoryBudget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  double total = pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page)
                                       : 4.0 * (1ull << 30);
  if (const auto limit = cgroupLimit()) total = std::min(total, static_cast<double>(*limit));
  return static_cast<std::uint64_t>(kDefaultMemoryShare * total);
}

namespace {

/// C(n, k): the choices of k fixed axes of a minimal m-face.
double faceChoices(int n, int k) {
  double choices = 1;
  for (int i = 0; i < k; ++i) choices = choices * (n - i) / (i + 1);
  return choices;
}

}  // namespace

double workPerCell(const Problem& problem) {
  double work = 0;
  for (const Expression& e : problem.equations) {
    double coefficients = 1, span = 0;
    for (int d : e.degrees()) {
      coefficients *= d + 1.0;
      span += d + 1.0;
    }
    // Without a dense form (densityFree) the connection evaluates the quadratic form: O(n^2)
    // per equation and box (8 n^2 matches the circles in R^10..R^16, docs/performance.md).
    const double n = static_cast<double>(problem.n());
    work += densityFree(e) ? std::min(coefficients * span, 8 * n * n) : coefficients * span;
  }
  // k >= 3: the crossing connection solves the C(n, k) minimal m-faces a cell owns, each a
  // square system (measured about 4,000 units per face choice: 3-spheres in R^4, S^1 x S^2 in
  // R^5, the flat 3-torus in R^6, docs/crossing.md "Any k").
  const int k = problem.k();
  if (k >= 3) work += 4000 * faceChoices(problem.n(), k);
  return work;
}

double bytesPerSolutionCell(int n, int k, const std::string& scalar, unsigned precisionBits) {
  // Measured peak RSS per solution cell (torus, spheres, circles and tori in R^2..R^8, depths
  // where the cells dominate): 330-600 bytes in double for n <= 6, growing with n; the model
  // stays above every measurement. k enters through the simplices per cell.
  double bytes = 256.0 + 96.0 * n + 64.0 * k;
  // k >= 3: the crossing connection keeps each of the cell's C(n, k) minimal m-faces (its key,
  // corner, solution) and the k! simplices of the crossed ones (measured 4-15 KB per cell for
  // C(n, k) = 4..20).
  if (k >= 3) bytes += 750.0 * faceChoices(n, k);
  // An MPFR number is a 32-byte header and its limbs, plus allocator overhead: measured 2.1x
  // double at 128 bits.
  if (scalar == "mpfr") bytes *= 1.5 + precisionBits / 128.0;
  return bytes;
}

double baseRunBytes(int n) { return (16.0 + 0.5 * n) * (1 << 20); }

std::optional<std::uint64_t> parseByteSize(const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (!std::isfinite(value) || value <= 0 || !std::isdigit(static_cast<unsigned char>(text[0])))
    return std::nullopt;
  std::string_view unit = std::string_view(text).substr(used);
  double scale = 1;
  const std::string_view prefixes = "KMGT";
  const auto at = unit.empty() ? std::string_view::npos
                               : prefixes.find(static_cast<char>(std::toupper(unit.front())));
  if (at != std::string_view::npos) {
    scale = std::ldexp(1.0, 10 * static_cast<int>(at + 1));
    unit.remove_prefix(1);
    if (unit != "" && unit != "B" && unit != "iB") return std::nullopt;
  } else if ((unit != "" && unit != "B") || value != std::floor(value)) {
    return std::nullopt;  // an unknown unit, or a fraction of a byte
  }
  const double bytes = value * scale;
  if (bytes < (1 << 20) || bytes > std::ldexp(1.0, 60)) return std::nullopt;
  return static_cast<std::uint64_t>(bytes);
}

std::string formatBytes(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int unit = 0;
  while (bytes >= 1024 && unit < 6) {
    bytes /= 1024;
    ++unit;
  }
  char text[48];
  std::snprintf(text, sizeof text, unit == 0 || bytes >= 100 ? "%.0f %s" : "%.1f %s", bytes,
                units[unit]);
  return text;
}

void limitAddressSpace(std::uint64_t bytes) {
#ifndef NDC_ADDRESS_SANITIZER
  // Slack for what is mapped but not resident: the program and its libraries, thread stacks
  // and the allocator's arenas.
  const rlim_t wanted = static_cast<rlim_t>(bytes) + (rlim_t{1} << 30);
  struct rlimit current {};
  if (::getrlimit(RLIMIT_AS, &current) != 0) return;
  if (current.rlim_cur != RLIM_INFINITY && current.rlim_cur <= wanted) return;
  struct rlimit next = current;
  next.rlim_cur = wanted;
  ::setrlimit(RLIMIT_AS, &next);
#else
  (void)bytes;
#endif
}

}  // namespace ndc
