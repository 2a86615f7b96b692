// `--threads N`: the outputs do not depend on the number of threads (docs/performance.md,
// "Threads"). The tool runs as a process with 1, 2 and 3 threads (3 oversubscribes a 2-core
// machine, so tasks are interleaved and stolen differently), and every output file is compared
// byte for byte; of summary.json only the wall times (`timing_s`) and `settings.threads` may
// differ.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <random>
#include <regex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "applications/load.hpp"
#include "framework/numeric/parallel.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/test_process.hpp"

namespace fs = std::filesystem;

namespace {

using ndc::test::quoted;
using ndc::test::slurp;

/// The output files a solve may write into --out (with --ascii --cells).
const std::vector<std::string> kOutputs = {"mesh.ply",    "cells.csv",       "singular.csv",
                                           "input.ply",   "uncertified.csv", "ruled.ply",
                                           "summary.json"};

/// summary.json without what may depend on the thread count: the line of `timing_s` (wall
/// times) and the value of `settings.threads`.
std::string comparable(const std::string& summary) {
  static const std::regex timing("\n  \"timing_s\": [^\n]*");
  static const std::regex threads("\"threads\": [0-9]+");
  return std::regex_replace(std::regex_replace(summary, timing, ""), threads, "\"threads\": _");
}

/// Solves `problem` (a file of experiments/problems) with `options` and `--threads threads`
/// into scratch/out-THREADS; returns the output folder.
fs::path solve(const fs::path& scratch, const std::string& problem, const std::string& options,
               int threads) {
  const fs::path out = scratch / ("out-" + std::to_string(threads));
  fs::remove_all(out);
  const fs::path file = fs::path(ndc::test::sourceDir()) / "experiments/problems" / problem;
  const auto run = ndc::test::runNdcontour(
      "solve " + quoted(file.string()) + " " + options + " --ascii --cells --threads " +
          std::to_string(threads) + " --out " + quoted(out.string()),
      scratch);
  INFO(run.err);
  REQUIRE(run.status == 0);
  return out;
}

/// Every output of `--threads 2` and `--threads 3` equals that of `--threads 1`.
void sameWhateverThreads(const std::string& problem, const std::string& options) {
  INFO(problem << " " << options);
  ndc::test::ScratchDir scratch("threads");
  const fs::path one = solve(scratch.path(), problem, options, 1);
  const std::string summary = slurp(one / "summary.json");
  REQUIRE(summary.find("\"threads\": 1,") != std::string::npos);
  for (int threads : {2, 3}) {
    INFO("--threads " << threads);
    const fs::path other = solve(scratch.path(), problem, options, threads);
    CHECK(slurp(other / "summary.json").find("\"threads\": " + std::to_string(threads) + ",") !=
          std::string::npos);
    for (const std::string& name : kOutputs) {
      INFO(name);
      REQUIRE(fs::exists(one / name) == fs::exists(other / name));
      if (!fs::exists(one / name)) continue;
      if (name == "summary.json")
        CHECK(comparable(slurp(other / name)) == comparable(summary));
      else
        CHECK(slurp(other / name) == slurp(one / name));
    }
  }
}

}  // namespace

TEST_CASE("threads: a torus in R^3, outputs identical with 1, 2 and 3 threads", "[threads]") {
  sameWhateverThreads("torus.toml", "--depth 5");
}

TEST_CASE("threads: curves in R^2 and R^4, outputs identical with 1, 2 and 3 threads",
          "[threads]") {
  sameWhateverThreads("circle.toml", "--depth 6");
  sameWhateverThreads("space-curve-r4.toml", "--depth 5");
}

TEST_CASE("threads: surfaces in R^4 and R^6, outputs identical with 1, 2 and 3 threads",
          "[threads]") {
  sameWhateverThreads("clifford-torus.toml", "--depth 4");
  sameWhateverThreads("torus-r6.toml", "--depth 3");
}

