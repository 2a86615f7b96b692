// Validation of what a solve is asked to do (docs/contracts.md 4.2), shared by the command-line
// tool and the Python module.
#include "pipeline/options.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string_view>
#include <utility>

#include "framework/io/io.hpp"
#include "framework/problem/budget.hpp"
#include "pipeline/pipeline.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/subdivision/subdivision.hpp"

namespace ndc {

namespace {

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

/// `--tolerance` refines below the grid: UsageError unless the connection spec names a model
/// that refines (its capabilities), naming the models that do.
void requireRefiningConnection(const std::string& spec) {
  const Registry<ConnectionFactory>& registry = connectionRegistry();
  if (registry.find(registry.parse(spec).name).spec.capabilities.refines) return;
  throw UsageError("--tolerance needs a connection that refines: --connection " +
                   connectionsThat([](const Capabilities& c) { return c.refines; }, " or "));
}

}  // namespace

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
  if (!o.outDir && (o.ascii || o.cells || o.vtk || o.legacyVtk || o.obj))
    throw UsageError(std::string(o.ascii       ? "--ascii"
                                 : o.cells     ? "--cells"
                                 : o.vtk       ? "--vtk"
                                 : o.legacyVtk ? "--vtk-legacy"
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
  // A mesh file whose cells cannot hold a k-simplex is refused before the work
  // (docs/contracts.md 4.4).
  for (const auto& [asked, flag] :
       {std::pair{o.vtk, "--vtk"}, std::pair{o.legacyVtk, "--vtk-legacy"},
        std::pair{o.obj, "--obj"}})
    if (const std::string refusal = formatRefusal(flag, problem.k()); asked && !refusal.empty())
      throw InputError(problem.path + ": " + refusal);
}

}  // namespace ndc
