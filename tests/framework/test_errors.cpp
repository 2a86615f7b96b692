// The error helpers (framework/util/errors.hpp): the "did you mean" hint and the reasons of
// file errors.
#include <catch2/catch.hpp>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "framework/util/errors.hpp"

namespace fs = std::filesystem;

TEST_CASE("errors: did you mean names the nearest known name, or nothing", "[errors]") {
  const std::vector<std::string> options = {"--depth", "--max-depth", "--threads",
                                            "--out",   "--bounding",  "--jitter"};
  CHECK(ndc::didYouMean("--depht", options) == " (did you mean '--depth'?)");
  CHECK(ndc::didYouMean("-depth", options) == " (did you mean '--depth'?)");
  CHECK(ndc::didYouMean("--max-dpeth", options) == " (did you mean '--max-depth'?)");
  CHECK(ndc::didYouMean("--thread", options) == " (did you mean '--threads'?)");
  CHECK(ndc::didYouMean("--bound", options) == " (did you mean '--bounding'?)");
  // Too far from every name (more than a third of the word's letters), or too short to say.
  CHECK(ndc::didYouMean("--frobnicate", options).empty());
  CHECK(ndc::didYouMean("--x", options).empty());
  CHECK(ndc::didYouMean("--", options).empty());
  CHECK(ndc::didYouMean("anything", {}).empty());
  const std::vector<std::string> keys = {"name",   "description", "variables",
                                         "domain", "equations",   "expect"};
  CHECK(ndc::didYouMean("equatons", keys) == " (did you mean 'equations'?)");
  CHECK(ndc::didYouMean("Domain", keys) == " (did you mean 'domain'?)");
  CHECK(ndc::didYouMean("colour", keys).empty());
}

TEST_CASE("errors: a folder that cannot be made says why", "[errors]") {
  const fs::path base = fs::temp_directory_path() / "ndcontour-test-errors";
  fs::remove_all(base);
  fs::create_directories(base);
  const fs::path file = base / "a-file";
  std::ofstream(file) << "x";
  const auto message = [](const fs::path& dir) {
    try {
      ndc::createDirectories(dir, "output directory");
    } catch (const ndc::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(message(base / "new" / "nested").empty());
  CHECK(fs::is_directory(base / "new" / "nested"));
  CHECK(message(file) == file.string() + ": cannot create the output directory: Not a directory");
  CHECK(message(file / "below")
            .rfind(
                (file / "below").string() + ": cannot create the output directory: Not a directory",
                0) == 0);
  errno = ENOSPC;
  CHECK(ndc::failureReason() == "No space left on device");
  CHECK(ndc::failureReason(std::make_error_code(std::errc::permission_denied)) ==
        "Permission denied");
  fs::remove_all(base);
}
