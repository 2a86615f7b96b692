// The artefact builders by id: the one table kBuilders, and buildArtefact (report.hpp).
#include <algorithm>
#include <array>
#include <string_view>

#include "experiments/report/artefacts/builders.hpp"
#include "experiments/report/artefacts/common.hpp"
#include "experiments/report/report.hpp"

namespace ndc::report {

using namespace detail;

namespace {

/// What a builder gets: the experiment id and CSV, its results folder `results/<id>/`, and the
/// directory of the paper's reference figures.
struct BuildInput {
  const std::string& id;
  const CsvTable& csv;
  const std::filesystem::path& dir;
  const std::filesystem::path& reference;
};

/// The builder of one artefact id (or, with `prefix`, of every id that starts with it).
struct Builder {
  std::string_view id;
  bool prefix;
  Artefact (*build)(const BuildInput&);
};

/// Every artefact the report knows, in report order: the one place that maps ids to builders.
/// Ids without a builder get genericTable.
constexpr std::array<Builder, 10> kBuilders = {{
    {"tab1-degeneracy", false,
     [](const BuildInput& in) {
       return tab1Degeneracy(in.id, in.csv, loadPaperTable1(in.reference));
     }},
    {"fig-degeneracy-vs-n", false,
     [](const BuildInput& in) {
       return figDegeneracyVsN(in.id, in.csv, loadPaperTable1(in.reference));
     }},
    // k = 3: one series per depth, and no paper points (its Table 1 has surfaces only).
    {"fig-degeneracy-vs-n-k3", false,
     [](const BuildInput& in) { return figDegeneracyVsN(in.id, in.csv, {}, true); }},
    {"tab-ablation-bounding", false,
     [](const BuildInput& in) { return tabAblation(in.id, in.csv, "bounding"); }},
    {"tab-ablation-subdivision", false,
     [](const BuildInput& in) { return tabAblation(in.id, in.csv, "subdivision"); }},
    {"tab-ablation-scalar", false,
     [](const BuildInput& in) { return tabAblation(in.id, in.csv, "scalar"); }},
    {"tab-connection", false, [](const BuildInput& in) { return tabConnection(in.id, in.csv); }},
    {"fig-convergence", false, [](const BuildInput& in) { return figConvergence(in.id, in.csv); }},
    {"fig-cells", false, [](const BuildInput& in) { return figCells(in.id, in.csv, in.dir); }},
    {"fig-app-", true, [](const BuildInput& in) { return figApplication(in.id, in.csv, in.dir); }},
}};

/// The ids of kBuilders that name one artefact (not a prefix), in report order.
constexpr auto kKnownArtefacts = [] {
  constexpr std::size_t count = static_cast<std::size_t>(std::count_if(
      kBuilders.begin(), kBuilders.end(), [](const Builder& b) { return !b.prefix; }));
  std::array<std::string_view, count> ids{};
  std::size_t i = 0;
  for (const Builder& b : kBuilders)
    if (!b.prefix) ids[i++] = b.id;
  return ids;
}();

/// The builder registered for `id`; nullptr when there is none.
const Builder* builderOf(std::string_view id) {
  for (const Builder& b : kBuilders)
    if (b.prefix ? id.starts_with(b.id) : id == b.id) return &b;
  return nullptr;
}

}  // namespace

std::span<const std::string_view> knownArtefacts() { return kKnownArtefacts; }

Artefact buildArtefact(const std::string& id, const CsvTable& csv, const std::filesystem::path& dir,
                       const std::filesystem::path& reference) {
  const Builder* builder = builderOf(id);
  Artefact a = builder ? builder->build({id, csv, dir, reference}) : genericTable(id, csv);
  a.runs = csv.size();
  a.failures = failedRuns(csv);
  return a;
}

}  // namespace ndc::report
