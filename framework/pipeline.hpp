/// \file pipeline.hpp
/// The pipeline of docs/algorithm1.md (paper, Algorithm 1): problem -> subdivision with bounding ->
/// solution cells -> projection -> classification -> connection -> complex -> analysis.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "application.hpp"
#include "complex.hpp"
#include "problem.hpp"
#include "strategy.hpp"
#include "summary.hpp"

namespace ndc {

/// Everything a run produces, in double for output (the run itself works in its scalar).
struct RunResult {
  Summary summary;
  int n = 0;
  int k = 0;
  /// Welded mesh: n coordinates per vertex, k + 1 vertex numbers per simplex.
  std::vector<double> vertices;
  std::vector<std::int32_t> simplices;
  /// Per solution cell: its multi-index (n ints), centre and projected point (n doubles
  /// each) and class.
  std::vector<std::int32_t> cellIndex;
  std::vector<double> cellCentre;
  std::vector<double> cellPoint;
  std::vector<CellClass> cellClass;
  /// The problem's application data (image map, input surfaces), or null.
  std::shared_ptr<const ApplicationData> application;
};

/// Runs the whole pipeline on a problem with the given settings. Strategy names are checked
/// first (ndc::InputError on unknown names or a depth the grid cannot hold); the scalar is
/// chosen at run time (`settings.scalar`, `settings.precisionBits`). `progress` may be empty.
RunResult runPipeline(const Problem& problem, const Settings& settings,
                      const Progress& progress = {});

/// Levels below `--depth` that adaptive refinement may reach by default: genus2 at depth 5
/// needs 6, the two circles 0.001 apart of curve-pair-close 9 (docs/certificate.md); the leaf
/// budget bounds the cost where refinement cannot succeed. `--max-depth` equal to `--depth`
/// turns it off.
inline constexpr int kDefaultRefinementLevels = 10;

/// The default `--max-depth`: depth + kDefaultRefinementLevels, or less where the cell keys
/// of the 2^n-tree would not fit (n * level <= 64).
int defaultMaxDepth(int n, int depth);

/// The maximum level of refinement of a run: settings.maxDepth, or the default when it is 0;
/// throws InputError when it is below the depth or does not fit.
int maxDepthOf(const Problem& problem, const Settings& settings);

}  // namespace ndc
