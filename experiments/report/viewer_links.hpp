/// \file viewer_links.hpp
/// The links of the report to the 3-D viewer pages of an experiment's runs (`ndcontour view`,
/// docs/viewer.md): one compact table per section, a row per problem and a short link per run,
/// instead of one line of full run ids.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "experiments/runner/csv.hpp"

namespace ndc::report {

/// Writes `view.html` into the folder `runsDir/RUN` of every run of `csv` (its `run` column)
/// that holds a mesh (`mesh.ply` and `summary.json`), and returns the Markdown that links them:
/// one sentence and a table with one row per problem (the `problem` column, in the order of the
/// CSV) whose cell links each of its runs to `linkPrefix` + `RUN/view.html`, labelled by the
/// settings that vary within the experiment (`naive`, `L6`, `mpfr 128 bits`, `j1`, ...; `view` when
/// only the problem varies). A run whose page cannot be made is left out. Empty when no page was
/// written, or when this build has no three.js.
std::string runViewerLinks(const CsvTable& csv, const std::filesystem::path& runsDir,
                           const std::string& linkPrefix);

/// The Markdown of runViewerLinks for the runs of `csv` for which `page(RUN)` returns true
/// (runViewerLinks's `page` writes the run's page and says whether it could); empty when it
/// returns false for every run.
std::string viewerLinkTable(const CsvTable& csv,
                            const std::function<bool(const std::string& run)>& page,
                            const std::string& linkPrefix);

}  // namespace ndc::report
