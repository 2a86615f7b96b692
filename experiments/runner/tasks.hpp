/// \file tasks.hpp
/// A list of commands run as the experiment runner runs its solves (docs/experiments.md): on this
/// machine, a few at once, or as one Slurm job array (slurm.hpp). `ndcontour solve --split` runs
/// its pieces with it (docs/split.md).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "experiments/runner/slurm.hpp"
#include "framework/problem/summary.hpp"

namespace ndc {

/// Where and how the tasks run.
struct TaskExecutor {
  bool slurm = false;  ///< one Slurm job array (`sbatch --array --wait`), else child processes
  int jobs = 1;        ///< tasks at once
  std::string name = "ndcontour";      ///< the Slurm job name
  std::filesystem::path logDir;        ///< the task list, batch script and Slurm logs (Slurm)
  std::string partition;               ///< `--partition` (Slurm; empty: the default)
  std::vector<std::string> slurmArgs;  ///< further sbatch options (Slurm)
};

/// How one task ended.
struct TaskOutcome {
  std::string status;           ///< ok, failed, timeout, crashed, error
  std::optional<int> exitCode;  ///< its exit status, when it exited
  std::string error;            ///< the last line of its standard error, or why it did not run
  double seconds = 0;           ///< its wall-clock time
};

/// The arguments of `ndcontour solve PROBLEM --out DIR` (without the program name) for
/// `settings`, as the experiment runner writes a run's: depth, strategies, scalar and precision,
/// jitter, threads and memory when set, and `--json`.
std::vector<std::string> solveArguments(const std::string& problem, const std::string& outDir,
                                        const Settings& settings);

/// Runs every task (SlurmTask::command in SlurmTask::runDir's stead: standard error into
/// `runDir/stderr.txt`, stopped past SlurmTask::timeoutS) and calls `finished(t, outcome)` as
/// task t ends. Returns the outcomes in task order. An interrupt (SIGINT, SIGTERM) stops the
/// running tasks (cancels the job) and throws InputError. Throws UsageError when `sbatch` is
/// missing for a Slurm executor.
std::vector<TaskOutcome> runTasks(
    const std::vector<SlurmTask>& tasks, const TaskExecutor& executor,
    const std::function<void(std::size_t, const TaskOutcome&)>& finished);

}  // namespace ndc
