// `ndcontour report` (issue 6): see cli/report.hpp.
#include "cli/report.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace ndc::cli {

void addReportOptions(CLI::App& report, ReportOptions& options) {
  report.add_option("--results", options.results, "Results directory (results/<id>/<id>.csv)")
      ->type_name("DIR");
  report.add_option("--configs", options.configs, "Experiment configs directory")
      ->type_name("DIR");
  report.add_flag("--quick", options.quick, "The results come from a --quick run");
}

int runReport(const ReportOptions& options) {
  std::cerr << "ndcontour report: not implemented yet\n";
  return 1;
}

}  // namespace ndc::cli
