// The layers of the source tree (docs/architecture.md "Layers"): core <- strategies <- pipeline
// <- applications <- experiments <- cli. Checked from the include lines: every quoted include is
// spelled from the repository root (the one include root) and names a file of the same or a lower
// layer.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "tests/test_process.hpp"

namespace {

namespace fs = std::filesystem;

/// The layers, lowest first, by the directory that holds each.
const std::vector<std::string> kLayerDirs = {"framework/core/",     "strategies/",
                                             "framework/pipeline/", "framework/applications/",
                                             "experiments/",        "framework/cli/"};

/// The layer of a path relative to the root, or -1 outside every layer (tests/ and so on).
int layerOf(const std::string& relative) {
  for (std::size_t i = 0; i < kLayerDirs.size(); ++i)
    if (relative.rfind(kLayerDirs[i], 0) == 0) return static_cast<int>(i);
  return -1;
}

/// One line per include that breaks the rules, for the sources under `root`: an include not
/// spelled from the root, or one that reaches a higher layer.
std::vector<std::string> layerViolations(const fs::path& root) {
  static const std::regex include(R"(^\s*#\s*include\s+"([^"]+)\")");
  std::vector<std::string> violations;
  for (const char* top : {"framework", "strategies", "experiments", "tests"}) {
    if (!fs::exists(root / top)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".hpp" && ext != ".cpp" && ext != ".inl") continue;
      const std::string file = fs::relative(entry.path(), root).generic_string();
      if (file.rfind("tests/corpus/", 0) == 0) continue;
      std::ifstream in(entry.path());
      std::string line;
      for (int number = 1; std::getline(in, line); ++number) {
        std::smatch m;
        if (!std::regex_search(line, m, include)) continue;
        const std::string target = m[1];
        const std::string where = file + ":" + std::to_string(number) + ": \"" + target + "\"";
        if (!fs::exists(root / target))
          violations.push_back(where + " is not a path from the repository root");
        else if (layerOf(file) >= 0 && layerOf(target) > layerOf(file))
          violations.push_back(where + " is a higher layer");
      }
    }
  }
  return violations;
}

void writeFile(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

}  // namespace

TEST_CASE("layers: no source includes a higher layer, all spell paths from the root", "[layers]") {
  const std::vector<std::string> violations = layerViolations(NDC_SOURCE_DIR);
  for (const std::string& v : violations) UNSCOPED_INFO(v);
  CHECK(violations.empty());
}

TEST_CASE("layers: the check finds an upward include and a path not from the root", "[layers]") {
  const ndc::test::ScratchDir dir("layers");
  writeFile(dir.path() / "framework/core/a.hpp", "#include \"framework/pipeline/p.hpp\"\n");
  writeFile(dir.path() / "framework/pipeline/p.hpp", "#include \"framework/core/a.hpp\"\n");
  writeFile(dir.path() / "strategies/s/s.cpp", "#include \"a.hpp\"\n#include <vector>\n");
  writeFile(dir.path() / "framework/cli/c.cpp",
            "#include \"framework/pipeline/p.hpp\"\n#include \"strategies/s/s.cpp\"\n");
  const std::vector<std::string> violations = layerViolations(dir.path());
  REQUIRE(violations.size() == 2);
  CHECK(std::count_if(violations.begin(), violations.end(), [](const std::string& v) {
          return v.rfind("framework/core/a.hpp:1:", 0) == 0 &&
                 v.find("higher layer") != std::string::npos;
        }) == 1);
  CHECK(std::count_if(violations.begin(), violations.end(), [](const std::string& v) {
          return v.rfind("strategies/s/s.cpp:1:", 0) == 0 &&
                 v.find("not a path from the repository root") != std::string::npos;
        }) == 1);
}
