// `ndcontour solve --split S` (docs/split.md): the pieces as `ndcontour solve --domain` runs of
// the experiment runner's executors, glued into one result that is reported as a solve's.
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "experiments/cli/commands.hpp"
#include "experiments/runner/tasks.hpp"
#include "framework/io/io.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/budget.hpp"
#include "framework/util/errors.hpp"
#include "pipeline/split.hpp"

namespace ndc::cli {

namespace {

namespace fs = std::filesystem;

/// A temporary folder for the pieces of a split solve without `--out`, removed with the object.
class TemporaryFolder {
 public:
  TemporaryFolder() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/ndcontour-split-XXXXXX";
    if (!::mkdtemp(pattern.data()))
      throw InputError(pattern +
                       ": cannot create a temporary folder for the pieces: " + failureReason());
    path_ = pattern;
  }
  ~TemporaryFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// The words of `--slurm-args`.
std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

/// The number as a command-line word that reads back to the same value.
std::string word(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

/// The `ndcontour solve` of piece p: the run's own arguments (as the experiment runner writes
/// them) at the piece's depth, on one thread, with the memory budget shared by the pieces that
/// run at once on this machine (a Slurm node has its own: the user's --max-memory, if any,
/// applies to each task), then the piece's box, its maximum depth and the chord tolerance.
std::vector<std::string> pieceCommand(const SolveOptions& o, const SplitPlan& plan, std::size_t p,
                                      const fs::path& dir, int atOnce) {
  Settings s = o.settings;
  s.depth = plan.pieceDepth;
  s.threads = 1;
  if (o.executor == "local")
    s.maxMemoryBytes = static_cast<std::uint64_t>(
        static_cast<double>(s.maxMemoryBytes ? s.maxMemoryBytes : defaultMemoryBudget()) / atOnce);
  std::error_code ec;
  fs::path executable = fs::canonical("/proc/self/exe", ec);
  if (ec) executable = "ndcontour";
  std::vector<std::string> c = {executable.string()};
  for (std::string& a : solveArguments(fs::absolute(o.problemPath).string(), dir.string(), s))
    c.push_back(std::move(a));
  c.insert(c.end(), {"--domain", domainText(plan.boxes[p]), "--max-depth",
                     std::to_string(plan.pieceMaxDepth)});
  if (o.tolerance) c.insert(c.end(), {"--tolerance", word(*o.tolerance)});
  return c;
}

/// Checks the options that `--split` cannot take or needs.
void checkSplitOptions(const SolveOptions& o) {
  if (o.executor != "local" && o.executor != "slurm")
    throw UsageError("--executor: unknown executor '" + o.executor + "' (accepted: local, slurm)");
  if (o.executor == "local" && (!o.slurmPartition.empty() || !o.slurmArgs.empty()))
    throw UsageError("--slurm-partition and --slurm-args need --executor slurm");
  if (o.executor == "slurm" && !o.outDir)
    throw UsageError(
        "--executor slurm needs --out: the pieces are written where the nodes can "
        "read them back");
  if (o.cells)
    throw UsageError(
        "--cells cannot be used with --split (each piece's cells.csv would index "
        "its own grid)");
  if (o.domain) throw UsageError("--domain cannot be used with --split");
}

/// Shows the pieces that have ended, on a terminal only and not with `--json` (contracts 4.2).
void showProgress(std::size_t done, std::size_t total, bool quiet) {
  if (quiet || !::isatty(STDERR_FILENO)) return;
  std::fprintf(stderr, "\rpieces       %zu of %zu solved", done, total);
  if (done == total) std::fputs("\n", stderr);
  std::fflush(stderr);
}

}  // namespace

int runSplitSolve(const SolveOptions& options, const Problem& problem) {
  checkSplitOptions(options);
  const auto start = std::chrono::steady_clock::now();
  const SplitPlan plan = planSplit(problem, options.settings, *options.split);
  if (options.outDir) checkWritable(*options.outDir);
  installInterruptCleanup();
  // `--timeout` for the whole split solve; each piece has the same limit of its own. (No
  // address-space limit here: the pieces would inherit it.)
  if (options.settings.timeoutSeconds)
    armTimeout(*options.settings.timeoutSeconds,
               problem.path + ": stopped by --timeout after " +
                   word(*options.settings.timeoutSeconds) + " s",
               kExitTimeout);
  // The pieces' folders: `--out`/pieces.partial while they run, `--out`/pieces once glued (a
  // failed run leaves pieces.partial to look into and the previous outputs as they were).
  std::optional<TemporaryFolder> temporary;
  if (!options.outDir) temporary.emplace();
  const fs::path base = options.outDir ? fs::absolute(*options.outDir) : temporary->path();
  const fs::path partial = base / "pieces.partial", final = base / "pieces";
  std::error_code ec;
  fs::remove_all(partial, ec);
  const int atOnce = options.executor == "local"
                         ? std::max(1, effectiveThreads(options.settings.threads))
                         : static_cast<int>(plan.boxes.size());
  std::vector<SlurmTask> tasks;
  const double timeout = options.settings.timeoutSeconds.value_or(kMaxTimeoutSeconds);
  for (std::size_t p = 0; p < plan.boxes.size(); ++p) {
    char name[32];
    std::snprintf(name, sizeof name, "piece-%03zu", p);
    const fs::path dir = partial / name;
    fs::create_directories(dir, ec);
    if (ec) throw InputError(dir.string() + ": cannot create the directory: " + ec.message());
    tasks.push_back({name, dir, partial / "outcomes" / (std::string(name) + ".txt"), timeout,
                     pieceCommand(options, plan, p, dir, atOnce)});
  }
  fs::create_directories(partial / "outcomes", ec);
  // Run the pieces and read back what each left.
  TaskExecutor executor;
  executor.slurm = options.executor == "slurm";
  executor.jobs = atOnce;
  executor.name = "ndcontour-split-" + problem.name;
  executor.logDir = partial / "slurm";
  executor.partition = options.slurmPartition;
  executor.slurmArgs = words(options.slurmArgs);
  std::size_t done = 0;
  const std::vector<TaskOutcome> outcomes = runTasks(
      tasks, executor,
      [&](std::size_t, const TaskOutcome&) { showProgress(++done, tasks.size(), options.json); });
  std::vector<PieceOutput> pieces;
  for (std::size_t p = 0; p < tasks.size(); ++p) {
    if (outcomes[p].status != "ok")
      throw InputError(problem.path + ": --split: piece " + std::to_string(p) + " (" +
                       domainText(plan.boxes[p]) + ") " + outcomes[p].status +
                       (outcomes[p].error.empty() ? "" : ": " + outcomes[p].error) + " (see " +
                       (tasks[p].runDir / "stderr.txt").string() + ")");
    pieces.push_back(readPiece(tasks[p].runDir, plan.boxes[p]));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RunResult result = mergePieces(problem, options.settings, plan, pieces, seconds);
  if (!options.outDir) disarmTimeout();
  // The pieces' folders in place of the previous run's, then the glued outputs.
  fs::remove_all(final, ec);
  fs::rename(partial, final, ec);
  if (ec) throw InputError(final.string() + ": cannot write the folder: " + ec.message());
  return reportSolve(options, problem, result);
}

}  // namespace ndc::cli
