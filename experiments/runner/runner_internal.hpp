// Private helpers and types shared by the runner's sources (not part of the public surface).
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/runner/experiment.hpp"
#include "experiments/runner/slurm.hpp"
#include "framework/problem/summary.hpp"

namespace ndc::runner_detail {

// --- Small helpers (experiment.cpp) ----------------------------------------------------------

/// The whole content of a file ("" when it cannot be read).
std::string readFile(const std::filesystem::path& file);

/// Shortest decimal text that reads back as the same double ("null" when not finite).
std::string jsonNumber(double v);

/// `s` as one word for a POSIX shell: unchanged when plain, else in single quotes.
std::string shellWord(const std::string& s);

// --- Provenance (provenance.cpp) -------------------------------------------------------------

/// `s` without leading and trailing white space.
std::string trimmed(std::string s);

/// The current time in UTC, ISO 8601 (`2024-01-31T12:00:00Z`).
std::string utcNow();

/// Counts of one invocation, for the report and the provenance.
struct Tally {
  std::size_t total = 0, ran = 0, skipped = 0, failed = 0;
  std::vector<std::string> failedRuns;
  std::size_t slurmTasks = 0;  ///< Slurm executor: the tasks submitted
  std::string slurmJobId;      ///< Slurm executor: the job submitted; empty when none
};

/// The text of provenance.json (docs/experiments.md): config, command, source revision, build,
/// grid, run counts, dates and machine; `started` is the utcNow() of the invocation's start.
std::string provenanceJson(const ExperimentConfig& c, const ExperimentOptions& o,
                           const Tally& tally, const std::string& started);

// --- Child processes (spawn.cpp) -------------------------------------------------------------

using Clock = std::chrono::steady_clock;

/// What became of one run.
struct Outcome {
  std::string status;  ///< ok, failed, timeout, crashed, error
  std::optional<int> exitCode;
  std::string error;
  bool skipped = false;
  double seconds = 0;
  std::vector<std::pair<std::string, std::string>> values;  ///< summary.json numbers
};

/// The signal (SIGINT or SIGTERM) that arrived while an InterruptScope was active; 0: none.
extern volatile std::sig_atomic_t gInterrupted;

/// Stops child processes: SIGTERM first, so that a solve removes its staging folder and leaves
/// its run directory whole, then SIGKILL for any still running after a second. Returns each
/// child's wait status, in the order given.
std::vector<int> stopChildren(const std::vector<pid_t>& pids);

/// The outcome of a finished run read back from the summary.json of its run directory.
Outcome readSummary(const std::filesystem::path& runDir);

/// The outcome of a child that ended with wait status `status` (or was killed on timeout).
Outcome outcomeOf(const std::filesystem::path& runDir, int status, bool timedOut, double timeoutS);

/// The arguments of `ndcontour solve` for one run (without the program name); `cells` adds
/// `--cells`.
std::vector<std::string> solveArguments(const std::string& problem, const std::string& runDir,
                                        const Settings& s, bool cells);

/// Starts a run: standard input /dev/null, standard output `stdoutFile` (/dev/null for a run),
/// standard error into `stderrFile` (the run directory's stderr.txt). Returns the pid, or -1 with
/// `error` set.
pid_t spawnRun(const std::string& executable, const std::vector<std::string>& arguments,
               const std::filesystem::path& stderrFile, std::string& error,
               const std::filesystem::path& stdoutFile = "/dev/null");

/// How a child process ended.
struct Ended {
  int status = 0;         ///< its wait status
  bool timedOut = false;  ///< stopped by pollChild past the timeout
  int lostErrno = 0;      ///< waitpid failed with this errno (the status is unknown)
  double seconds = 0;     ///< wall-clock time from its start
};

/// Polls a child started at `start`: nullopt while it runs within `timeoutS`; past the timeout it
/// is stopped (stopChildren) and recorded as timed out.
std::optional<Ended> pollChild(pid_t pid, Clock::time_point start, double timeoutS);

/// The outcome of an ended child, as outcomeOf (or an error when its status was lost).
Outcome outcomeOfEnded(const std::filesystem::path& runDir, const Ended& ended, double timeoutS);

// --- The runs (experiment.cpp) -----------------------------------------------------------------

/// Prepares run `run` in `runDir` (creates it, writes command.txt) and returns the arguments of
/// its `ndcontour solve`, with the memory budget shared by `jobs` runs at once. Throws InputError
/// when the directory cannot be made.
std::vector<std::string> prepareRun(const ExperimentConfig& config, const ExperimentRun& run,
                                    const std::filesystem::path& runDir, int jobs);

// --- The Slurm executor (slurm.cpp) --------------------------------------------------------------

/// Runs the pending runs (indices into `runs`) as one Slurm job array of `ndcontour
/// experiment-task` tasks (slurm.hpp) and calls `finished(i, outcome)` as each run's outcome
/// appears in the results folder `dir`; `tick` is called while waiting. Returns the Slurm job id
/// ("" when nothing was submitted). Stops at an interrupt (gInterrupted) after cancelling the
/// job. Throws InputError when `sbatch` is missing or refuses the job.
std::string runOnSlurm(const ExperimentConfig& config, const ExperimentOptions& options,
                       const std::vector<ExperimentRun>& runs, const std::filesystem::path& dir,
                       const std::vector<std::size_t>& pending,
                       const std::function<void(std::size_t, const Outcome&)>& finished,
                       const std::function<void()>& tick);

/// Runs `tasks` as one Slurm job array (`job` gives its name, executable, log and working
/// folders, limits and sbatch options; the task list and script go into its log folder) and
/// calls `finished(t, outcome)` as task t's outcome appears; `tick` is called while waiting.
/// Returns the job id. Throws as runOnSlurm.
std::string runTasksOnSlurm(SlurmJob job, const std::vector<SlurmTask>& tasks,
                            const std::function<void(std::size_t, const Outcome&)>& finished,
                            const std::function<void()>& tick);

/// Sets gInterrupted on SIGINT and SIGTERM; restores the previous handlers at scope exit.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();

 private:
  struct sigaction savedInt_ {
  }, savedTerm_{};
};

}  // namespace ndc::runner_detail
