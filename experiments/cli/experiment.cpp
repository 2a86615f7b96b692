// `ndcontour experiment`: runs an experiment config (experiments/runner/experiment.hpp).
#include "experiments/cli/experiment.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <sstream>
#include <thread>
#include <vector>

#include "experiments/runner/experiment.hpp"
#include "experiments/runner/slurm.hpp"
#include "framework/util/errors.hpp"

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
  experiment
      .add_option("--executor", o.executor,
                  "Where the runs execute: local (child processes) or slurm (one sbatch job array)")
      ->type_name("local|slurm")
      ->capture_default_str();
  experiment
      .add_option("--slurm-partition", o.slurmPartition, "Slurm executor: sbatch --partition")
      ->type_name("P");
  experiment
      .add_option("--slurm-args", o.slurmArgs,
                  "Slurm executor: further sbatch options, split at spaces (e.g. \"--mem=4G\")")
      ->type_name("\"...\"");
}

void addExperimentTaskOptions(CLI::App& task, ExperimentTaskOptions& o) {
  task.add_option("tasks", o.tasks, "Task list written by the Slurm executor")->required();
  task.add_option("index", o.index, "Task index, 0-based ($SLURM_ARRAY_TASK_ID)")->required();
}

int runExperimentTaskCommand(const ExperimentTaskOptions& o) {
  return ndc::runSlurmTask(o.tasks, o.index);
}

namespace {

/// The executor of `--executor`, checked before anything runs.
Executor parseExecutor(const ExperimentCommandOptions& o) {
  if (o.executor == "local") return Executor::local;
  if (o.executor != "slurm")
    throw UsageError("--executor: unknown executor '" + o.executor + "' (accepted: local, slurm)");
  if (findOnPath("sbatch").empty())
    throw UsageError(
        "--executor slurm: sbatch not found on PATH (install Slurm's client, e.g. "
        "scripts/setup.sh --slurm)");
  return Executor::slurm;
}

std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

}  // namespace

int runExperimentCommand(const ExperimentCommandOptions& o, const std::string& commandLine) {
  const Executor executor = parseExecutor(o);
  if (executor == Executor::local && (!o.slurmPartition.empty() || !o.slurmArgs.empty()))
    throw UsageError("--slurm-partition and --slurm-args need --executor slurm");
  const ExperimentConfig config = loadExperimentConfig(o.config, o.quick);
  ndc::ExperimentOptions run;
  run.executor = executor;
  run.slurmPartition = o.slurmPartition;
  run.slurmArgs = words(o.slurmArgs);
  run.outDir = o.out;
  run.jobs =
      o.jobs > 0 ? o.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  run.commandLine = commandLine;
  return ndc::runExperiment(config, run);
}

}  // namespace ndc::cli
