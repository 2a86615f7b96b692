/// \file options.hpp
/// What a solve is asked to do, and its validation before the pipeline runs (docs/contracts.md
/// 4.2): the one check of strategy specs, ranges and option combinations that both the
/// command-line tool (experiments/cli/) and the Python module (experiments/python/) use, so that
/// every bad value is one UsageError naming the option.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"

namespace ndc {

/// Everything a solve was asked to do: the options of `ndcontour solve` and the keywords of the
/// Python `solve()`, which share their names, ranges and checks.
struct SolveOptions {
  std::string problemPath;  ///< PROBLEM.toml
  /// `--depth`, the strategy names, `--scalar`, `--precision` (53 for double) and `--jitter`;
  /// defaults as in Settings.
  Settings settings;
  std::optional<unsigned> precision;  ///< `--precision BITS` as given (before defaulting)
  std::optional<double> tolerance;    ///< `--tolerance h`: the chord error target (settings)
  /// `--out DIR`: write summary.json, mesh.ply, singular.csv (and cells.csv with `--cells`)
  std::optional<std::string> outDir;
  bool ascii = false;      ///< `--ascii`: the PLY files of `--out` as ASCII (else binary) PLY
  bool cells = false;      ///< `--cells`: also write cells.csv into `--out`
  bool vtk = false;        ///< `--vtk`: also write mesh.vtu into `--out`
  bool legacyVtk = false;  ///< `--vtk-legacy`: also write mesh.vtk into `--out`
  bool obj = false;        ///< `--obj`: also write mesh.obj into `--out`
  bool json = false;       ///< `--json`: the summary on standard output, nothing else
  std::string maxMemory;   ///< `--max-memory SIZE` as given (parsed into settings)
  /// `--check`: exit with kExitExpectMismatch when the mesh differs from the problem's `[expect]`.
  bool check = false;
  /// `--domain lo:hi,..`: solve on this box instead of the problem's domain (docs/split.md).
  std::optional<std::string> domain;
  /// `--split S`: cut the domain into S pieces solved apart and glued (docs/split.md).
  std::optional<int> split;
  std::string executor = "local";  ///< `--executor local|slurm` of `--split`
  std::string slurmPartition;      ///< `--slurm-partition P` (Slurm executor)
  std::string slurmArgs;           ///< `--slurm-args "..."`: further sbatch options
};

/// The longest `--timeout`: a year.
inline constexpr double kMaxTimeoutSeconds = 365.0 * 24 * 3600;

/// The most `--threads` accepted.
inline constexpr int kMaxThreads = 4096;

/// Checks the option values on their own (strategy specs against their registries, ranges) and
/// fills defaults that depend on other options (precision of the scalar); throws UsageError.
void validateSolveOptions(SolveOptions& options);

/// Checks the options against the loaded problem (the depth must fit the cell index for n
/// variables); throws UsageError, or InputError naming the problem file for a mesh format that
/// cannot hold its dimension k (formatRefusal: `--vtk` for k >= 4, `--obj` for k >= 3).
void validateSolveOptions(const SolveOptions& options, const Problem& problem);

}  // namespace ndc
