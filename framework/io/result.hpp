/// \file result.hpp
/// What a run of the pipeline produces (pipeline/pipeline.hpp), as the output writers
/// (framework/io/io.hpp) and the report read it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "framework/mesh/complex.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/summary.hpp"

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

}  // namespace ndc
