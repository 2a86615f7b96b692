// `ndcontour report` (issue 6): see cli/report.hpp and report.hpp.
#include "experiments/cli/report.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

#include "experiments/report/report.hpp"

namespace ndc::cli {

void addReportOptions(CLI::App& report, ReportOptions& options) {
  report
      .add_option("--results", options.results,
                  "Results directory: reads <DIR>/<id>/<id>.csv, writes tables, figures and "
                  "<DIR>/report.md")
      ->type_name("DIR")
      ->capture_default_str();
  report
      .add_option("--configs", options.configs,
                  "Experiment configs (<id>.toml): the artefacts the report expects")
      ->type_name("DIR")
      ->capture_default_str();
  report.add_flag("--quick", options.quick, "Say in the report that the results are --quick ones");
}

int runReport(const ReportOptions& options) {
  ndc::report::ReportSettings settings;
  settings.results = options.results;
  settings.configs = options.configs;
  settings.quick = options.quick;
  const ndc::report::ReportOutcome outcome = ndc::report::writeReport(settings, std::cerr);
  for (const std::string& note : outcome.notes) std::cerr << "report: " << note << '\n';
  std::cout << "wrote " << (settings.results / "report.md").string() << ": "
            << outcome.written.size() << " artefacts, " << outcome.missing.size() << " missing, "
            << outcome.failedRuns << " failed runs, " << outcome.errors.size() << " errors\n";
  // Bad input in a results file: one line, status 2 (the report is written all the same).
  if (outcome.status == 2)
    for (const std::string& e : outcome.errors) std::cerr << "ndcontour: " << e << '\n';
  return outcome.status;
}

}  // namespace ndc::cli
