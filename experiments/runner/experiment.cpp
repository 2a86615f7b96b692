// Experiments (experiment.hpp, docs/experiments.md): the scheduler of the runs, progress,
// resume, the combined CSV and runExperiment.
#include "experiments/runner/experiment.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "experiments/runner/runner_internal.hpp"
#include "framework/io/io.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/budget.hpp"
#include "framework/problem/expectation.hpp"
#include "framework/util/errors.hpp"

namespace ndc {
namespace fs = std::filesystem;
using runner_detail::Clock;
using runner_detail::gInterrupted;
using runner_detail::InterruptScope;
using runner_detail::jsonNumber;
using runner_detail::Outcome;
using runner_detail::prepareRun;
using runner_detail::provenanceJson;
using runner_detail::readFile;
using runner_detail::readSummary;
using runner_detail::shellWord;
using runner_detail::solveArguments;
using runner_detail::spawnRun;
using runner_detail::stopChildren;
using runner_detail::Tally;
using runner_detail::utcNow;

// --- Small helpers -------------------------------------------------------------------------

namespace runner_detail {

std::string shellWord(const std::string& s) {
  const bool plain = !s.empty() && s.find_first_not_of(
                                       "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                       "0123456789_-./=:+@%,") == std::string::npos;
  if (plain) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string readFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Shortest decimal text that reads back as the same double ("null" when not finite).
std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buffer[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
    if (std::strtod(buffer, nullptr) == v) break;
  }
  return buffer;
}

}  // namespace runner_detail

namespace {

/// A CSV field (RFC 4180): quoted when it holds a comma, quote or line break.
std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

namespace runner_detail {

std::vector<std::string> prepareRun(const ExperimentConfig& config, const ExperimentRun& run,
                                    const fs::path& runDir, int jobs) {
  const ExperimentProblem& p = config.problems[run.problem];
  createDirectories(runDir, "run directory");
  // The command that repeats this run by hand, from the repository root.
  std::string command = "ndcontour";
  for (const std::string& a : solveArguments(p.file, runDir.string(), run.settings, config.cells)) {
    command += ' ';
    command += shellWord(a);
  }
  writeAtomically(runDir / "command.txt", command + "\n");
  // Runs at once share the machine's memory budget.
  Settings shared = run.settings;
  shared.maxMemoryBytes =
      std::max<std::uint64_t>(defaultMemoryBudget() / std::max(1, jobs), 1u << 30);
  // And its cores: jobs x threads stays at the hardware threads.
  shared.threads = std::max(1, effectiveThreads(0) / std::max(1, jobs));
  return solveArguments(p.path.string(), runDir.string(), shared, config.cells);
}

}  // namespace runner_detail

// --- Runner ----------------------------------------------------------------------------------

namespace {

/// Progress on standard error: a redrawn bar on a terminal, else one line per finished run.
class ProgressReport {
 public:
  ProgressReport(std::size_t total, std::size_t done, std::size_t failed)
      : tty_(::isatty(STDERR_FILENO) == 1),
        total_(total),
        done_(done),
        failed_(failed),
        start_(Clock::now()) {}

  void finished(const std::string& run, const Outcome& o) {
    ++done_;
    ++ran_;
    if (o.status != "ok") ++failed_;
    if (tty_) {
      if (o.status != "ok") {
        std::fprintf(stderr, "\r\033[K%s: %s: %s\n", run.c_str(), o.status.c_str(),
                     o.error.c_str());
      }
      draw();
    } else {
      std::fprintf(stderr, "[%zu/%zu] %s %.2f s %s%s%s\n", done_, total_, o.status.c_str(),
                   o.seconds, run.c_str(), o.error.empty() ? "" : ": ", o.error.c_str());
    }
    std::fflush(stderr);
  }

  /// Redraws the bar (terminal only) at most five times a second.
  void tick() {
    if (!tty_ || Clock::now() - lastDraw_ < std::chrono::milliseconds(200)) return;
    draw();
  }

  void end() {
    if (tty_) std::fputs("\n", stderr);
    std::fflush(stderr);
  }

 private:
  void draw() {
    lastDraw_ = Clock::now();
    const int width = 30;
    const int filled = total_ ? static_cast<int>(width * done_ / total_) : width;
    std::string bar(filled, '#');
    bar.resize(width, '.');
    std::string eta = "eta ?";
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    if (ran_ > 0)
      eta = "eta " + std::to_string(static_cast<long>(elapsed / ran_ * (total_ - done_) + 0.5)) +
            " s";
    std::fprintf(stderr, "\r[%s] %zu/%zu runs, %zu failed, %s\033[K", bar.c_str(), done_, total_,
                 failed_, eta.c_str());
    std::fflush(stderr);
  }

