// The layers of the source tree, as docs/architecture.md draws them ("Layers"): its table gives
// each source folder a level, and the test reads that table. Checked from the include lines: every
// quoted include is spelled from the repository root (the one include root) and names a file of
// the same or a lower level; every source file of the layered top-level folders lies in a folder
// of the table, and every folder of the table exists.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/test_process.hpp"

namespace {

namespace fs = std::filesystem;

/// The top-level folders whose sources are layered; tests/ is checked for root-spelled paths only.
const std::vector<std::string> kLayeredTops = {"framework", "strategies", "pipeline",
                                               "applications", "experiments"};

/// The layer table of docs/architecture.md: folder (relative, ending in '/') -> level. Rows are
/// `| level | \`folder/\` | ...` under the heading "## Layers", lowest level first.
std::map<std::string, int> readLayerTable(const fs::path& architectureMd) {
  static const std::regex row(R"(^\|\s*(\d+)\s*\|\s*`([a-z_/]+/)`\s*\|)");
  std::ifstream in(architectureMd);
  std::map<std::string, int> levels;
  bool inLayers = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) inLayers = line == "## Layers";
    std::smatch m;
    if (inLayers && std::regex_search(line, m, row)) levels[m[2]] = std::stoi(m[1]);
  }
  return levels;
}

/// The level of a path relative to the root: that of the longest table folder holding it, or -1.
int levelOf(const std::map<std::string, int>& levels, const std::string& relative) {
  int level = -1;
  std::size_t longest = 0;
  for (const auto& [folder, l] : levels)
    if (relative.rfind(folder, 0) == 0 && folder.size() > longest) {
      longest = folder.size();
      level = l;
    }
  return level;
}

bool isSource(const fs::path& file) {
  const std::string ext = file.extension().string();
  return ext == ".hpp" || ext == ".cpp" || ext == ".inl";
}

/// The include-line violations of one source file: an include not spelled from the root, or
/// one that reaches a higher level.
void checkIncludes(const fs::path& root, const std::string& file,
                   const std::map<std::string, int>& levels, std::vector<std::string>& out) {
  static const std::regex include(R"(^\s*#\s*include\s+"([^"]+)\")");
  std::ifstream in(root / file);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::smatch m;
    if (!std::regex_search(line, m, include)) continue;
    const std::string target = m[1];
    const std::string where = file + ":" + std::to_string(number) + ": \"" + target + "\"";
    const int from = levelOf(levels, file);
    if (!fs::exists(root / target))
      out.push_back(where + " is not a path from the repository root");
    else if (from >= 0 && levelOf(levels, target) > from)
      out.push_back(where + " is a higher layer");
  }
}

/// One line per break of the rules for the tree under `root`, against its
/// docs/architecture.md.
std::vector<std::string> layerViolations(const fs::path& root) {
  const std::map<std::string, int> levels = readLayerTable(root / "docs/architecture.md");
  std::vector<std::string> violations;
  if (levels.empty()) return {"docs/architecture.md: no layer table under \"## Layers\""};
  for (const auto& [folder, level] : levels)
    if (!fs::is_directory(root / folder))
      violations.push_back(folder + " (level " + std::to_string(level) + ") does not exist");

  std::vector<std::string> tops = kLayeredTops;
  tops.push_back("tests");
  for (const std::string& top : tops) {
    if (!fs::exists(root / top)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
      if (!entry.is_regular_file() || !isSource(entry.path())) continue;
      const std::string file = fs::relative(entry.path(), root).generic_string();
      if (file.rfind("tests/corpus/", 0) == 0) continue;
      if (top != "tests" && levelOf(levels, file) < 0)
        violations.push_back(file + " is in no folder of the layer table");
      checkIncludes(root, file, levels, violations);
    }
  }
  return violations;
}

void writeFile(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

std::size_t countStarting(const std::vector<std::string>& lines, const std::string& prefix,
                          const std::string& containing) {
  return std::count_if(lines.begin(), lines.end(), [&](const std::string& v) {
    return v.rfind(prefix, 0) == 0 && v.find(containing) != std::string::npos;
  });
}

}  // namespace

TEST_CASE("layers: no source includes a higher layer, all spell paths from the root", "[layers]") {
  const std::vector<std::string> violations = layerViolations(NDC_SOURCE_DIR);
  for (const std::string& v : violations) UNSCOPED_INFO(v);
  CHECK(violations.empty());
  // The table holds every layer of the drawing, framework's floors first.
  const auto levels = readLayerTable(fs::path(NDC_SOURCE_DIR) / "docs/architecture.md");
  CHECK(levels.size() >= 13);
  CHECK(levelOf(levels, "framework/util/errors.hpp") < levelOf(levels, "strategies/x.hpp"));
  // The report makes viewer pages; the viewer does not need the report.
  CHECK(levelOf(levels, "experiments/view/b.cpp") < levelOf(levels, "experiments/report/a.cpp"));
  CHECK(levelOf(levels, "experiments/cli/c.cpp") == levelOf(levels, "experiments/python/p.cpp"));
}

TEST_CASE("layers: the check finds an upward include, a path not from the root, a stray folder",
          "[layers]") {
  const ndc::test::ScratchDir dir("layers");
  writeFile(dir.path() / "docs/architecture.md",
            "# Architecture\n## Layers\n| level | folder |\n|---|---|\n| 1 | `framework/util/` |\n"
            "| 2 | `strategies/` |\n| 3 | `pipeline/` |\n| 3 | `experiments/cli/` |\n"
            "| 4 | `applications/` |\n## Next\n| 9 | `experiments/` |\n");
  writeFile(dir.path() / "framework/util/a.hpp", "#include \"pipeline/p.hpp\"\n");
  writeFile(dir.path() / "pipeline/p.hpp", "#include \"framework/util/a.hpp\"\n");
  writeFile(dir.path() / "strategies/s/s.cpp", "#include \"a.hpp\"\n#include <vector>\n");
  writeFile(dir.path() / "experiments/cli/c.cpp",
            "#include \"pipeline/p.hpp\"\n#include \"strategies/s/s.cpp\"\n");
  writeFile(dir.path() / "experiments/stray/x.cpp", "#include <vector>\n");
  const std::vector<std::string> violations = layerViolations(dir.path());
  for (const std::string& v : violations) UNSCOPED_INFO(v);
  REQUIRE(violations.size() == 4);
  CHECK(countStarting(violations, "framework/util/a.hpp:1:", "higher layer") == 1);
  CHECK(countStarting(violations, "strategies/s/s.cpp:1:", "not a path from the repository") == 1);
  // The table row after another heading is not a layer: experiments/stray is in none.
  CHECK(countStarting(violations, "experiments/stray/x.cpp", "no folder of the layer table") == 1);
  CHECK(countStarting(violations, "applications/", "does not exist") == 1);
}
