/// \file experiment.hpp
/// Experiments (docs/experiments.md): a config names problems and lists of strategy settings,
/// depths and jitter seeds; the runner solves every combination of them (the grid) in child
/// processes of `ndcontour solve`, resumes where a previous invocation stopped, records every
/// failure, and collects the summaries in one CSV per experiment with a provenance record.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "experiments/runner/columns.hpp"  // kExperimentRunColumns, kExperimentSummaryColumns
#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"
#include "framework/util/json.hpp"  // flattenJsonNumbers, which reads the runs' summary.json

namespace ndc {

/// One problem of an experiment: a problem file, or a problem made by a generator
/// (generate.hpp) that the runner writes out before solving it.
struct ExperimentProblem {
  std::string name;            ///< the problem's `name`, unique within the experiment
  std::string file;            ///< the path recorded in the CSV (`problem_file`)
  std::filesystem::path path;  ///< where `solve` reads it
  std::string generatedText;   ///< generated problems: the file text; empty for files
  int n = 0, k = 0;            ///< dimensions of the problem
  Expectation expect;          ///< its `[expect]` table
  std::vector<int> depths;     ///< the depths to run it at
  /// The jitter seeds to run it with; one empty entry means a single run without jitter.
  std::vector<std::optional<std::uint64_t>> jitter;
};

/// A validated experiment config (`experiments/configs/<id>.toml`), in full or quick mode.
struct ExperimentConfig {
  std::filesystem::path file;  ///< the config file
  std::string text;            ///< its text (hashed into the provenance)
  std::filesystem::path root;  ///< the directory problem paths are relative to
  std::string id;              ///< equals the file stem; names every result file
  std::string artefact;        ///< `table` or `figure`
  std::string description;
  bool quick = false;  ///< whether the `[quick]` overrides were applied
  std::vector<ExperimentProblem> problems;
  /// The strategy lists whose cross product is run, in grid order.
  std::vector<std::string> bounding, subdivision, projection, classification, connection, scalar;
  std::vector<unsigned> precision;   ///< MPFR precisions in bits (used with scalar `mpfr`)
  std::vector<int> depths;           ///< default depths (a problem entry may override them)
  std::vector<std::uint64_t> seeds;  ///< default jitter seeds; empty: no jitter
  double timeoutS = 600;             ///< wall-clock limit of one run
  /// `cells = true`: every run also writes cells.csv (`solve --cells`), e.g. for fig-cells.
  bool cells = false;
};

/// Reads and validates a config (every key, type, name, range and file; the `[quick]` table
/// in either mode) and applies the `[quick]` overrides when `quick`. Throws InputError
/// (`FILE:LINE:COL: message`).
ExperimentConfig loadExperimentConfig(const std::filesystem::path& file, bool quick);

/// One run of the grid: a problem with settings (strategies, scalar, depth, jitter).
struct ExperimentRun {
  std::string id;           ///< the run directory name, stable across invocations
  std::size_t problem = 0;  ///< index into ExperimentConfig::problems
  Settings settings;
};

/// The runs of a config in grid order: problems (as listed, globs sorted, generated problems
/// by n then seed), then bounding, subdivision, projection, classification, connection,
/// scalar and precision, depth, and jitter seed.
std::vector<ExperimentRun> experimentGrid(const ExperimentConfig& config);

/// Where the runs of an experiment are executed (docs/experiments.md).
enum class Executor {
  local,  ///< child processes of the runner on this machine, `jobs` at once
  /// One Slurm job array (`sbatch --array --wait`, slurm.hpp), `jobs` tasks at once; the results
  /// folder must be shared by the submitting machine and the nodes.
  slurm
};

/// Options of one invocation of the runner.
struct ExperimentOptions {
  std::filesystem::path outDir = "results";  ///< results go to `<outDir>/<id>/`
  int jobs = 1;                              ///< runs at once
  Executor executor = Executor::local;       ///< where the runs are executed
  /// Slurm executor: the partition (`sbatch --partition`); empty: the cluster's default.
  std::string slurmPartition;
  /// Slurm executor: further `sbatch` options, after the runner's own (so they override them).
  std::vector<std::string> slurmArgs;
  /// The `ndcontour` executable the runs are started with.
  std::string executable = "/proc/self/exe";
  /// The command-line spelling of the invocation, recorded in the provenance.
  std::string commandLine;
};

/// Runs every unfinished run of the grid (a run is finished when its summary.json exists, and
/// its cells.csv when the config asks for `cells`),
/// at most `jobs` at once, each limited to `timeoutS`, with the executor of `options` (the Slurm
/// executor submits them as one job array and waits for it), and writes `<out>/<id>/<id>.csv` and
/// `provenance.json`. Progress goes to standard error, the final report to standard output.
/// Returns 0 when every run succeeded, 1 when any failed, 128 + the signal (130, 143) when
/// interrupted by SIGINT or SIGTERM (the Slurm job is cancelled). Throws
/// InputError when the output directory cannot be written or `sbatch` refuses the job.
int runExperiment(ExperimentConfig config, const ExperimentOptions& options);

/// SHA-256 of `text` as 64 lowercase hex digits (the config hash of the provenance).
std::string sha256Hex(std::string_view text);

}  // namespace ndc