  bool tty_;
  std::size_t total_, done_, failed_, ran_ = 0;
  Clock::time_point start_, lastDraw_{};
};

/// The `expect_ok` and `expect_notes` columns of a run: the problem's `[expect]` compared with
/// the mesh of its summary by checkExpectation, as `solve` does (recomputed here, so summaries
/// of earlier invocations get them too). `expect_ok` is `true` or `false` (a compared key
/// differs; empty when no key could be compared), `expect_notes` lists the keys that differ or
/// could not be compared; both are empty when the problem has no `[expect]` or the run has no
/// summary.
std::pair<std::string, std::string> expectationColumns(const ExperimentProblem& p,
                                                       const Outcome& o) {
  const Expectation& x = p.expect;
  if (o.status != "ok" || x.empty()) return {};
  const std::map<std::string, std::string> values(o.values.begin(), o.values.end());
  // The mesh statistics of the summary (kSummaryFields). A field of the contract (4.3) must be
  // there; an extension (4.5) only when [expect] names it: a summary written before it cannot be
  // compared on it.
  MeshStats m;
  for (const SummaryField& f : kSummaryFields) {
    if (!f.meshStat) continue;
    const auto it = values.find(std::string(f.path));
    if (it == values.end() || it->second.empty()) {
      if (!f.extension || x.other.count(std::string(f.path.substr(f.path.rfind('.') + 1))))
        return {};
      continue;
    }
    try {
      m.*f.meshStat = std::stoll(it->second);
    } catch (const std::exception&) {
      return {};
    }
  }
  // The Betti numbers: list elements `mesh.betti.0` .. (absent from older summaries).
  for (auto [list, path] : {std::pair{&m.betti, "mesh.betti."}, {&m.bettiZ2, "mesh.betti_z2."}}) {
    for (auto it = values.find(path + std::string("0")); it != values.end();
         it = values.find(path + std::to_string(list->size()))) {
      try {
        list->push_back(std::stoll(it->second));
      } catch (const std::exception&) {
        return {};
      }
    }
  }
  const std::vector<ExpectCheck> checks = checkExpectation(x, m, p.k);
  std::string notes;
  bool compared = false;
  for (const ExpectCheck& check : checks) {
    compared = compared || check.notComparable.empty();
    if (!check.ok) notes += (notes.empty() ? "" : "; ") + describeCheck(check);
  }
  if (!compared) return {"", notes};
  return {expectationMismatch(checks) ? "false" : "true", notes};
}

void writeCsv(const fs::path& file, const ExperimentConfig& c,
              const std::vector<ExperimentRun>& runs, const std::vector<Outcome>& outcomes) {
  // Columns: the run's identity, then the known summary numbers, then any others (sorted).
  std::vector<std::string> columns(kExperimentSummaryColumns.begin(),
                                   kExperimentSummaryColumns.end());
  // A list element has a number in its path (`diagnostics.singular_points.0.sigma_min`): lists
  // vary in length from run to run and stay in the run's files.
  const auto listElement = [](const std::string& name) {
    std::istringstream parts(name);
    for (std::string part; std::getline(parts, part, '.');)
      if (!part.empty() && std::all_of(part.begin(), part.end(),
                                       [](unsigned char ch) { return std::isdigit(ch) != 0; }))
        return true;
    return false;
  };
  std::set<std::string> extra;
  for (const Outcome& o : outcomes)
    for (const auto& [name, value] : o.values)
      if (name != "n" && name != "k" && name.rfind("settings.", 0) != 0 &&
          name.rfind("expect.", 0) != 0 && !listElement(name) &&
          std::find(columns.begin(), columns.end(), name) == columns.end())
        extra.insert(name);
  columns.insert(columns.end(), extra.begin(), extra.end());

  std::ostringstream csv;
  for (std::size_t i = 0; i < kExperimentRunColumns.size(); ++i)
    csv << (i ? "," : "") << kExperimentRunColumns[i];
  for (const std::string& name : columns) csv << ',' << name;
  csv << '\n';
  const auto optional = [](const auto& v) { return v ? std::to_string(*v) : std::string(); };
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const ExperimentRun& run = runs[r];
    const ExperimentProblem& p = c.problems[run.problem];
    const Settings& s = run.settings;
    const Outcome& o = outcomes[r];
    const auto [expectOk, expectNotes] = expectationColumns(p, o);
    const std::vector<std::string> fields = {c.id,
                                             run.id,
                                             p.name,
                                             p.file,
                                             std::to_string(p.n),
                                             std::to_string(p.k),
                                             std::to_string(s.depth),
                                             optional(s.jitter),
                                             s.scalar,
                                             std::to_string(s.precisionBits),
                                             s.bounding,
                                             s.subdivision,
                                             s.projection,
                                             s.classification,
                                             s.connection,
                                             o.status,
                                             optional(o.exitCode),
                                             o.error,
                                             optional(p.expect.components),
                                             optional(p.expect.eulerCharacteristic),
                                             expectOk,
                                             expectNotes};
    for (std::size_t i = 0; i < fields.size(); ++i) csv << (i ? "," : "") << csvField(fields[i]);
    const std::map<std::string, std::string> values(o.values.begin(), o.values.end());
    for (const std::string& name : columns) {
      const auto it = values.find(name);
      csv << ',' << (it == values.end() ? "" : csvField(it->second));
    }
    csv << '\n';
  }
  writeAtomically(file, csv.str());
}

/// Generated problems become files beside the results, so that each run can be repeated with
/// `ndcontour solve`; an identical existing file is left alone.
void writeGeneratedProblems(ExperimentConfig& config, const fs::path& dir) {
  std::error_code ec;
  for (ExperimentProblem& p : config.problems) {
    if (p.generatedText.empty()) continue;
    fs::create_directories(dir / "problems", ec);
    p.path = dir / "problems" / (p.name + ".toml");
    p.file = p.path.generic_string();
    if (!fs::exists(p.path, ec) || readFile(p.path) != p.generatedText)
      writeAtomically(p.path, p.generatedText);
  }
}

/// Resume: a run whose folder has a summary (and cells.csv when the config asks for `cells`)
/// finished before; its outcome is read back. Returns the runs still to do, in grid order.
std::vector<std::size_t> resumeFinished(const std::vector<ExperimentRun>& runs,
                                        const fs::path& runsDir, bool cells,
                                        std::vector<Outcome>& outcomes, Tally& tally) {
  std::error_code ec;
  std::vector<std::size_t> pending;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const fs::path runDir = runsDir / runs[i].id;
    if (fs::exists(runDir / "summary.json", ec) &&
        (!cells || fs::exists(runDir / "cells.csv", ec))) {
      outcomes[i] = readSummary(runDir);
      outcomes[i].skipped = true;
      ++tally.skipped;
    } else {
      pending.push_back(i);
    }
  }
  return pending;
}

/// Runs the pending runs as child processes, `jobs` at once, each within the timeout, until
/// all finished or SIGINT / SIGTERM arrives.
class Scheduler {
 public:
  Scheduler(const ExperimentConfig& config, const ExperimentOptions& options,
            const std::vector<ExperimentRun>& runs, const fs::path& runsDir,
            std::vector<Outcome>& outcomes, ProgressReport& progress)
      : config_(config),
        options_(options),
        runs_(runs),
        runsDir_(runsDir),
        outcomes_(outcomes),
        progress_(progress),
        jobs_(std::max(1, options.jobs)) {}

