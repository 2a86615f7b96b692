/// \file builders.hpp
/// The artefact builders of the report (internal to experiments/report/), one per file of
/// experiments/report/artefacts/ and registered in one table in artefacts.cpp (kBuilders). Each
/// reads an experiment's CSV and returns its tables, figure script and sentences (Artefact);
/// each throws InputError for a missing column.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "experiments/report/artefacts/paper_reference.hpp"
#include "experiments/report/report.hpp"

namespace ndc::report::detail {

/// `tab1-degeneracy` (tab1_degeneracy.cpp): the paper's Table 1, ours beside the paper's.
Artefact tab1Degeneracy(const std::string& id, const CsvTable& t,
                        const std::vector<PaperRow>& paper);

/// `fig-degeneracy-vs-n` and `fig-degeneracy-vs-n-k3` (fig_degeneracy_vs_n.cpp): the abnormal
/// share against n, one series per k (and per depth with `depthSeries`); the paper's Table 1
/// points beside them unless `paper` is empty.
Artefact figDegeneracyVsN(const std::string& id, const CsvTable& t,
                          const std::vector<PaperRow>& paper, bool depthSeries = false);

/// `tab-ablation-*` (tab_ablation.cpp): the variants of one strategy family (`bounding`,
/// `subdivision`) or of the scalar type (`scalar`) compared.
Artefact tabAblation(const std::string& id, const CsvTable& t, const std::string& family);

/// `tab-connection` (tab_connection.cpp): the connection strategies over the problem corpus.
Artefact tabConnection(const std::string& id, const CsvTable& t);

/// `fig-convergence` (fig_convergence.cpp): convergence with the depth.
Artefact figConvergence(const std::string& id, const CsvTable& t);

/// `fig-cells` (fig_cells.cpp): the solution cells of a 2-D problem; `dir` is `results/<id>/`.
Artefact figCells(const std::string& id, const CsvTable& t, const std::filesystem::path& dir);

/// `fig-app-*` (fig_app.cpp): the mesh of each application problem; `dir` is `results/<id>/`.
Artefact figApplication(const std::string& id, const CsvTable& t, const std::filesystem::path& dir);

/// Any other id (generic_table.cpp): a table with one row per run.
Artefact genericTable(const std::string& id, const CsvTable& t);

}  // namespace ndc::report::detail
