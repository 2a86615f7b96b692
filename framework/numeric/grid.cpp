#include "framework/numeric/grid.hpp"

namespace ndc {

CellKey Grid::pack(std::span<const std::int32_t> index) const {
  CellKey key = 0;
  for (int j = n - 1; j >= 0; --j) key = (key << depth) | static_cast<CellKey>(index[j]);
  return key;
}

void Grid::unpack(CellKey key, std::span<std::int32_t> index) const {
  const CellKey mask = (CellKey{1} << depth) - 1;  // depth <= 30
  for (int j = 0; j < n; ++j) {
    index[j] = static_cast<std::int32_t>(key & mask);
    key >>= depth;
  }
}

CellKey Grid::neighbour(CellKey key, int axis, int sign) const {
  const CellKey unit = CellKey{1} << (axis * depth);
  return sign > 0 ? key + unit : key - unit;
}

double Grid::cellWidth(int axis) const {
  return (domain.hi[axis] - domain.lo[axis]) / static_cast<double>(cellsPerAxis());
}

double Grid::cellLower(int axis, std::int32_t i) const {
  // Interpolate from both ends so the last cell's upper face is exactly hi.
  const double t = static_cast<double>(i) / static_cast<double>(cellsPerAxis());
  return domain.lo[axis] * (1.0 - t) + domain.hi[axis] * t;
}

std::int32_t SolutionCells::neighbour(std::size_t c, int axis, int sign) const {
  const std::int32_t i = index[c * grid.n + axis] + sign;
  if (i < 0 || i >= grid.cellsPerAxis()) return -1;
  const CellKey key = grid.neighbour(grid.pack(cell(c)), axis, sign);
  return find(key);
}

void SolutionCells::add(std::span<const std::int32_t> cellIndex) {
  const auto number = static_cast<std::int32_t>(size());
  index.insert(index.end(), cellIndex.begin(), cellIndex.end());
  lookup.insert(grid.pack(cellIndex), number);
}

}  // namespace ndc