  /// Runs `pending`; on an interrupt the children still running are stopped.
  void run(const std::vector<std::size_t>& pending) {
    std::size_t next = 0;
    {
      InterruptScope interrupts;
      while ((next < pending.size() || !running_.empty()) && !gInterrupted) {
        // Start runs in grid order while there is room.
        while (static_cast<int>(running_.size()) < jobs_ && next < pending.size() && !gInterrupted)
          start(pending[next++]);
        if (!collect()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
          progress_.tick();
        }
      }
    }
    if (!gInterrupted) return;
    std::vector<pid_t> pids;
    for (const Child& child : running_) pids.push_back(child.pid);
    stopChildren(pids);
  }

 private:
  struct Child {
    pid_t pid;
    std::size_t run;
    Clock::time_point start;
  };

  /// Starts run i (its folder, its command.txt, the child), or records why it could not.
  void start(std::size_t i) {
    const ExperimentRun& run = runs_[i];
    const fs::path runDir = runsDir_ / run.id;
    std::string error;
    pid_t pid = -1;
    try {
      pid = spawnRun(options_.executable, prepareRun(config_, run, runDir, jobs_),
                     runDir / "stderr.txt", error);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (pid < 0) {
      outcomes_[i].status = "error";
      outcomes_[i].error = oneLine(error);
      progress_.finished(run.id, outcomes_[i]);
      return;
    }
    running_.push_back({pid, i, Clock::now()});
  }

  /// Collects finished children and kills those past the timeout; whether any ended.
  bool collect() {
    bool changed = false;
    for (auto it = running_.begin(); it != running_.end();) {
      const std::optional<runner_detail::Ended> ended =
          runner_detail::pollChild(it->pid, it->start, config_.timeoutS);
      if (!ended) {
        ++it;
        continue;
      }
      const fs::path runDir = runsDir_ / runs_[it->run].id;
      outcomes_[it->run] = runner_detail::outcomeOfEnded(runDir, *ended, config_.timeoutS);
      progress_.finished(runs_[it->run].id, outcomes_[it->run]);
      it = running_.erase(it);
      changed = true;
    }
    return changed;
  }

  const ExperimentConfig& config_;
  const ExperimentOptions& options_;
  const std::vector<ExperimentRun>& runs_;
  const fs::path& runsDir_;
  std::vector<Outcome>& outcomes_;
  ProgressReport& progress_;
  const int jobs_;
  std::vector<Child> running_;
};

/// The combined CSV, the provenance and the closing lines on standard output; the exit status.
int finishExperiment(const ExperimentConfig& config, const ExperimentOptions& options,
                     const std::vector<ExperimentRun>& runs, const std::vector<Outcome>& outcomes,
                     Tally& tally, const fs::path& dir, const std::string& started) {
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!outcomes[i].skipped) ++tally.ran;
    if (outcomes[i].status != "ok") {
      ++tally.failed;
      tally.failedRuns.push_back(runs[i].id);
    }
  }
  const fs::path csv = dir / (config.id + ".csv");
  writeCsv(csv, config, runs, outcomes);
  writeAtomically(dir / "provenance.json", provenanceJson(config, options, tally, started));

