/// \file report.hpp
/// Tables and figures from experiment results (issue 6): reads the combined CSV that
/// `ndcontour experiment` writes for each experiment (`results/<id>/<id>.csv`, one row per run),
/// aggregates it, and writes each artefact under the same id as its config: tables as Markdown
/// (`<id>.md`) and LaTeX (`<id>.tex`), figures as gnuplot scripts (`<id>.gp`) rendered to
/// `<id>.png` and `<id>.pdf`, the sentences computed from the data as `<id>-summary.tex`, one
/// `results/applications.tex` listing the application figures, and one `results/report.md`
/// with every artefact. The paper (`paper/ndcontour.tex`) includes only these files.
///
/// The numbers of the paper (Seong, Elber and Kim 2005) that the artefacts set beside ours are
/// data, not code: they are read at run time from the reference directory, by default the
/// sibling `reference/` of the configs directory (`experiments/reference/` for the default
/// `experiments/configs`; see referenceDir). `table1.toml` holds the paper's Table 1 (used by
/// `tab1-degeneracy` and `fig-degeneracy-vs-n`). A missing or malformed reference file makes
/// that artefact fail with a one-line ndc::InputError naming the file.
///
/// Each known artefact id has one builder, registered in one table in artefacts.cpp (kBuilders);
/// docs/experiments.md ("The report's files") lists the files of the report and their roles.
#pragma once

#include <cstddef>
#include <filesystem>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/report/gnuplot.hpp"
#include "experiments/report/stats.hpp"
#include "experiments/report/table.hpp"
#include "experiments/runner/csv.hpp"
#include "framework/io/io.hpp"

namespace ndc::report {

// --- Reading run outputs -----------------------------------------------------------------------

/// The PLY reader lives in core beside the writer (framework/io/io.hpp); these names keep
/// `ndc::report::PlyMesh` and `ndc::report::readPly` working.
using ndc::PlyMesh;
using ndc::readPly;

// --- The report --------------------------------------------------------------------------------

/// One artefact made from one experiment's CSV.
struct Artefact {
  std::string id;                      ///< the experiment and artefact id
  bool figure = false;                 ///< `fig-*` ids are figures, others tables
  std::string title;                   ///< a heading for the report
  std::vector<Table> tables;           ///< tables[0] is `<id>.md`/`<id>.tex`; figures: data tables
  std::string gnuplot;                 ///< figures: the script `<id>.gp`
  std::vector<std::string> sentences;  ///< what it shows, computed from the data
  std::size_t runs = 0;                ///< rows of the CSV
  std::vector<std::string> failures;   ///< one line per failed run: run, problem, status, error
  std::vector<std::string> shownRuns;  ///< figures: the runs (`runs/<run>/`) the figure shows
  /// What the paper's conclusion takes from this artefact (computed from the data; may be empty).
  std::vector<std::string> conclusion;
};

/// The directory of the paper's reference figures (`table1.toml`, ...) for the configs
/// directory `configs`: its sibling `../reference` (e.g. `experiments/reference` for
/// `experiments/configs`) when that is a directory; otherwise `experiments/reference` of the
/// source tree this program was built from (configs outside the repository, e.g. in tests).
std::filesystem::path referenceDir(const std::filesystem::path& configs = "experiments/configs");

/// Builds the artefact of experiment `id` from its CSV; `dir` is `results/<id>/` (for the
/// per-run files a figure may read: `runs/<run>/cells.csv`, `runs/<run>/mesh.ply`) and
/// `reference` the directory of the paper's reference figures (see referenceDir). Known ids
/// (`tab1-degeneracy`, `fig-degeneracy-vs-n`, `tab-ablation-*`, `tab-connection`,
/// `fig-convergence`, `fig-cells`, `fig-app-*`) get their own tables, figures and sentences;
/// any other id a table with one row per run. Throws InputError for a missing column or a
/// missing or malformed reference file.
Artefact buildArtefact(const std::string& id, const CsvTable& csv, const std::filesystem::path& dir,
                       const std::filesystem::path& reference = referenceDir());

/// Settings of writeReport.
struct ReportSettings {
  std::filesystem::path results = "results";              ///< `<id>/<id>.csv` per experiment
  std::filesystem::path configs = "experiments/configs";  ///< `<id>.toml`: the expected ids
  bool quick = false;                                     ///< said so in the report
  bool render = true;  ///< run gnuplot for figures when it is on PATH
  /// The paper's reference figures (`table1.toml`); empty: referenceDir(configs).
  std::filesystem::path reference;
};

/// What writeReport did.
struct ReportOutcome {
  std::vector<std::string> written;  ///< artefact ids written
  std::vector<std::string> missing;  ///< expected ids without a CSV
  std::vector<std::string> errors;   ///< one line per artefact that could not be made
  std::size_t failedRuns = 0;        ///< failed runs over all experiments
  std::vector<std::string> notes;    ///< e.g. "gnuplot not found: figures not rendered"
  /// 0: all fine; 1: failed runs, missing experiments or unrendered figures; 2: an
  /// experiment's CSV was bad input.
  int status = 0;
};

/// Writes every artefact whose CSV exists under `settings.results`, `results/report.md` (which
/// ends with the conclusion) and `results/conclusion.tex`, the paper's conclusion computed from
/// the results: runs, failed and certified runs over all experiments, then each artefact's
/// Artefact::conclusion in report order,
/// each file atomically (a failed artefact leaves its previous files alone). Progress lines go
/// to `log`. Throws InputError when `settings.results` is not a directory.
ReportOutcome writeReport(const ReportSettings& settings, std::ostream& log);

/// The artefact ids the report knows, in report order (application figures `fig-app-*` are
/// found in the configs and results directories).
std::span<const std::string_view> knownArtefacts();

}  // namespace ndc::report
