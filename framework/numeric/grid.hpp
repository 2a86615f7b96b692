/// \file grid.hpp
/// The uniform grid of the subdivision's final depth: 2^L cells per axis, cells named by
/// integer multi-indices and kept in a hash map keyed by the packed index (docs/algorithm1.md).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/util/flat_map.hpp"

namespace ndc {

/// Packed multi-index of a grid cell: L bits per axis, axis 0 lowest, in 128 bits. Requires
/// n * L <= 128 (Grid::fits): a curve in R^30 fits up to depth 4, R^8 up to depth 16.
__extension__ using CellKey = unsigned __int128;

/// Hash of a CellKey (std::hash has none for 128-bit integers in ISO C++). Keys below 2^64
/// hash to themselves, as std::hash<std::uint64_t> does.
struct CellKeyHash {
  std::size_t operator()(CellKey key) const noexcept {
    const auto lo = static_cast<std::uint64_t>(key), hi = static_cast<std::uint64_t>(key >> 64);
    return static_cast<std::size_t>(lo ^ (hi * 0x9E3779B97F4A7C15ull));
  }
};

/// Hash maps and sets keyed by CellKey.
template <class V>
using CellMap = std::unordered_map<CellKey, V, CellKeyHash>;
using CellSet = std::unordered_set<CellKey, CellKeyHash>;

/// The most bits of a CellKey (n * L), and the most axes (the cell tree marks regions outside
/// the grid with two bits per axis).
inline constexpr int kCellKeyBits = 128;
inline constexpr int kMaxCellKeyAxes = 64;

/// The uniform grid of `2^L` cells per axis on a box domain.
struct Grid {
  int n = 0;           ///< ambient dimension
  int depth = 0;       ///< L
  Box<double> domain;  ///< the problem domain (jitter, if any, is already applied)

  /// Cells per axis, 2^L.
  std::int64_t cellsPerAxis() const { return std::int64_t{1} << depth; }
  /// Whether n * L fits a CellKey.
  static bool fits(int n, int depth) { return depth <= deepestFor(n); }
  /// The deepest level whose keys fit for n axes (min(30, 128 / n); -1 beyond 64 axes).
  static int deepestFor(int n) {
    return n > kMaxCellKeyAxes ? -1 : std::min(30, kCellKeyBits / std::max(n, 1));
  }
  CellKey pack(std::span<const std::int32_t> index) const;
  void unpack(CellKey key, std::span<std::int32_t> index) const;
  /// The key of the face neighbour `index + sign e_axis` (caller checks the bounds).
  CellKey neighbour(CellKey key, int axis, int sign) const;
  /// Lower corner and width of a cell along an axis, in double.
  double cellLower(int axis, std::int32_t i) const;
  double cellWidth(int axis) const;
};

/// cellBox into `box`, whose vectors keep their storage (no allocation once sized).
template <class S>
void cellBoxInto(const Grid& grid, const Box<S>& domain, std::span<const std::int32_t> index,
                 Box<S>& box) {
  box.lo.resize(grid.n);
  box.hi.resize(grid.n);
  const S cells = S(static_cast<double>(grid.cellsPerAxis()));
  for (int j = 0; j < grid.n; ++j) {
    const S w = (domain.hi[j] - domain.lo[j]) / cells;
    box.lo[j] = domain.lo[j] + w * S(static_cast<double>(index[j]));
    // The same formula for both ends, so neighbouring cells share their face exactly.
    box.hi[j] = index[j] + 1 == grid.cellsPerAxis()
                    ? domain.hi[j]
                    : domain.lo[j] + w * S(static_cast<double>(index[j] + 1));
  }
}

/// The closed box of the cell with multi-index `index` in scalar S, on `domain` (the grid's
/// domain in S): `lo_j + (hi_j - lo_j) i_j / 2^L`.
template <class S>
Box<S> cellBox(const Grid& grid, const Box<S>& domain, std::span<const std::int32_t> index) {
  Box<S> box;
  cellBoxInto(grid, domain, index, box);
  return box;
}

/// The solution cells: final-depth boxes the subdivision could not discard.
struct SolutionCells {
  Grid grid;
  std::int64_t visited = 0;               ///< boxes the subdivision bounded
  std::vector<std::int32_t> index;        ///< n ints per cell, cell c at [c n, (c+1) n)
  FlatMap<CellKey, std::int32_t> lookup;  ///< packed index -> cell number

  std::size_t size() const { return grid.n ? index.size() / grid.n : 0; }
  std::span<const std::int32_t> cell(std::size_t c) const {
    return {index.data() + c * grid.n, static_cast<std::size_t>(grid.n)};
  }
  /// Cell number of the face neighbour of cell c across `axis` in direction `sign` (+1/-1),
  /// or -1 when that neighbour is not a solution cell or lies outside the grid.
  std::int32_t neighbour(std::size_t c, int axis, int sign) const;
  /// The number of the cell with packed index `key`, or -1.
  std::int32_t find(CellKey key) const {
    const std::int32_t* number = lookup.find(key);
    return number ? *number : -1;
  }
  /// Appends a cell (its key must be new).
  void add(std::span<const std::int32_t> cellIndex);
};

}  // namespace ndc
