/// \file solve_options.hpp
/// The options of `ndcontour solve` on the command line (docs/contracts.md 4.2). What they fill
/// and its validation are the pipeline's (pipeline/options.hpp), shared with the Python module;
/// every bad value exits with status 2 and one line on standard error.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "pipeline/options.hpp"

namespace CLI {
class App;
class Validator;
}  // namespace CLI

namespace ndc::cli {

/// A bad command line: ndc::UsageError (framework/util/errors.hpp).
using ndc::UsageError;

// The names each strategy family accepts are the strategies' own lists (ndc::kBoundingNames
// and so on); the scalar names and the numeric ranges are the pipeline's
// (pipeline/pipeline.hpp).

using ndc::kMaxThreads;
using ndc::kMaxTimeoutSeconds;
using ndc::SolveOptions;
using ndc::validateSolveOptions;

/// Exit statuses of the tool: success (also a mismatch with `[expect]` without `--check`), an
/// internal error, bad input or usage (one line on standard error), and `solve --check` finding
/// the mesh different from the problem's `[expect]`.
inline constexpr int kExitOk = 0, kExitInternal = 1, kExitBadInput = 2, kExitExpectMismatch = 3;
/// `solve --timeout` reached (the convention of timeout(1)); nothing in `--out` is touched.
inline constexpr int kExitTimeout = 124;

/// The exit statuses as the help text lists them.
inline constexpr const char* kExitStatusHelp =
    "Exit status: 0 success (a mismatch with [expect] is only a warning without --check), 1 "
    "internal error, 2 bad input or usage (one line on standard error naming the file), 3 "
    "solve --check: the mesh differs from the problem's [expect], 124 solve --timeout reached, "
    "130 and 143 interrupted by SIGINT and SIGTERM (an --out folder keeps its previous run).";

/// A CLI11 check that accepts a decimal integer in [0, max] (CLI11 alone would wrap "-3" or an
/// overflow silently), for `--jitter` of `solve` and `bench`.
CLI::Validator unsignedUpTo(std::uint64_t max);

/// Declares `--threads N` (1..kMaxThreads; unset: every hardware thread) on `app`, writing into
/// `threads` (Settings::threads), for `solve` and `bench`.
void addThreadsOption(CLI::App& app, int& threads);

/// Declares the options of the `solve` subcommand on `solve`, writing into `options`.
void addSolveOptions(CLI::App& solve, SolveOptions& options);

}  // namespace ndc::cli
