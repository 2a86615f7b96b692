// The Slurm executor (slurm.hpp, docs/experiments.md "Running a grid on Slurm"): the task list,
// the batch script, the submission with `sbatch --array --wait`, the tasks themselves
// (`ndcontour experiment-task`) and the collection of their outcomes.
#include "experiments/runner/slurm.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <sstream>
#include <thread>

#include "experiments/runner/runner_internal.hpp"
#include "framework/io/io.hpp"
#include "framework/util/errors.hpp"

namespace ndc {
namespace fs = std::filesystem;
using runner_detail::Clock;
using runner_detail::Ended;
using runner_detail::gInterrupted;
using runner_detail::jsonNumber;
using runner_detail::Outcome;
using runner_detail::readFile;
using runner_detail::shellWord;
using runner_detail::trimmed;

// --- The task list ---------------------------------------------------------------------------

namespace {

std::string escapeField(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '\\':
        out += "\\\\";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string unescapeField(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\') {
      out += s[i];
      continue;
    }
    if (++i == s.size()) throw InputError("task list: a field ends in a lone backslash");
    switch (s[i]) {
      case '\\':
        out += '\\';
        break;
      case 't':
        out += '\t';
        break;
      case 'n':
        out += '\n';
        break;
      case 'r':
        out += '\r';
        break;
      default:
        throw InputError(std::string("task list: unknown escape \\") + s[i]);
    }
  }
  return out;
}

}  // namespace

std::string slurmTaskLine(const SlurmTask& task) {
  std::string line = escapeField(task.run) + '\t' + escapeField(task.runDir.string()) + '\t' +
                     escapeField(task.outcomeFile.string()) + '\t' + jsonNumber(task.timeoutS);
  for (const std::string& word : task.command) line += '\t' + escapeField(word);
  return line;
}

SlurmTask parseSlurmTaskLine(std::string_view line) {
  std::vector<std::string> fields;
  for (std::size_t start = 0;;) {
    const std::size_t tab = line.find('\t', start);
    fields.push_back(unescapeField(line.substr(start, tab - start)));
    if (tab == std::string_view::npos) break;
    start = tab + 1;
  }
  if (fields.size() < 5)
    throw InputError(
        "task list: a line needs run, run directory, outcome file, timeout and a "
        "command; it has " +
        std::to_string(fields.size()) + " fields");
  SlurmTask task;
  task.run = fields[0];
  task.runDir = fields[1];
  task.outcomeFile = fields[2];
  char* end = nullptr;
  task.timeoutS = std::strtod(fields[3].c_str(), &end);
  if (fields[3].empty() || *end != '\0' || !(task.timeoutS > 0))
    throw InputError("task list: the timeout '" + fields[3] + "' is not a positive number");
  task.command.assign(fields.begin() + 4, fields.end());
  return task;
}

// --- The job ---------------------------------------------------------------------------------

std::vector<std::string> sbatchArguments(const SlurmJob& job) {
  // The run's timeout, 2 minutes for start-up and the stop after it, in whole minutes.
  const long long minutes = static_cast<long long>(std::ceil(job.timeoutS / 60.0)) + 2;
  std::vector<std::string> a = {
      "--parsable",
      "--wait",
      "--array=0-" + std::to_string(job.tasks - 1) + "%" + std::to_string(std::max(1, job.jobs)),
      "--job-name=" + job.name,
      "--output=" + (job.logDir / "task-%a.log").string(),
      "--chdir=" + job.workDir.string(),
      "--time=" + std::to_string(minutes)};
  if (!job.partition.empty()) a.push_back("--partition=" + job.partition);
  a.insert(a.end(), job.extraArgs.begin(), job.extraArgs.end());
  a.push_back(job.script.string());
  return a;
}

