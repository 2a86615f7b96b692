// The Slurm executor's pure parts (experiments/runner/slurm.hpp): the task list, the sbatch
// arguments and the batch script, one task run without Slurm, and the `--executor` option. The
// executor on a real cluster is tests/slurm_executor_test.sh (ctest test `slurm`).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "experiments/runner/slurm.hpp"
#include "framework/io/io.hpp"
#include "framework/util/errors.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& scratch() {
  static const ndc::test::ScratchDir dir("slurm");
  return dir.path();
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

ndc::SlurmJob sampleJob() {
  ndc::SlurmJob job;
  job.name = "ndcontour-tiny";
  job.executable = "/opt/nd contour/bin/ndcontour";
  job.tasksFile = "/shared/results/tiny/slurm/tasks.tsv";
  job.script = "/shared/results/tiny/slurm/job.sh";
  job.logDir = "/shared/results/tiny/slurm";
  job.workDir = "/shared/repo";
  job.tasks = 4;
  job.jobs = 2;
  job.timeoutS = 600;
  return job;
}

/// A task list of one task running `/bin/sh -c SCRIPT` in `dir`, within `timeoutS`.
fs::path shellTask(const fs::path& dir, const std::string& script, double timeoutS) {
  fs::create_directories(dir / "run");
  const ndc::SlurmTask task{
      "run", dir / "run", dir / "outcome.txt", timeoutS, {"/bin/sh", "-c", script}};
  ndc::writeAtomically(dir / "tasks.tsv", ndc::slurmTaskLine(task) + "\n");
  return dir / "tasks.tsv";
}

}  // namespace

TEST_CASE("slurm: a task line reads back whatever its fields hold", "[experiment][slurm]") {
  const ndc::SlurmTask task{"circle.L3.linearized.binary.newton.paper.crossing.double53",
                            "results/a b/runs/x",
                            "/abs/out\tcome\\n.txt",
                            0.25,
                            {"/usr/bin/ndcontour", "solve", "line\nbreak", "back\\slash", "cr\r"}};
  const std::string line = ndc::slurmTaskLine(task);
  CHECK(line.find('\n') == std::string::npos);
  CHECK(line.find('\r') == std::string::npos);
  const ndc::SlurmTask back = ndc::parseSlurmTaskLine(line);
  CHECK(back.run == task.run);
  CHECK(back.runDir == task.runDir);
  CHECK(back.outcomeFile == task.outcomeFile);
  CHECK(back.timeoutS == task.timeoutS);
  CHECK(back.command == task.command);
}

TEST_CASE("slurm: malformed task lines are errors", "[experiment][slurm]") {
  CHECK_THROWS_AS(ndc::parseSlurmTaskLine("run\tdir\toutcome\t5"), ndc::InputError);
  CHECK_THROWS_AS(ndc::parseSlurmTaskLine("run\tdir\toutcome\tsoon\t/bin/true"), ndc::InputError);
  CHECK_THROWS_AS(ndc::parseSlurmTaskLine("run\tdir\toutcome\t0\t/bin/true"), ndc::InputError);
  CHECK_THROWS_AS(ndc::parseSlurmTaskLine("run\tdir\\x\toutcome\t1\t/bin/true"), ndc::InputError);
  CHECK_THROWS_AS(ndc::parseSlurmTaskLine("run\tdir\toutcome\t1\t/bin/true\\"), ndc::InputError);
}

TEST_CASE("slurm: sbatch submits one throttled array and waits; user options come last",
          "[experiment][slurm]") {
  ndc::SlurmJob job = sampleJob();
  std::vector<std::string> a = ndc::sbatchArguments(job);
  const std::vector<std::string> expected = {"--parsable",
                                             "--wait",
                                             "--array=0-3%2",
                                             "--job-name=ndcontour-tiny",
                                             "--output=/shared/results/tiny/slurm/task-%a.log",
                                             "--chdir=/shared/repo",
                                             "--time=12",
                                             "/shared/results/tiny/slurm/job.sh"};
  CHECK(a == expected);
  job.partition = "short";
  job.extraArgs = {"--mem=4G", "--time=30"};
  job.timeoutS = 0.5;
  job.tasks = 1;
  a = ndc::sbatchArguments(job);
  CHECK(a[2] == "--array=0-0%2");
  CHECK(a[6] == "--time=3");
  CHECK(std::vector<std::string>(a.end() - 4, a.end()) ==
        std::vector<std::string>{"--partition=short", "--mem=4G", "--time=30",
                                 "/shared/results/tiny/slurm/job.sh"});
}

