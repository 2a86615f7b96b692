// The report's links to the viewer pages of the runs: see viewer_links.hpp.
#include "experiments/report/viewer_links.hpp"

#include <system_error>
#include <vector>

#include "experiments/report/artefacts/common.hpp"
#include "experiments/view/view.hpp"

namespace ndc::report {
namespace {

/// The short label of run `r` among the others: the values of the settings that vary within
/// the experiment (`varying`), e.g. "naive L6" or "mpfr 128 bits"; "view" when none does.
std::string runLabel(const CsvTable& t, std::size_t r, const std::vector<std::string>& varying) {
  std::vector<std::string> parts;
  for (const std::string& c : varying) {
    const std::string value = t.cell(r, c);
    if (value.empty()) continue;
    if (c == "depth")
      parts.push_back("L" + value);
    else if (c == "seed")
      parts.push_back("j" + value);
    else if (c == "precision_bits")
      parts.push_back(t.hasColumn("scalar") && t.cell(r, "scalar") == "double" ? ""
                                                                               : value + " bits");
    else
      parts.push_back(value);
  }
  std::erase(parts, std::string());
  return parts.empty() ? "view" : detail::join(parts, " ");
}

}  // namespace

std::string viewerLinkTable(const CsvTable& csv,
                            const std::function<bool(const std::string& run)>& page,
                            const std::string& linkPrefix) {
  if (!csv.hasColumn("run") || !csv.hasColumn("problem")) return "";
  // What tells the runs of one problem apart.
  std::vector<std::string> candidates = detail::kSettingColumns;
  candidates.push_back("seed");
  const std::vector<std::string> varying = varyingColumns(csv, candidates);
  // One row per problem, one link per run with a page.
  Table table;
  table.columns = {"problem", "3-D views"};
  table.align = "ll";
  std::size_t pages = 0;
  for (const Group& g : groupBy(csv, std::vector<std::string>{"problem"})) {
    std::vector<std::string> links;
    for (std::size_t r : g.rows) {
      const std::string run = csv.cell(r, "run");
      if (run.empty() || !page(run)) continue;
      links.push_back("[" + runLabel(csv, r, varying) + "](" + linkPrefix + run + "/view.html)");
    }
    if (links.empty()) continue;
    pages += links.size();
    table.rows.push_back({g.key[0], detail::join(links, " · ")});
  }
  if (pages == 0) return "";
  return "\n\n3-D views of the meshes (`ndcontour view`, " + std::to_string(pages) +
         (pages == 1 ? " page" : " pages") + "):\n\n" + toMarkdown(table);
}

std::string runViewerLinks(const CsvTable& csv, const std::filesystem::path& runsDir,
                           const std::string& linkPrefix) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!ndc::view::viewerAvailable() || !fs::is_directory(runsDir, error)) return "";
  const auto page = [&](const std::string& run) {
    const fs::path dir = runsDir / run;
    if (!fs::exists(dir / "mesh.ply") || !fs::exists(dir / "summary.json")) return false;
    try {
      ndc::view::writeViewer(dir, dir / "view.html");
      return true;
    } catch (const InputError&) {
      return false;
    }
  };
  return viewerLinkTable(csv, page, linkPrefix);
}

}  // namespace ndc::report