std::string slurmBatchScript(const SlurmJob& job) {
  std::string submit = "sbatch";
  for (const std::string& a : sbatchArguments(job)) submit += ' ' + shellWord(a);
  return "#!/bin/sh\n"
         "# " +
         job.name +
         ": written and submitted by `ndcontour experiment` or `solve --split` (`--executor "
         "slurm`) as\n"
         "#   " +
         submit +
         "\n"
         "# Task i runs line i + 1 of the task list: the `ndcontour solve` of one run (also in "
         "the\n"
         "# run's command.txt) within the run's timeout, standard error into the run's\n"
         "# stderr.txt; it records how the run ended for the runner to collect.\n"
         "exec " +
         shellWord(job.executable.string()) + " experiment-task " +
         shellWord(job.tasksFile.string()) + " \"$SLURM_ARRAY_TASK_ID\"\n";
}

fs::path findOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0)
      return fs::absolute(candidate, ec);
  }
  return {};
}

// --- The outcome file ------------------------------------------------------------------------
// `wait_status N`, `timed_out 0|1` and `seconds S` lines for a run that was started and ended;
// one `error MESSAGE` line for a run that could not start.

namespace {

void writeOutcome(const fs::path& file, const Ended& e) {
  writeAtomically(file, "wait_status " + std::to_string(e.status) + "\ntimed_out " +
                            (e.timedOut ? "1" : "0") + "\nlost_errno " +
                            std::to_string(e.lostErrno) + "\nseconds " + jsonNumber(e.seconds) +
                            "\n");
}

/// The outcome of a task's run from its outcome file, as the local executor would have it.
Outcome readOutcome(const SlurmTask& task) {
  std::istringstream in(readFile(task.outcomeFile));
  Ended e;
  for (std::string key; in >> key;) {
    std::string value;
    std::getline(in, value);
    value = trimmed(value);
    if (key == "error") {
      Outcome o;
      o.status = "error";
      o.error = value;
      return o;
    }
    if (key == "wait_status") e.status = std::atoi(value.c_str());
    if (key == "timed_out") e.timedOut = value == "1";
    if (key == "lost_errno") e.lostErrno = std::atoi(value.c_str());
    if (key == "seconds") e.seconds = std::atof(value.c_str());
  }
  return runner_detail::outcomeOfEnded(task.runDir, e, task.timeoutS);
}

}  // namespace

int runSlurmTask(const fs::path& tasksFile, std::size_t index) {
  std::error_code ec;
  if (!fs::is_regular_file(tasksFile, ec)) throw InputError(tasksFile.string() + ": no task list");
  std::istringstream lines(readFile(tasksFile));
  std::string line;
  for (std::size_t i = 0; i <= index; ++i)
    if (!std::getline(lines, line))
      throw InputError(tasksFile.string() + ": no task " + std::to_string(index) + " (it has " +
                       std::to_string(i) + ")");
  const SlurmTask task = parseSlurmTaskLine(line);
  if (task.command.empty()) throw InputError(tasksFile.string() + ": task without a command");
  std::string error;
  const auto start = Clock::now();
  const std::vector<std::string> arguments(task.command.begin() + 1, task.command.end());
  const pid_t pid =
      runner_detail::spawnRun(task.command.front(), arguments, task.runDir / "stderr.txt", error);
  if (pid < 0) {
    writeAtomically(task.outcomeFile, "error " + oneLine(error) + "\n");
    return 0;
  }
  std::optional<Ended> ended;
  {
    runner_detail::InterruptScope interrupts;
    while (!(ended = runner_detail::pollChild(pid, start, task.timeoutS)) && !gInterrupted)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!ended) {
    runner_detail::stopChildren({pid});
    return 128 + gInterrupted;
  }
  writeOutcome(task.outcomeFile, *ended);
  return 0;
}

// --- Submission and collection ---------------------------------------------------------------