TEST_CASE("slurm: the batch script runs experiment-task with the array index",
          "[experiment][slurm]") {
  const std::string script = ndc::slurmBatchScript(sampleJob());
  CHECK(script.rfind("#!/bin/sh\n", 0) == 0);
  CHECK(contains(script, "#   sbatch --parsable --wait --array=0-3%2 "));
  CHECK(contains(script,
                 "\nexec '/opt/nd contour/bin/ndcontour' experiment-task "
                 "/shared/results/tiny/slurm/tasks.tsv \"$SLURM_ARRAY_TASK_ID\"\n"));
}

TEST_CASE("slurm: a task runs its command and records how it ended", "[experiment][slurm]") {
  SECTION("exit status and standard error") {
    const fs::path dir = scratch() / "failing";
    const fs::path tasks = shellTask(dir, "echo 'last words' >&2; exit 3", 60);
    CHECK(ndc::runSlurmTask(tasks, 0) == 0);
    const std::string outcome = ndc::test::slurp(dir / "outcome.txt");
    CHECK(contains(outcome, "wait_status 768\n"));  // exit status 3
    CHECK(contains(outcome, "timed_out 0\n"));
    CHECK(contains(ndc::test::slurp(dir / "run" / "stderr.txt"), "last words"));
  }
  SECTION("a run past its timeout is stopped") {
    const fs::path dir = scratch() / "slow";
    const fs::path tasks = shellTask(dir, "exec sleep 30", 0.2);
    CHECK(ndc::runSlurmTask(tasks, 0) == 0);
    CHECK(contains(ndc::test::slurp(dir / "outcome.txt"), "timed_out 1\n"));
  }
  SECTION("a command that cannot start") {
    const fs::path dir = scratch() / "missing";
    fs::create_directories(dir / "run");
    const ndc::SlurmTask task{"run", dir / "run", dir / "outcome.txt", 5, {"/nonexistent/x"}};
    ndc::writeAtomically(dir / "tasks.tsv", ndc::slurmTaskLine(task) + "\n");
    CHECK(ndc::runSlurmTask(dir / "tasks.tsv", 0) == 0);
    CHECK(contains(ndc::test::slurp(dir / "outcome.txt"), "error cannot start /nonexistent/x"));
  }
  SECTION("an index past the list") {
    const fs::path tasks = shellTask(scratch() / "short", "true", 5);
    CHECK_THROWS_AS(ndc::runSlurmTask(tasks, 1), ndc::InputError);
    CHECK_THROWS_AS(ndc::runSlurmTask(scratch() / "none.tsv", 0), ndc::InputError);
  }
}

TEST_CASE("slurm: --executor accepts local and slurm, and slurm needs sbatch",
          "[experiment][slurm]") {
  const std::string config =
      ndc::test::quoted(ndc::test::sourceDir() + "/tests/slurm/slurm-grid.toml");
  const fs::path out = scratch() / "cli";
  const std::string outArg = " --out " + ndc::test::quoted(out.string());
  ndc::test::CliRun run =
      ndc::test::runNdcontour("experiment " + config + outArg + " --executor cloud", scratch());
  CHECK(run.status == 2);
  CHECK(contains(run.err, "--executor"));
  CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);

  run = ndc::test::runNdcontour("experiment " + config + outArg + " --slurm-args --mem=1G",
                                scratch());
  CHECK(run.status == 2);
  CHECK(contains(run.err, "need --executor slurm"));

  // Without sbatch on PATH (the tool is started by its absolute path).
  const char* path = std::getenv("PATH");
  const std::string saved = path ? path : "";
  ::setenv("PATH", "/nonexistent", 1);
  run = ndc::test::runNdcontour("experiment " + config + outArg + " --executor slurm", scratch());
  ::setenv("PATH", saved.c_str(), 1);
  CHECK(run.status == 2);
  CHECK(run.err ==
        "ndcontour: --executor slurm: sbatch not found on PATH (install Slurm's "
        "client, e.g. scripts/setup.sh --slurm)\n");
  CHECK(!fs::exists(out));
}
