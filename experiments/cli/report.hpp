/// \file report.hpp
/// `ndcontour report`: turns the experiment results (`results/<id>/<id>.csv`) into tables
/// (Markdown and LaTeX), figures (gnuplot scripts, PNG and PDF when gnuplot is on PATH) and one
/// `results/report.md` that shows every artefact with a few sentences computed from the data.
#pragma once

#include <string>

namespace CLI {
class App;
}

namespace ndc::cli {

/// Options of `ndcontour report`.
struct ReportOptions {
  /// Directory holding one `<id>/<id>.csv` per experiment; outputs are written beside them.
  std::string results = "results";
  /// Directory of the experiment configs (`<id>.toml`): the list of expected artefacts.
  std::string configs = "experiments/configs";
  /// The results come from `ndcontour experiment --quick` (said so in the report).
  bool quick = false;
};

/// Declares the options of the `report` subcommand.
void addReportOptions(CLI::App& report, ReportOptions& options);

/// `ndcontour report`: writes every table, figure and `results/report.md`. Returns the exit
/// status: 0 when every present experiment had only successful runs, 1 when some run failed or
/// an experiment is missing (the report is written in every case), 2 for bad input (e.g. a
/// results CSV without a required column), which is thrown as UsageError.
int runReport(const ReportOptions& options);

}  // namespace ndc::cli