namespace {

/// Runs a program to its end (at most `timeoutS`), its output into `log`; its wait status.
int runProgram(const fs::path& program, const std::vector<std::string>& arguments,
               const fs::path& log, double timeoutS) {
  std::string error;
  const auto start = Clock::now();
  const pid_t pid = runner_detail::spawnRun(program.string(), arguments, log, error, log);
  if (pid < 0) return -1;
  std::optional<Ended> ended;
  while (!(ended = runner_detail::pollChild(pid, start, timeoutS)))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return ended->status;
}

/// The job id that `sbatch --parsable` printed (`ID` or `ID;CLUSTER`); empty before it did.
std::string jobIdOf(const fs::path& sbatchOut) {
  const std::string text = readFile(sbatchOut);
  if (text.find('\n') == std::string::npos) return "";
  return trimmed(text.substr(0, text.find_first_of(";\n")));
}

/// The last non-empty line of a file.
std::string lastLineOf(const fs::path& file) {
  std::istringstream in(readFile(file));
  std::string last;
  for (std::string line; std::getline(in, line);)
    if (!trimmed(line).empty()) last = trimmed(line);
  return oneLine(last);
}

/// The task list and batch script for the pending runs; runs that cannot be prepared are
/// reported through `finished` at once, as the local executor does.
struct Submission {
  SlurmJob job;
  std::vector<SlurmTask> tasks;
  std::vector<std::size_t> runOf;  ///< the run (index into the grid) of each task
};

Submission prepareSubmission(const ExperimentConfig& config, const ExperimentOptions& options,
                             const std::vector<ExperimentRun>& runs, const fs::path& dir,
                             const std::vector<std::size_t>& pending,
                             const std::function<void(std::size_t, const Outcome&)>& finished) {
  std::error_code ec;
  const fs::path slurmDir = fs::absolute(dir / "slurm", ec);
  fs::remove_all(slurmDir / "outcomes", ec);  // those of an earlier submission
  createDirectories(slurmDir / "outcomes", "directory");
  Submission s;
  // The absolute path of the executable (/proc/self/exe means this process's own).
  fs::path executable = fs::canonical(options.executable, ec);
  if (ec) executable = fs::absolute(options.executable);
  for (const std::size_t i : pending) {
    const fs::path runDir = dir / "runs" / runs[i].id;
    SlurmTask task{runs[i].id,
                   runDir,
                   slurmDir / "outcomes" / (std::to_string(s.tasks.size()) + ".txt"),
                   config.timeoutS,
                   {executable.string()}};
    try {
      const std::vector<std::string> args =
          runner_detail::prepareRun(config, runs[i], runDir, options.jobs);
      task.command.insert(task.command.end(), args.begin(), args.end());
    } catch (const std::exception& e) {
      Outcome o;
      o.status = "error";
      o.error = oneLine(e.what());
      finished(i, o);
      continue;
    }
    s.tasks.push_back(task);
    s.runOf.push_back(i);
  }
  s.job.name = "ndcontour-" + config.id;
  s.job.executable = executable;
  s.job.tasksFile = slurmDir / "tasks.tsv";
  s.job.script = slurmDir / "job.sh";
  s.job.logDir = slurmDir;
  s.job.workDir = fs::current_path(ec);
  s.job.tasks = s.tasks.size();
  s.job.jobs = options.jobs;
  s.job.timeoutS = config.timeoutS;
  s.job.partition = options.slurmPartition;
  s.job.extraArgs = options.slurmArgs;
  std::string list;
  for (const SlurmTask& task : s.tasks) list += slurmTaskLine(task) + "\n";
  writeAtomically(s.job.tasksFile, list);
  if (!s.tasks.empty()) writeAtomically(s.job.script, slurmBatchScript(s.job));
  return s;
}

/// Waits for sbatch, reporting each task's outcome as it appears; cancels the job on an
/// interrupt. Returns the job id.
std::string waitForJob(const Submission& s, pid_t sbatch,
                       const std::function<void(std::size_t, const Outcome&)>& finished,
                       const std::function<void()>& tick) {
  const fs::path out = s.job.logDir / "sbatch.out", err = s.job.logDir / "sbatch.err";
  std::vector<bool> reported(s.tasks.size(), false);
  const auto collect = [&] {
    std::error_code ec;
    for (std::size_t t = 0; t < s.tasks.size(); ++t)
      if (!reported[t] && fs::exists(s.tasks[t].outcomeFile, ec)) {
        reported[t] = true;
        finished(s.runOf[t], readOutcome(s.tasks[t]));
      }
  };
  std::string jobId;
  std::optional<Ended> ended;
  {
    runner_detail::InterruptScope interrupts;
    const auto start = Clock::now();
    while (!gInterrupted && !(ended = runner_detail::pollChild(sbatch, start, 1e12))) {
      if (jobId.empty() && !(jobId = jobIdOf(out)).empty()) {
        std::fprintf(stderr, "slurm: submitted job %s: %zu tasks, at most %d at once (%s)\n",
                     jobId.c_str(), s.tasks.size(), std::max(1, s.job.jobs),
                     s.job.script.string().c_str());
        std::fflush(stderr);
      }
      collect();
      tick();
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
  if (jobId.empty()) jobId = jobIdOf(out);
  if (gInterrupted) {
    std::fprintf(stderr, "slurm: cancelling job %s\n", jobId.empty() ? "?" : jobId.c_str());
    const fs::path scancel = findOnPath("scancel");
    if (!jobId.empty() && !scancel.empty())
      runProgram(scancel, {jobId}, s.job.logDir / "scancel.log", 30);
    if (!ended) runner_detail::stopChildren({sbatch});
    return jobId;
  }
  if (jobId.empty())
    throw InputError("sbatch did not submit the job: " + lastLineOf(err) + " (" + err.string() +
                     ")");
  collect();
  for (std::size_t t = 0; t < s.tasks.size(); ++t)
    if (!reported[t]) {
      Outcome o;
      o.status = "error";
      o.error = "Slurm job " + jobId + " task " + std::to_string(t) + " recorded no outcome (see " +
                (s.job.logDir / ("task-" + std::to_string(t) + ".log")).string() + ")";
      finished(s.runOf[t], o);
    }
  std::fprintf(stderr, "slurm: job %s finished (sbatch exit status %d)\n", jobId.c_str(),
               WIFEXITED(ended->status) ? WEXITSTATUS(ended->status) : -1);
  std::fflush(stderr);
  return jobId;
}

/// Submits a prepared job array with sbatch and waits for it (waitForJob). Returns the job id
/// ("" when there was nothing to submit).
std::string submitAndWait(const Submission& s,
                          const std::function<void(std::size_t, const Outcome&)>& finished,
                          const std::function<void()>& tick) {
  if (s.tasks.empty()) {
    std::fprintf(stderr, "slurm: nothing to submit\n");
    std::fflush(stderr);
    return "";
  }
  std::string error;
  const pid_t pid =
      runner_detail::spawnRun(findOnPath("sbatch").string(), sbatchArguments(s.job),
                              s.job.logDir / "sbatch.err", error, s.job.logDir / "sbatch.out");
  if (pid < 0) throw InputError(error);
  return waitForJob(s, pid, finished, tick);
}

}  // namespace

namespace runner_detail {

std::string runOnSlurm(const ExperimentConfig& config, const ExperimentOptions& options,
                       const std::vector<ExperimentRun>& runs, const fs::path& dir,
                       const std::vector<std::size_t>& pending,
                       const std::function<void(std::size_t, const Outcome&)>& finished,
                       const std::function<void()>& tick) {
  if (findOnPath("sbatch").empty()) throw UsageError("--executor slurm: sbatch not found on PATH");
  // Every run finished before: the files of the latest submission stay as they are.
  const Submission s = pending.empty()
                           ? Submission{}
                           : prepareSubmission(config, options, runs, dir, pending, finished);
  return submitAndWait(s, finished, tick);
}

std::string runTasksOnSlurm(SlurmJob job, const std::vector<SlurmTask>& tasks,
                            const std::function<void(std::size_t, const Outcome&)>& finished,
                            const std::function<void()>& tick) {
  if (findOnPath("sbatch").empty()) throw UsageError("--executor slurm: sbatch not found on PATH");
  Submission s;
  s.tasks = tasks;
  for (std::size_t t = 0; t < tasks.size(); ++t) s.runOf.push_back(t);
  job.tasksFile = job.logDir / "tasks.tsv";
  job.script = job.logDir / "job.sh";
  job.tasks = tasks.size();
  s.job = std::move(job);
  std::string list;
  for (const SlurmTask& task : s.tasks) list += slurmTaskLine(task) + "\n";
  writeAtomically(s.job.tasksFile, list);
  if (!s.tasks.empty()) writeAtomically(s.job.script, slurmBatchScript(s.job));
  return submitAndWait(s, finished, tick);
}

}  // namespace runner_detail

}  // namespace ndc
