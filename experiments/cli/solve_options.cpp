// The `solve` options on the command line (docs/contracts.md 4.2); their validation is the
// pipeline's (pipeline/options.cpp).
#include "experiments/cli/solve_options.hpp"

#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>

#include "framework/problem/budget.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline/split.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/subdivision/subdivision.hpp"

namespace ndc::cli {

namespace {

/// The names joined by '|', as a type name in the help text.
template <std::size_t N>
std::string joined(const std::array<std::string_view, N>& names) {
  std::string text;
  for (std::size_t i = 0; i < N; ++i) text += (i ? "|" : "") + std::string(names[i]);
  return text;
}

/// Declares `--FAMILY SPEC` with the registry's models and parameters as its help.
template <class Factory>
void addStrategyOption(CLI::App& app, const std::string& flag, std::string& spec,
                       const Registry<Factory>& registry) {
  std::string family = registry.family();
  family[0] = static_cast<char>(family[0] - 'a' + 'A');
  app.add_option(flag, spec,
                 family + " strategy: " + registryHelp(registry.specs(), spec) +
                     " (docs/adding-a-strategy.md)")
      ->type_name("NAME[:KEY=VALUE,...]");
}

}  // namespace

CLI::Validator unsignedUpTo(std::uint64_t max) {
  return CLI::Validator(
      [max](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (text.empty() || ec != std::errc() || end != text.data() + text.size() || max < value)
          return "'" + text + "' is not an integer in 0.." + std::to_string(max);
        return "";
      },
      "", "unsigned");
}

void addThreadsOption(CLI::App& app, int& threads) {
  app.add_option("--threads", threads,
                 "Worker threads (default: every hardware thread); the outputs are the same "
                 "whatever the count")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            int value = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
            if (text.empty() || ec != std::errc() || end != text.data() + text.size() ||
                value < 1 || value > kMaxThreads)
              return "'" + text + "' is not an integer in 1.." + std::to_string(kMaxThreads);
            return "";
          },
          "", "threads"))
      ->type_name("N");
}

void addSolveOptions(CLI::App& solve, SolveOptions& o) {
  Settings& s = o.settings;
  solve.add_option("problem", o.problemPath, "Problem file (TOML, docs/contracts.md 4.1)")
      ->required()
      ->type_name("PROBLEM.toml");
  solve.add_option("--depth", s.depth, "Subdivision depth L: 2^L cells per axis")
      ->type_name("L")
      ->capture_default_str();
  solve
      .add_option("--tolerance", o.tolerance,
                  "Chord error h: refine the grid (adaptively, down to --max-depth) where the "
                  "mesh lies farther than h from M; --depth stays the base resolution")
      ->type_name("h");
  solve
      .add_option("--max-depth", s.maxDepth,
                  "Deepest level adaptive refinement may reach where a cell's topology "
                  "certificate fails (default: depth + " +
                      std::to_string(kDefaultRefinementLevels) +
                      ", or less where n * level > 128; equal to --depth: no refinement)")
      ->type_name("L");
  addStrategyOption(solve, "--bounding", s.bounding, boundingRegistry());
  addStrategyOption(solve, "--subdivision", s.subdivision, subdivisionRegistry());
  solve.add_option("--scalar", s.scalar, "Scalar type of the whole run")
      ->type_name(joined(kScalarNames))
      ->capture_default_str();
  solve
      .add_option("--precision", o.precision,
                  "Working precision in bits of --scalar mpfr (default " +
                      std::to_string(kDefaultMpfrPrecision) + ")")
      ->type_name("BITS");
  addStrategyOption(solve, "--classification", s.classification, classificationRegistry());
  addStrategyOption(solve, "--connection", s.connection, connectionRegistry());
  solve.add_option("--jitter", s.jitter, "Seed of a grid jitter (default: no jitter)")
      ->check(unsignedUpTo(std::numeric_limits<std::uint64_t>::max()))
      ->type_name("SEED");
  solve
      .add_option("--out", o.outDir,
                  "Write summary.json, mesh.ply (binary PLY unless --ascii), singular.csv, "
                  "cells.csv (with --cells) and (when the topology is not certified) "
                  "uncertified.csv to DIR")
      ->type_name("DIR");
  solve.add_flag("--ascii", o.ascii,
                 "Write the PLY files of --out (mesh.ply; input.ply, ruled.ply of applications) "
                 "as ASCII PLY instead of binary little-endian PLY, and mesh.vtu with ASCII "
                 "instead of zlib-compressed binary data");
  solve.add_flag("--cells", o.cells,
                 "Also write cells.csv to --out: one row per solution cell (index, centre, "
                 "class, projected point)");
  solve.add_flag("--vtk", o.vtk,
                 "Also write mesh.vtu to --out: VTK XML for ParaView and meshio, with the "
                 "coordinates u0.. in R^n (also under the variables' names), the cell class and "
                 "the singular and uncertified flags");
  solve.add_flag("--vtk-legacy", o.legacyVtk,
                 "Also write mesh.vtk to --out: legacy VTK (ASCII) with the arrays of mesh.vtu, "
                 "which meshio reads curves from as well as surfaces");
  solve.add_flag("--obj", o.obj,
                 "Also write mesh.obj to --out: Wavefront OBJ (f records, or l for curves)");
  solve
      .add_option("--max-memory", o.maxMemory,
                  "Memory the run may use (K, M, G, T: powers of 1024); a depth that needs more "
                  "is refused before the work (default: " +
                      std::to_string(std::lround(kDefaultMemoryShare * 100)) +
                      "% of the machine's memory)")
      ->type_name("SIZE");
  solve
      .add_option("--timeout", s.timeoutSeconds,
                  "Stop the solve after this many seconds of wall time (exit status " +
                      std::to_string(kExitTimeout) + "; --out keeps its previous run)")
      ->type_name("SECONDS");
  addThreadsOption(solve, s.threads);
  solve
      .add_option("--domain", o.domain,
                  "Solve on this box instead of the problem's domain: lo:hi for each variable, "
                  "comma-separated")
      ->type_name("LO:HI,...");
  solve
      .add_option("--split", o.split,
                  "Cut the domain into S pieces (a power of two, up to " +
                      std::to_string(kMaxSplitPieces) +
                      ") on grid planes, solve each apart and glue them into one mesh "
                      "(docs/split.md); --threads pieces at once with the local executor")
      ->type_name("S");
  solve
      .add_option("--executor", o.executor,
                  "Where the pieces of --split run: local (child processes) or slurm (one "
                  "sbatch job array; needs --out on a folder the nodes share)")
      ->type_name("local|slurm")
      ->capture_default_str();
  solve.add_option("--slurm-partition", o.slurmPartition, "Slurm executor: sbatch --partition")
      ->type_name("P");
  solve
      .add_option("--slurm-args", o.slurmArgs,
                  "Slurm executor: further sbatch options, split at spaces (e.g. \"--mem=4G\")")
      ->type_name("\"...\"");
  solve.add_flag("--json", o.json, "Print the summary (JSON) on standard output, nothing else");
  solve.add_flag("--check", o.check,
                 "Exit with status " + std::to_string(kExitExpectMismatch) +
                     " when the mesh differs from the problem's [expect] (each difference is a "
                     "warning on standard error either way)");
  solve.footer(kExitStatusHelp);
}

}  // namespace ndc::cli
