/// \file solve_options.hpp
/// The options of `ndcontour solve` (docs/contracts.md 4.2), parsed and validated before the
/// pipeline runs, so that every bad value exits with status 2 and one line on standard error.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "framework/core/problem.hpp"
#include "framework/core/summary.hpp"

namespace CLI {
class App;
class Validator;
}  // namespace CLI

namespace ndc::cli {

/// A bad command line: ndc::UsageError (framework/core/errors.hpp).
using ndc::UsageError;

// The names each strategy family accepts are the strategies' own lists (ndc::kBoundingNames
// and so on); the scalar names and the numeric ranges are the pipeline's
// (framework/pipeline/pipeline.hpp).

/// Everything `ndcontour solve` was asked to do.
struct SolveOptions {
  std::string problemPath;  ///< PROBLEM.toml
  /// `--depth`, the strategy names, `--scalar`, `--precision` (53 for double) and `--jitter`;
  /// defaults as in Settings.
  Settings settings;
  std::optional<unsigned> precision;  ///< `--precision BITS` as given (before defaulting)
  std::optional<double> tolerance;    ///< `--tolerance h`: the chord error target (settings)
  /// `--out DIR`: write summary.json, mesh.ply, singular.csv (and cells.csv with `--cells`)
  std::optional<std::string> outDir;
  bool ascii = false;     ///< `--ascii`: the PLY files of `--out` as ASCII (else binary) PLY
  bool cells = false;     ///< `--cells`: also write cells.csv into `--out`
  bool vtk = false;       ///< `--vtk`: also write mesh.vtu into `--out`
  bool obj = false;       ///< `--obj`: also write mesh.obj into `--out`
  bool json = false;      ///< `--json`: the summary on standard output, nothing else
  std::string maxMemory;  ///< `--max-memory SIZE` as given (parsed into settings)
  /// `--check`: exit with kExitExpectMismatch when the mesh differs from the problem's `[expect]`.
  bool check = false;
};

/// Exit statuses of the tool: success (also a mismatch with `[expect]` without `--check`), an
/// internal error, bad input or usage (one line on standard error), and `solve --check` finding
/// the mesh different from the problem's `[expect]`.
inline constexpr int kExitOk = 0, kExitInternal = 1, kExitBadInput = 2, kExitExpectMismatch = 3;
/// `solve --timeout` reached (the convention of timeout(1)); nothing in `--out` is touched.
inline constexpr int kExitTimeout = 124;
/// The longest `--timeout`: a year.
inline constexpr double kMaxTimeoutSeconds = 365.0 * 24 * 3600;

/// The exit statuses as the help text lists them.
inline constexpr const char* kExitStatusHelp =
    "Exit status: 0 success (a mismatch with [expect] is only a warning without --check), 1 "
    "internal error, 2 bad input or usage (one line on standard error naming the file), 3 "
    "solve --check: the mesh differs from the problem's [expect], 124 solve --timeout reached, "
    "130 and 143 interrupted by SIGINT and SIGTERM (an --out folder keeps its previous run).";

/// A CLI11 check that accepts a decimal integer in [0, max] (CLI11 alone would wrap "-3" or an
/// overflow silently), for `--jitter` of `solve` and `bench`.
CLI::Validator unsignedUpTo(std::uint64_t max);

/// The most `--threads` accepted.
inline constexpr int kMaxThreads = 4096;

/// Declares `--threads N` (1..kMaxThreads; unset: every hardware thread) on `app`, writing into
/// `threads` (Settings::threads), for `solve` and `bench`.
void addThreadsOption(CLI::App& app, int& threads);

/// Declares the options of the `solve` subcommand on `solve`, writing into `options`.
void addSolveOptions(CLI::App& solve, SolveOptions& options);

/// Checks the option values on their own (strategy names, ranges) and fills defaults that
/// depend on other options (precision of the scalar); throws UsageError.
void validateSolveOptions(SolveOptions& options);

/// Checks the options against the loaded problem (the depth must fit the cell index for n
/// variables); throws UsageError.
void validateSolveOptions(const SolveOptions& options, const Problem& problem);

}  // namespace ndc::cli
