/// \file cell_tree.hpp
/// The adaptive 2^n-tree of the crossing connection (docs/certificate.md): the solution cells of
/// the base grid as leaves, refined where a cell's topology certificate fails.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "framework/numeric/grid.hpp"
#include "framework/util/flat_map.hpp"

namespace ndc {

/// What occupies the region next to a face: a leaf of the tree, finer leaves (the face is not
/// minimal), the outside of the domain, or a cell the bounding excluded (no leaf): a base cell
/// the subdivision excluded, or a child of a refined leaf that refinement excluded.
struct Occupant {
  enum class Kind { kLeaf, kFiner, kOutside, kEmpty };
  Kind kind = Kind::kEmpty;
  std::int32_t leaf = -1;   ///< kLeaf: the leaf
  std::int32_t level = -1;  ///< kEmpty: the excluded cell's level
  /// kOutside: which axes the region lies beyond (2 bits per axis: 1 below, 2 above);
  /// kEmpty: the packed index of the excluded cell at its level.
  CellKey key = 0;
};

/// A 2^n-tree over the grid of `base` depth, refined down to at most `maxLevel`. Leaves are never
/// removed: a refined leaf becomes inactive, an internal node, and those of its 2^n children
/// the bounding keeps become leaves; the others stay regions without a leaf, as the base cells
/// the subdivision excluded (find: kEmpty, with their level), so that a refinement costs its
/// kept children, not 2^n. Leaf numbers are stable.
class CellTree {
 public:
  CellTree(const Grid& base, int maxLevel);

  int n() const { return n_; }
  int baseLevel() const { return base_; }
  int maxLevel() const { return maxLevel_; }
  /// The grid of level `level` (same domain, 2^level cells per axis).
  const Grid& grid(int level) const { return grids_[level - base_]; }

  /// Adds the solution cells of the base grid as leaves 0 .. cells.size() - 1 of an empty tree,
  /// each with its cell number (baseCell). The tree looks them up in `cells`' own lookup, so
  /// `cells` must outlive it.
  void addBaseCells(const SolutionCells& cells);
  /// Adds a leaf (its key must be new at its level); returns its number.
  std::int32_t addLeaf(int level, std::span<const std::int32_t> index, bool solution);
  /// Refines an active leaf: it becomes internal, and the children the bounding keeps become
  /// solution leaves: `halves` holds n entries per kept child (entry j: 1 for the upper half of
  /// axis j; ConnectionInput::refine). Returns the first child's number (the others follow).
  std::int32_t refine(std::int32_t leaf, const std::vector<std::uint8_t>& halves);

  /// The region at `index` of level `level` (the index may lie outside the grid).
  Occupant find(int level, std::span<const std::int32_t> index) const;

  std::size_t size() const { return level_.size(); }
  int level(std::int32_t leaf) const { return level_[leaf]; }
  std::span<const std::int32_t> index(std::int32_t leaf) const {
    return {index_.data() + std::size_t(leaf) * n_, static_cast<std::size_t>(n_)};
  }
  bool active(std::int32_t leaf) const { return active_[leaf] != 0; }
  /// Whether the bounding could not exclude the leaf (a solution cell); touch cells and
  /// excluded children are not.
  bool solution(std::int32_t leaf) const { return solution_[leaf] != 0; }
  /// Active leaves the bounding could not exclude: the leaves whose certificates cost work.
  std::size_t solutionLeaves() const { return solutionLeaves_; }
  /// The solution-cell number of a base leaf (its number in the pipeline's cells), else -1.
  std::int32_t baseCell(std::int32_t leaf) const {
    return leaf < baseCells_ && level_[leaf] == base_ ? leaf : -1;
  }

 private:
  int n_, base_, maxLevel_;
  std::vector<Grid> grids_;
  /// The active leaf of `level` with key `key`, or nullptr.
  const std::int32_t* leafAt(int level, CellKey key) const;

  const FlatMap<CellKey, std::int32_t>* baseLookup_ = nullptr;  // the base cells' (addBaseCells)
  std::vector<FlatMap<CellKey, std::int32_t>> leaves_;    // per level - base; base: other leaves
  std::vector<FlatMap<CellKey, std::uint8_t>> internal_;  // per level - base (a set)
  std::vector<std::int8_t> level_;
  std::vector<std::int32_t> index_;
  std::vector<std::uint8_t> active_, solution_;
  std::int32_t baseCells_ = 0;
  std::size_t solutionLeaves_ = 0;
};

}  // namespace ndc
