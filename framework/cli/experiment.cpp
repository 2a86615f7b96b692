// `ndcontour experiment`: runs an experiment config (experiments/runner/experiment.hpp).
#include "framework/cli/experiment.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <thread>

#include "experiments/runner/experiment.hpp"

namespace ndc::cli {

void addExperimentOptions(CLI::App& experiment, ExperimentCommandOptions& o) {
  experiment.add_option("config", o.config, "Experiment config (TOML, docs/experiments.md)")
      ->required()
      ->type_name("CONFIG.toml");
  experiment.add_option("--out", o.out, "Write the results to DIR/<id>/")
      ->type_name("DIR")
      ->capture_default_str();
  experiment.add_option("--jobs", o.jobs, "Runs at once (default: the number of hardware threads)")
      ->type_name("N")
      ->check(CLI::Range(1, 1024));
  experiment.add_flag("--quick", o.quick, "Apply the config's [quick] overrides (smaller runs)");
}

int runExperimentCommand(const ExperimentCommandOptions& o, const std::string& commandLine) {
  const ExperimentConfig config = loadExperimentConfig(o.config, o.quick);
  ndc::ExperimentOptions run;
  run.outDir = o.out;
  run.jobs =
      o.jobs > 0 ? o.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  run.commandLine = commandLine;
  return ndc::runExperiment(config, run);
}

}  // namespace ndc::cli
