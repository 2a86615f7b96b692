/// \file slurm.hpp
/// The Slurm executor of experiments (docs/experiments.md, "Running a grid on Slurm"): the
/// pending runs of a grid become one job array, submitted with `sbatch --array --wait`. Task i
/// runs `ndcontour experiment-task TASKS i`, which starts the `ndcontour solve` of pending run i
/// exactly as the local executor does (same arguments, standard error into the run directory,
/// stopped past the same timeout) and records how it ended; the runner collects those records as
/// the local executor collects its children.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace ndc {

/// One task of the job array: a pending run and how to run it.
struct SlurmTask {
  std::string run;                    ///< the run id
  std::filesystem::path runDir;       ///< its directory (stderr.txt goes there)
  std::filesystem::path outcomeFile;  ///< where the task records how the run ended
  double timeoutS = 600;              ///< wall-clock limit of the run, in seconds
  std::vector<std::string> command;   ///< the executable, then the arguments of `solve`
};

/// A task as one line of the task list (without the line break): run, run directory, outcome
/// file, timeout and the command words, separated by tabs; backslash, tab, line feed and carriage
/// return inside a field are written `\\`, `\t`, `\n` and `\r`.
std::string slurmTaskLine(const SlurmTask& task);

/// Reads back a line written by slurmTaskLine. Throws InputError for a malformed line.
SlurmTask parseSlurmTaskLine(std::string_view line);

/// One submission of a job array.
struct SlurmJob {
  std::string name;                    ///< the job name (`--job-name`)
  std::filesystem::path executable;    ///< the absolute path of `ndcontour`
  std::filesystem::path tasksFile;     ///< the task list, one slurmTaskLine per task
  std::filesystem::path script;        ///< the batch script (slurmBatchScript)
  std::filesystem::path logDir;        ///< Slurm's output of task i goes to `task-i.log` here
  std::filesystem::path workDir;       ///< the tasks' working directory (the runner's)
  std::size_t tasks = 1;               ///< number of tasks, at least 1
  int jobs = 1;                        ///< tasks at once (the `%` limit of `--array`)
  double timeoutS = 600;               ///< a run's timeout; a task may take 2 minutes more
  std::string partition;               ///< `--partition`; empty: the cluster's default
  std::vector<std::string> extraArgs;  ///< further sbatch options, last so that they win
};

/// The batch script of a job: `exec EXECUTABLE experiment-task TASKS "$SLURM_ARRAY_TASK_ID"`,
/// after comments that say how it was submitted.
std::string slurmBatchScript(const SlurmJob& job);

/// The arguments of `sbatch` (without the program name) that submit the job array and wait for
/// its end: `--parsable --wait --array=0-(N-1)%J --job-name=NAME --output=LOGDIR/task-%a.log
/// --chdir=WORKDIR --time=MINUTES [--partition=P] EXTRA... SCRIPT`.
std::vector<std::string> sbatchArguments(const SlurmJob& job);

/// `ndcontour experiment-task TASKS INDEX`: runs task INDEX (0-based) of a task list as the local
/// executor runs a run and writes its outcome file. Returns 0 when the outcome was recorded
/// (whatever the run's own status), 128 + the signal when interrupted by SIGINT or SIGTERM (the
/// run is stopped and nothing is recorded). Throws InputError for an unreadable task list, an
/// index out of range or a malformed line.
int runSlurmTask(const std::filesystem::path& tasksFile, std::size_t index);

/// The absolute path of the program `name` in a directory of PATH; empty when there is none.
std::filesystem::path findOnPath(const std::string& name);

}  // namespace ndc