TEST_CASE("threads: refinement, certified and not, outputs identical with 1, 2 and 3 threads",
          "[threads]") {
  // genus2 at depth 4 refines about 5000 cells to certify; at depth 5 without refinement it
  // is not certified (blocks, uncertified.csv).
  sameWhateverThreads("genus2.toml", "--depth 4");
  sameWhateverThreads("genus2.toml", "--depth 5 --max-depth 5");
}

TEST_CASE("threads: touch leaves added while the next window is solved, outputs identical",
          "[threads]") {
  // The torus in R^5 at depth 5 has about 11,700 leaves (three windows of the crossing walk),
  // and the walk of the last windows adds touch leaves (M meets excluded base cells at a face):
  // the walk defers them until the window solved beside it is done (docs/performance.md).
  sameWhateverThreads("torus-r5.toml", "--depth 5");
}

TEST_CASE("threads: MPFR at 200 bits, outputs identical with 1, 2 and 3 threads", "[threads]") {
  sameWhateverThreads("two-circles.toml", "--depth 5 --scalar mpfr --precision 200");
  sameWhateverThreads("clifford-torus.toml", "--depth 3 --scalar mpfr --precision 200");
}

TEST_CASE("threads: bisector application, outputs identical with 1, 2 and 3 threads", "[threads]") {
  sameWhateverThreads("bisector-fig8a.toml", "--depth 4");
}

TEST_CASE("threads: runPipeline gives the same result with 1 and 2 threads", "[threads]") {
  const ndc::Problem problem =
      ndc::loadProblem(fs::path(ndc::test::sourceDir()) / "experiments/problems/sphere-r4.toml");
  ndc::Settings settings;
  settings.depth = 4;
  settings.threads = 1;
  const ndc::RunResult one = ndc::runPipeline(problem, settings);
  settings.threads = 2;
  const ndc::RunResult two = ndc::runPipeline(problem, settings);
  CHECK(one.summary.settings.threads == 1);
  CHECK(two.summary.settings.threads == 2);
  CHECK(two.vertices == one.vertices);  // exact, not approximate
  CHECK(two.simplices == one.simplices);
  CHECK(two.cellIndex == one.cellIndex);
  CHECK(two.cellPoint == one.cellPoint);
  CHECK(two.summary.visited == one.summary.visited);
  CHECK(two.summary.topology.certified == one.summary.topology.certified);
  CHECK(two.summary.mesh.maxChordError == one.summary.mesh.maxChordError);
}

TEST_CASE("threads: threadScratch keeps one object per thread and user in double, none in MPFR",
          "[threads]") {
  struct User {};
  struct Other {};
  std::optional<std::vector<int>> fresh;
  std::vector<int>& mine = ndc::threadScratch<double, User>(fresh);
  CHECK(!fresh);  // double: nothing made in the caller's storage
  mine.assign(100, 7);
  const int* storage = mine.data();
  // The same object again on this thread, with its storage; another user has its own.
  CHECK(&ndc::threadScratch<double, User>(fresh) == &mine);
  CHECK(ndc::threadScratch<double, User>(fresh).data() == storage);
  CHECK(&ndc::threadScratch<double, Other>(fresh) != &mine);
  // Another thread has its own.
  const std::vector<int>* theirs = nullptr;
  std::thread([&] { theirs = &ndc::threadScratch<double, User>(fresh); }).join();
  CHECK(theirs != &mine);
  // MPFR: a new object in the caller's storage every time.
  std::optional<std::vector<int>> mpfr;
  std::vector<int>& made = ndc::threadScratch<ndc::Mpfr, User>(mpfr);
  REQUIRE(mpfr);
  CHECK(&made == &*mpfr);
  CHECK(made.empty());
}

