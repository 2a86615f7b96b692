/// \file cli/experiment.hpp
/// `ndcontour experiment CONFIG.toml [--out DIR] [--jobs N] [--quick] [--executor local|slurm]
/// [--slurm-partition P] [--slurm-args "..."]` (docs/experiments.md), and the hidden
/// `ndcontour experiment-task TASKS INDEX` that runs one task of the Slurm executor.
#pragma once

#include <cstddef>
#include <string>

namespace CLI {
class App;
}

namespace ndc::cli {

/// Options of `ndcontour experiment`.
struct ExperimentCommandOptions {
  std::string config;              ///< CONFIG.toml
  std::string out = "results";     ///< results go to `<out>/<id>/`
  int jobs = 0;                    ///< runs at once; 0: the number of hardware threads
  bool quick = false;              ///< apply the config's `[quick]` overrides
  std::string executor = "local";  ///< `local` or `slurm`
  std::string slurmPartition;      ///< `--slurm-partition`: sbatch's partition
  std::string slurmArgs;           ///< `--slurm-args`: further sbatch options, split at spaces
};

/// Options of `ndcontour experiment-task` (one task of a Slurm job array, slurm.hpp).
struct ExperimentTaskOptions {
  std::string tasks;      ///< the task list
  std::size_t index = 0;  ///< the task, 0-based (`$SLURM_ARRAY_TASK_ID`)
};

/// Declares the options of the `experiment` subcommand.
void addExperimentOptions(CLI::App& experiment, ExperimentCommandOptions& options);

/// Declares the arguments of the hidden `experiment-task` subcommand.
void addExperimentTaskOptions(CLI::App& task, ExperimentTaskOptions& options);

/// `ndcontour experiment-task`: runs one task of a Slurm job array (ndc::runSlurmTask).
int runExperimentTaskCommand(const ExperimentTaskOptions& options);

/// `ndcontour experiment`: validates the options (UsageError: an unknown executor, or `slurm`
/// without `sbatch` on PATH) and the config (InputError on bad input), runs the grid and
/// returns the exit status (0 all runs succeeded, 1 some failed). `commandLine` is recorded
/// in the provenance.
int runExperimentCommand(const ExperimentCommandOptions& options, const std::string& commandLine);

}  // namespace ndc::cli