  std::printf("experiment %s: %zu runs: %zu ran, %zu skipped (finished before), %zu failed\n",
              config.id.c_str(), tally.total, tally.ran, tally.skipped, tally.failed);
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (outcomes[i].status != "ok")
      std::printf("  failed: %s: %s%s%s\n", runs[i].id.c_str(), outcomes[i].status.c_str(),
                  outcomes[i].error.empty() ? "" : ": ", outcomes[i].error.c_str());
  std::printf("wrote %s and %s\n", csv.string().c_str(),
              (dir / "provenance.json").string().c_str());
  std::fflush(stdout);
  return tally.failed ? 1 : 0;
}

}  // namespace

int runExperiment(ExperimentConfig config, const ExperimentOptions& options) {
  const std::string started = utcNow();
  const fs::path dir = options.outDir / config.id;
  const fs::path runsDir = dir / "runs";
  createDirectories(runsDir, "output directory");
  writeGeneratedProblems(config, dir);

  const std::vector<ExperimentRun> runs = experimentGrid(config);
  std::vector<Outcome> outcomes(runs.size());
  Tally tally;
  tally.total = runs.size();
  const std::vector<std::size_t> pending =
      resumeFinished(runs, runsDir, config.cells, outcomes, tally);
  std::size_t failedBefore = 0;
  for (const Outcome& o : outcomes)
    if (o.skipped && o.status != "ok") ++failedBefore;
  std::fprintf(stderr,
               "experiment %s%s: %zu runs, %zu finished before, %d at once%s, timeout %s s\n",
               config.id.c_str(), config.quick ? " (quick)" : "", runs.size(), tally.skipped,
               std::max(1, options.jobs), options.executor == Executor::slurm ? " on Slurm" : "",
               jsonNumber(config.timeoutS).c_str());
  std::fflush(stderr);

  ProgressReport progress(runs.size(), tally.skipped, failedBefore);
  if (options.executor == Executor::slurm) {
    const auto finished = [&](std::size_t i, const Outcome& o) {
      outcomes[i] = o;
      progress.finished(runs[i].id, o);
    };
    tally.slurmTasks = pending.size();
    tally.slurmJobId = runner_detail::runOnSlurm(config, options, runs, dir, pending, finished,
                                                 [&] { progress.tick(); });
  } else {
    Scheduler(config, options, runs, runsDir, outcomes, progress).run(pending);
  }
  progress.end();
  if (gInterrupted) {
    // Finished runs keep their summaries; the rest run on the next invocation.
    std::fprintf(stderr,
                 "experiment %s: interrupted; finished runs are kept and the next invocation "
                 "resumes\n",
                 config.id.c_str());
    return 128 + gInterrupted;
  }
  return finishExperiment(config, options, runs, outcomes, tally, dir, started);
}

}  // namespace ndc
