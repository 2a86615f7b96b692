// Parsing and validation of the `solve` options (docs/contracts.md 4.2).
#include "framework/cli/solve_options.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>

#include "framework/core/budget.hpp"
#include "framework/core/grid.hpp"
#include "framework/pipeline/pipeline.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/subdivision/subdivision.hpp"

namespace ndc::cli {

namespace {

template <std::size_t N>
std::string joined(const std::array<std::string_view, N>& names) {
  std::string text;
  for (std::size_t i = 0; i < N; ++i) text += (i ? "|" : "") + std::string(names[i]);
  return text;
}

/// Rejects a scalar name that is not among `names`, naming the accepted ones.
template <std::size_t N>
void checkName(const std::string& flag, const std::string& value,
               const std::array<std::string_view, N>& names, const std::string& family) {
  if (std::find(names.begin(), names.end(), value) != names.end()) return;
  std::string accepted;
  for (std::size_t i = 0; i < N; ++i) accepted += (i ? ", " : "") + std::string(names[i]);
  throw UsageError(flag + ": unknown " + family + " '" + value + "' (accepted: " + accepted + ")");
}

/// Rejects a strategy spec its family's registry does not accept, naming the flag.
template <class Factory>
void checkSpec(const std::string& flag, const std::string& spec,
               const Registry<Factory>& registry) {
  try {
    registry.parse(spec);
  } catch (const UsageError& error) {
    throw UsageError(flag + ": " + error.what());
  }
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

/// `--tolerance` refines below the grid: UsageError unless the connection spec names a model
/// that refines (its capabilities), naming the models that do.
void requireRefiningConnection(const std::string& spec) {
  const Registry<ConnectionFactory>& registry = connectionRegistry();
  if (registry.find(registry.parse(spec).name).spec.capabilities.refines) return;
  throw UsageError("--tolerance needs a connection that refines: --connection " +
                   connectionsThat([](const Capabilities& c) { return c.refines; }, " or "));
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
                 "as ASCII PLY instead of binary little-endian PLY");
  solve.add_flag("--cells", o.cells,
                 "Also write cells.csv to --out: one row per solution cell (index, centre, "
                 "class, projected point)");
  solve.add_flag("--vtk", o.vtk,
                 "Also write mesh.vtu to --out: VTK XML for ParaView and meshio, with the "
                 "coordinates u0.. in R^n, the cell class and the singular and uncertified flags");
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
  solve.add_flag("--json", o.json, "Print the summary (JSON) on standard output, nothing else");
  solve.add_flag("--check", o.check,
                 "Exit with status " + std::to_string(kExitExpectMismatch) +
                     " when the mesh differs from the problem's [expect] (each difference is a "
                     "warning on standard error either way)");
  solve.footer(kExitStatusHelp);
}

void validateSolveOptions(SolveOptions& o) {
  Settings& s = o.settings;
  checkSpec("--bounding", s.bounding, boundingRegistry());
  checkSpec("--subdivision", s.subdivision, subdivisionRegistry());
  checkSpec("--classification", s.classification, classificationRegistry());
  checkSpec("--connection", s.connection, connectionRegistry());
  checkName("--scalar", s.scalar, kScalarNames, "scalar type");

  checkDepths(s.depth, s.maxDepth, 0, "");

  // The precision belongs to the scalar: double is always 53 bits.
  if (o.precision) {
    if (*o.precision < kMinPrecision || *o.precision > kMaxPrecision)
      throw UsageError("--precision " + std::to_string(*o.precision) +
                       " is out of range (accepted: " + std::to_string(kMinPrecision) + ".." +
                       std::to_string(kMaxPrecision) + " bits)");
    if (s.scalar == "double" && *o.precision != 53)
      throw UsageError("--precision " + std::to_string(*o.precision) +
                       " needs --scalar mpfr (double has 53 bits)");
  }
  s.precisionBits = s.scalar == "double" ? 53 : o.precision.value_or(kDefaultMpfrPrecision);

  if (o.tolerance && !(std::isfinite(*o.tolerance) && *o.tolerance > 0))
    throw UsageError("--tolerance must be a positive finite number");
  if (o.tolerance) requireRefiningConnection(s.connection);
  if (o.tolerance) s.tolerance = *o.tolerance;
  if (s.timeoutSeconds && !(*s.timeoutSeconds > 0 && *s.timeoutSeconds <= kMaxTimeoutSeconds))
    throw UsageError("--timeout must be a positive number of seconds, at most a year");
  if (!o.maxMemory.empty()) {
    const auto bytes = parseByteSize(o.maxMemory);
    if (!bytes)
      throw UsageError("--max-memory '" + o.maxMemory +
                       "' is not a size between 1M and 1048576T (a number with K, M, G or T)");
    s.maxMemoryBytes = *bytes;
  }

  // An existing output must be a directory; the pipeline decides what it may overwrite.
  if (!o.outDir && (o.ascii || o.cells || o.vtk || o.obj))
    throw UsageError(std::string(o.ascii   ? "--ascii"
                                 : o.cells ? "--cells"
                                 : o.vtk   ? "--vtk"
                                           : "--obj") +
                     " needs --out DIR (it chooses the files written there)");
  if (o.outDir) {
    std::error_code ec;
    if (o.outDir->empty()) throw UsageError("--out: empty directory name");
    if (std::filesystem::exists(*o.outDir, ec) && !std::filesystem::is_directory(*o.outDir, ec))
      throw UsageError("--out " + *o.outDir + ": exists and is not a directory");
  }
}

void validateSolveOptions(const SolveOptions& o, const Problem& problem) {
  checkDepths(o.settings.depth, o.settings.maxDepth, problem.n(), problem.path);
}

}  // namespace ndc::cli
