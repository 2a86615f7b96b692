/// \file cli/experiment.hpp
/// `ndcontour experiment CONFIG.toml [--out DIR] [--jobs N] [--quick]` (docs/experiments.md).
#pragma once

#include <string>

namespace CLI {
class App;
}

namespace ndc::cli {

/// Options of `ndcontour experiment`.
struct ExperimentCommandOptions {
  std::string config;           ///< CONFIG.toml
  std::string out = "results";  ///< results go to `<out>/<id>/`
  int jobs = 0;                 ///< runs at once; 0: the number of hardware threads
  bool quick = false;           ///< apply the config's `[quick]` overrides
};

/// Declares the options of the `experiment` subcommand.
void addExperimentOptions(CLI::App& experiment, ExperimentCommandOptions& options);

/// `ndcontour experiment`: validates the config (InputError on bad input), runs the grid and
/// returns the exit status (0 all runs succeeded, 1 some failed). `commandLine` is recorded
/// in the provenance.
int runExperimentCommand(const ExperimentCommandOptions& options, const std::string& commandLine);

}  // namespace ndc::cli
