/// \file commands.hpp
/// The subcommands of the `ndcontour` command-line tool.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "experiments/cli/solve_options.hpp"
#include "framework/io/result.hpp"
#include "framework/problem/problem.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc::cli {

/// `ndcontour info`: prints the problem (name, n, k, m, variables and domain, each equation
/// with its degrees per variable and Bernstein coefficient count, and the expectations).
void printInfo(const Problem& problem, std::ostream& out);

/// `ndcontour solve`: runs the pipeline with the options' settings, compares the mesh with the
/// problem's `[expect]` (checkExpectation), writes summary.json, mesh.ply (binary, or ASCII with
/// `--ascii`), singular.csv and with `--cells` cells.csv into `--out DIR` and prints the summary
/// (JSON with `--json`). Differences from `[expect]`, dual vertices off M and unverified general
/// position are warnings on standard error, one line each. Returns the exit status: kExitOk, or
/// kExitExpectMismatch with `--check` when a compared key of `[expect]` differs.
int runSolve(SolveOptions options, const Problem& problem);

/// What runSolve does after the run: `[expect]`, the outputs of `--out`, the warnings and the
/// printed summary. Returns the exit status as runSolve.
int reportSolve(const SolveOptions& options, const Problem& problem, RunResult& result);

/// `ndcontour solve --split S` (docs/split.md): the pieces solved by `--executor` (local child
/// processes, `--threads` at once, or one Slurm job array), glued and reported as runSolve
/// reports a run. Their folders go to `--out`/pieces (a temporary folder without `--out`).
int runSplitSolve(const SolveOptions& options, const Problem& problem);

/// Fails early (before minutes of work) if `dir` cannot receive the outputs: InputError.
void checkWritable(const std::filesystem::path& dir);

/// A one-line progress bar on standard error, only when it is a terminal and not `quiet`
/// (`--json`): the stage (with its counts, e.g. the connection's round and leaves), a bar and
/// the percentage, redrawn at most ten times a second and ended by a line break at 100 %.
Progress terminalProgress(bool quiet = false);

/// Options of `ndcontour bench`.
struct BenchOptions {
  std::vector<std::string> problems;
  Settings settings;
  std::optional<std::uint64_t> jitter;
  int repeat = 5;
};

/// Declares the options of the `bench` subcommand.
void addBenchOptions(CLI::App& bench, BenchOptions& options);

/// `ndcontour bench`: runs the pipeline `repeat` times on each problem and prints the median
/// time of each stage as a Markdown table row. Returns the exit status.
int runBench(BenchOptions options);

/// Options of `ndcontour view` (docs/viewer.md).
struct ViewOptions {
  std::string resultDir;  ///< RESULT_DIR: the `--out` folder of `ndcontour solve`
  std::string out;        ///< `--out FILE`; empty: `RESULT_DIR/view.html`
};

/// Declares the arguments of the `view` subcommand.
void addViewOptions(CLI::App& view, ViewOptions& options);

/// `ndcontour view`: writes the viewer page of a result folder (ndc::view::writeViewer) and
/// prints one line saying where and what it shows. Bad input throws ndc::InputError (status 2).
int runView(const ViewOptions& options);

}  // namespace ndc::cli
