// Private helpers and types shared by the runner's sources (not part of the public surface).
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/runner/experiment.hpp"
#include "framework/core/summary.hpp"

namespace ndc::runner_detail {

// --- Small helpers (experiment.cpp) ----------------------------------------------------------

/// The whole content of a file ("" when it cannot be read).
std::string readFile(const std::filesystem::path& file);

/// Shortest decimal text that reads back as the same double ("null" when not finite).
std::string jsonNumber(double v);

// --- Provenance (provenance.cpp) -------------------------------------------------------------

/// `s` without leading and trailing white space.
std::string trimmed(std::string s);

/// The current time in UTC, ISO 8601 (`2024-01-31T12:00:00Z`).
std::string utcNow();

/// Counts of one invocation, for the report and the provenance.
struct Tally {
  std::size_t total = 0, ran = 0, skipped = 0, failed = 0;
  std::vector<std::string> failedRuns;
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

/// Starts a run: standard input and output /dev/null, standard error into the run directory.
/// Returns the pid, or -1 with `error` set.
pid_t spawnRun(const std::string& executable, const std::vector<std::string>& arguments,
               const std::filesystem::path& stderrFile, std::string& error);

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
