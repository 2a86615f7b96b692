// Memory budgets (framework/problem/budget.hpp): sizes as the command line spells them, and the
// model of the bytes a run needs per solution cell against what runs measure.
#include <catch2/catch.hpp>

#include "framework/problem/budget.hpp"

TEST_CASE("budget: --max-memory sizes", "[budget]") {
  using ndc::parseByteSize;
  CHECK(parseByteSize("512M") == 512ull << 20);
  CHECK(parseByteSize("512MB") == 512ull << 20);
  CHECK(parseByteSize("16GiB") == 16ull << 30);
  CHECK(parseByteSize("1.5g") == 3ull << 29);
  CHECK(parseByteSize("2T") == 2ull << 40);
  CHECK(parseByteSize("1048576") == 1ull << 20);
  CHECK(parseByteSize("1048576B") == 1ull << 20);
  // Not sizes, or out of range: below 1 MiB, above 2^60, fractions of a byte, other units.
  for (const char* bad : {"", "G", "-1G", "0", "1K", "1048575", "1e30", "2000000T", "1.5", "12X",
                          "1GG", "nan", "inf", " 1G", "1G "})
    CHECK_FALSE(parseByteSize(bad).has_value());
}

TEST_CASE("budget: byte counts for people", "[budget]") {
  CHECK(ndc::formatBytes(512) == "512 bytes");
  CHECK(ndc::formatBytes(30.0 * (1 << 20)) == "30.0 MiB");
  CHECK(ndc::formatBytes(55.2 * (1 << 30)) == "55.2 GiB");
  CHECK(ndc::formatBytes(883.0 * (1ull << 30)) == "883 GiB");
}

TEST_CASE("budget: the per-cell model stays above measured runs", "[budget]") {
  // Peak RSS per solution cell measured on Release builds (docs/input-limits.md, "Budgets"):
  // (n, k, scalar, bits, bytes).
  struct Measured {
    int n, k;
    const char* scalar;
    unsigned bits;
    double bytes;
  };
  for (const Measured& m : {Measured{3, 2, "double", 53, 518}, Measured{4, 2, "double", 53, 570},
                            Measured{3, 2, "double", 53, 476}, Measured{3, 1, "double", 53, 334},
                            Measured{5, 1, "double", 53, 311}, Measured{6, 1, "double", 53, 430},
                            Measured{2, 1, "double", 53, 337}, Measured{3, 2, "mpfr", 128, 1090}})
    CHECK(ndc::bytesPerSolutionCell(m.n, m.k, m.scalar, m.bits) >= m.bytes);
  // The default budget is a share of a real machine.
  CHECK(ndc::defaultMemoryBudget() > (64ull << 20));
}