TEST_CASE("threads: parallelSort gives std::sort's order on 1, 2 and 3 threads", "[threads]") {
  // Records with many equal keys and a unique tie-break (as the facet, edge and duplicate
  // sorts of the analysis have): the order is total, so every sort must give the same one.
  struct Record {
    std::uint64_t key;
    std::uint32_t index;
    bool operator==(const Record&) const = default;
  };
  const auto less = [](const Record& a, const Record& b) {
    return a.key != b.key ? a.key < b.key : a.index < b.index;
  };
  std::mt19937_64 rng(7);
  for (const std::size_t count :
       {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{300000}}) {
    std::vector<Record> records(count);
    for (std::size_t i = 0; i < count; ++i)
      records[i] = {rng() % (count / 8 + 1), static_cast<std::uint32_t>(i)};
    std::vector<Record> expected = records;
    std::sort(expected.begin(), expected.end(), less);
    for (const int threads : {1, 2, 3}) {
      std::vector<Record> sorted = records;
      ndc::withThreads(threads, [&] { ndc::parallelSort(sorted.begin(), sorted.end(), less); });
      CHECK(sorted == expected);
    }
  }
}

TEST_CASE("threads: a task beside the caller runs its loops, rethrows, and never outlives it",
          "[threads]") {
  for (const int threads : {1, 2, 3}) {
    INFO("threads " << threads);
    ndc::withThreads(threads, [&] {
      // The task's parallel loop fills its vector while the caller fills another.
      std::vector<std::uint64_t> beside(100000), caller(100000);
      ndc::TaskBeside task;
      task.start(
          [&] { ndc::parallelFor(beside.size(), [&](std::size_t i) { beside[i] = i * i; }); });
      for (std::size_t i = 0; i < caller.size(); ++i) caller[i] = i * i;
      task.wait();
      CHECK(beside == caller);
      // Its exception reaches wait(), and the task can start again afterwards.
      task.start([] { throw std::runtime_error("from the task"); });
      CHECK_THROWS_WITH(task.wait(), "from the task");
      int runs = 0;
      task.start([&] { ++runs; });
      task.wait();
      CHECK(runs == 1);
      // An exception in the caller while the task runs: the destructor waits for it.
      std::vector<int> done(64, 0);
      CHECK_THROWS_AS(
          [&] {
            ndc::TaskBeside running;
            running.start(
                [&] { ndc::parallelFor(done.size(), [&](std::size_t i) { done[i] = 1; }); });
            throw std::logic_error("from the caller");
          }(),
          std::logic_error);
    });
  }
}

TEST_CASE("threads: more threads than the hardware has run as asked, without a warning",
          "[threads][cli]") {
  ndc::test::ScratchDir scratch("threads-over");
  const int threads = static_cast<int>(std::thread::hardware_concurrency()) + 2;
  const fs::path file = fs::path(ndc::test::sourceDir()) / "experiments/problems/circle.toml";
  const auto run = ndc::test::runNdcontour(
      "solve " + quoted(file.string()) + " --depth 4 --json --threads " + std::to_string(threads) +
          " --out " + quoted((scratch.path() / "out").string()),
      scratch.path());
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.err.find("TBB") == std::string::npos);  // oneTBB's limit was raised, not hit
  // oneTBB has all of them: the arena reports its concurrency.
  ndc::withThreads(threads, [&] { CHECK(tbb::this_task_arena::max_concurrency() == threads); });
}

TEST_CASE("threads: --threads takes an integer from 1 to 4096, else exit 2 with one line",
          "[threads][cli]") {
  ndc::test::ScratchDir scratch("threads-cli");
  const std::string file =
      quoted(ndc::test::sourceDir() + "/experiments/problems/circle.toml") + " --depth 3";
  for (const std::string bad : {"0", "-1", "two", "4097", "1.5", ""}) {
    INFO("--threads '" << bad << "'");
    const auto run =
        ndc::test::runNdcontour("solve " + file + " --threads " + quoted(bad), scratch.path());
    CHECK(run.status == 2);
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
  }
  const auto run = ndc::test::runNdcontour("solve " + file + " --threads 1 --json", scratch.path());
  CHECK(run.status == 0);
  CHECK(run.out.find("\"threads\": 1,") != std::string::npos);
}
