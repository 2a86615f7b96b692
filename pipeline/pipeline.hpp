/// \file pipeline.hpp
/// The pipeline of docs/algorithm1.md (paper, Algorithm 1): problem -> subdivision with bounding ->
/// solution cells -> projection -> classification -> connection -> complex -> analysis.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "framework/io/result.hpp"
#include "framework/mesh/complex.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc {

/// Names accepted for the scalar type (`--scalar`, `scalar` in experiment configs); the strategy
/// families' names are in their registries (boundingRegistry() and so on).
inline constexpr std::array<std::string_view, 2> kScalarNames = {"double", "mpfr"};
/// Accepted ranges of the numeric settings (`--depth`, `--precision`).
inline constexpr int kMinDepth = 1, kMaxDepth = 30;
inline constexpr unsigned kMinPrecision = 24, kMaxPrecision = 4096;
/// Working precision of `--scalar mpfr` when `--precision` is not given.
inline constexpr unsigned kDefaultMpfrPrecision = 128;

/// The one check of a run's levels: `depth` (--depth) and `maxDepth` (--max-depth, 0 for the
/// default) must lie in kMinDepth..kMaxDepth, with depth <= maxDepth, and, when the number of
/// variables n is known (n > 0), fit the grid's 128-bit cell keys (n * level <= 128). Throws
/// UsageError with one line naming the option, prefixed by `file` when it is not empty. The
/// command line calls it before reading the problem (n = 0) and with it; runPipeline before
/// any work.
void checkDepths(int depth, int maxDepth, int n, std::string_view file);

/// The five strategy specs of a Settings (`paper:extra_layers=1`), parsed against the
/// families' registries.
struct StrategyChoices {
  StrategyChoice bounding, subdivision, projection, classification, connection;
};

/// Parses the strategy specs of `settings`; UsageError on an unknown name, parameter or value.
StrategyChoices parseStrategies(const Settings& settings);

/// Turns a certified topology record uncertified when the welded mesh has non-manifold edges,
/// branch vertices (k = 1) or singular points: a flaw between the certificate and the output can
/// never reach the user as a certified wrong answer.
void checkCertificate(Summary& summary);

/// The summary's header: the problem, and the settings with each strategy by name and its
/// parameter values apart (contracts 4.3).
void describeRun(Summary& summary, const Problem& problem, const Settings& settings,
                 const StrategyChoices& choices, unsigned precisionBits);

/// Runs the whole pipeline on a problem with the given settings. Strategy names are checked
/// first (ndc::InputError on unknown names or a depth the grid cannot hold); the scalar is
/// chosen at run time (`settings.scalar`, `settings.precisionBits`). `progress` may be empty;
/// `notice` gets the time estimate of a run estimated to take longer than kAnnounceSeconds,
/// after the subdivision and before the other stages (docs/input-limits.md, "Time").
RunResult runPipeline(const Problem& problem, const Settings& settings,
                      const Progress& progress = {}, const Notice& notice = {});

/// Levels below `--depth` that adaptive refinement may reach by default: genus2 at depth 5
/// needs 6, the two circles 0.001 apart of curve-pair-close 9 (docs/certificate.md); the leaf
/// budget bounds the cost where refinement cannot succeed. `--max-depth` equal to `--depth`
/// turns it off.
inline constexpr int kDefaultRefinementLevels = 10;

/// The default `--max-depth`: depth + kDefaultRefinementLevels, or less where the cell keys
/// of the 2^n-tree would not fit (n * level <= 128).
int defaultMaxDepth(int n, int depth);

/// The maximum level of refinement of a run: settings.maxDepth, or the default when it is 0;
/// throws InputError when it is below the depth or does not fit.
int maxDepthOf(const Problem& problem, const Settings& settings);

}  // namespace ndc
