// A list of commands, run as the experiment runner runs its solves (tasks.hpp).
#include "experiments/runner/tasks.hpp"

#include <chrono>
#include <thread>

#include "experiments/runner/runner_internal.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

namespace {

namespace fs = std::filesystem;
using runner_detail::Clock;
using runner_detail::gInterrupted;
using runner_detail::Outcome;

TaskOutcome taskOutcome(const Outcome& o) { return {o.status, o.exitCode, o.error, o.seconds}; }

/// The tasks as child processes of this one, `jobs` at once, in order.
void runLocally(const std::vector<SlurmTask>& tasks, int jobs,
                const std::function<void(std::size_t, const Outcome&)>& finished) {
  struct Child {
    pid_t pid;
    std::size_t task;
    Clock::time_point start;
  };
  std::vector<Child> running;
  std::size_t next = 0;
  {
    runner_detail::InterruptScope interrupts;
    while ((next < tasks.size() || !running.empty()) && !gInterrupted) {
      // Start tasks in order while there is room.
      while (static_cast<int>(running.size()) < jobs && next < tasks.size()) {
        const SlurmTask& task = tasks[next];
        std::string error;
        const std::vector<std::string> arguments(task.command.begin() + 1, task.command.end());
        const pid_t pid = runner_detail::spawnRun(task.command.front(), arguments,
                                                  task.runDir / "stderr.txt", error);
        if (pid < 0) {
          Outcome o;
          o.status = "error";
          o.error = oneLine(error);
          finished(next++, o);
          continue;
        }
        running.push_back({pid, next++, Clock::now()});
      }
      // Collect the children that ended (or ran past their timeout).
      bool ended = false;
      for (auto it = running.begin(); it != running.end();) {
        const SlurmTask& task = tasks[it->task];
        const auto end = runner_detail::pollChild(it->pid, it->start, task.timeoutS);
        if (!end) {
          ++it;
          continue;
        }
        finished(it->task, runner_detail::outcomeOfEnded(task.runDir, *end, task.timeoutS));
        it = running.erase(it);
        ended = true;
      }
      if (!ended) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  if (!gInterrupted) return;
  std::vector<pid_t> pids;
  for (const Child& child : running) pids.push_back(child.pid);
  runner_detail::stopChildren(pids);
}

}  // namespace

std::vector<std::string> solveArguments(const std::string& problem, const std::string& outDir,
                                        const Settings& settings) {
  return runner_detail::solveArguments(problem, outDir, settings, false);
}

std::vector<TaskOutcome> runTasks(
    const std::vector<SlurmTask>& tasks, const TaskExecutor& executor,
    const std::function<void(std::size_t, const TaskOutcome&)>& finished) {
  std::vector<TaskOutcome> outcomes(tasks.size());
  std::vector<bool> done(tasks.size(), false);
  const auto record = [&](std::size_t t, const Outcome& o) {
    outcomes[t] = taskOutcome(o);
    done[t] = true;
    if (finished) finished(t, outcomes[t]);
  };
  gInterrupted = 0;
  if (executor.slurm) {
    SlurmJob job;
    job.name = executor.name;
    std::error_code ec;
    job.executable = tasks.empty() ? fs::path() : fs::path(tasks.front().command.front());
    job.logDir = fs::absolute(executor.logDir, ec);
    createDirectories(job.logDir, "directory");
    job.workDir = fs::current_path(ec);
    job.jobs = std::max(1, executor.jobs);
    for (const SlurmTask& task : tasks) job.timeoutS = std::max(job.timeoutS, task.timeoutS);
    job.partition = executor.partition;
    job.extraArgs = executor.slurmArgs;
    runner_detail::runTasksOnSlurm(job, tasks, record, [] {});
  } else {
    runLocally(tasks, std::max(1, executor.jobs), record);
  }
  if (gInterrupted) throw InputError("interrupted: the tasks still running were stopped");
  for (std::size_t t = 0; t < tasks.size(); ++t)
    if (!done[t]) record(t, Outcome{"error", std::nullopt, "the task did not run", false, 0, {}});
  return outcomes;
}

}  // namespace ndc
