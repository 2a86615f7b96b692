#include "strategies/connection/crossing/cell_tree.hpp"

#include <stdexcept>

namespace ndc {

CellTree::CellTree(const Grid& base, int maxLevel)
    : n_(base.n), base_(base.depth), maxLevel_(std::max(maxLevel, base.depth)) {
  if (!Grid::fits(n_, maxLevel_))
    throw std::invalid_argument("CellTree: level " + std::to_string(maxLevel_) +
                                " does not fit a cell key");
  for (int level = base_; level <= maxLevel_; ++level) {
    Grid g = base;
    g.depth = level;
    grids_.push_back(g);
  }
  leaves_.resize(grids_.size());
  internal_.resize(grids_.size());
}

void CellTree::addBaseCells(const SolutionCells& cells) {
  if (size() != 0 || cells.grid.n != n_ || cells.grid.depth != base_)
    throw std::invalid_argument("CellTree::addBaseCells: not an empty tree of the cells' grid");
  // The base grid's keys are the cells' keys (the same n and depth), and leaf c is cell c:
  // the cells' own lookup finds them (leafAt).
  baseLookup_ = &cells.lookup;
  level_.assign(cells.size(), static_cast<std::int8_t>(base_));
  index_ = cells.index;
  active_.assign(cells.size(), 1);
  solution_.assign(cells.size(), 1);
  solutionLeaves_ = cells.size();
  baseCells_ = static_cast<std::int32_t>(cells.size());
}

std::int32_t CellTree::addLeaf(int level, std::span<const std::int32_t> index, bool solution) {
  const auto leaf = static_cast<std::int32_t>(level_.size());
  leaves_[level - base_].insert(grid(level).pack(index), leaf);
  level_.push_back(static_cast<std::int8_t>(level));
  index_.insert(index_.end(), index.begin(), index.end());
  active_.push_back(1);
  solution_.push_back(solution ? 1 : 0);
  solutionLeaves_ += solution ? 1 : 0;
  return leaf;
}

std::int32_t CellTree::refine(std::int32_t leaf, const std::vector<std::uint8_t>& halves) {
  const int level = level_[leaf];
  if (level >= maxLevel_) throw std::logic_error("CellTree::refine: at the maximum level");
  const CellKey key = grid(level).pack(index(leaf));
  leaves_[level - base_].erase(key);
  internal_[level - base_].insert(key, 1);
  active_[leaf] = 0;
  solutionLeaves_ -= solution_[leaf];
  const std::vector<std::int32_t> parent(index(leaf).begin(), index(leaf).end());
  std::vector<std::int32_t> child(n_);
  const auto first = static_cast<std::int32_t>(level_.size());
  if (halves.size() % std::size_t(n_) != 0)
    throw std::logic_error("CellTree::refine: not n entries per child");
  for (std::size_t c = 0; c < halves.size(); c += std::size_t(n_)) {
    for (int j = 0; j < n_; ++j)
      child[j] = 2 * parent[j] + static_cast<std::int32_t>(halves[c + j]);
    addLeaf(level + 1, child, true);
  }
  return first;
}

const std::int32_t* CellTree::leafAt(int level, CellKey key) const {
  if (level == base_ && baseLookup_) {
    // A base cell is a leaf until it is refined (then it is internal: inactive).
    if (const std::int32_t* cell = baseLookup_->find(key)) return active_[*cell] ? cell : nullptr;
  }
  return leaves_[level - base_].find(key);
}

Occupant CellTree::find(int level, std::span<const std::int32_t> index) const {
  Occupant out;
  const std::int64_t top = grid(level).cellsPerAxis();
  CellKey outside = 0;
  for (int j = 0; j < n_; ++j) {
    if (index[j] < 0) outside |= CellKey{1} << (2 * j);
    if (index[j] >= top) outside |= CellKey{2} << (2 * j);
  }
  if (outside) {
    out.kind = Occupant::Kind::kOutside;
    out.key = outside;
    return out;
  }
  // A leaf of the level itself first (the common case: a neighbour of the same size); leaves
  // do not overlap, so no coarser leaf holds the region then.
  if (level > base_) {
    if (const std::int32_t* leaf = leaves_[level - base_].find(grid(level).pack(index))) {
      out.kind = Occupant::Kind::kLeaf;
      out.leaf = *leaf;
      return out;
    }
  }
  // From the base level down: the first leaf met holds the region; a level where the cell is
  // neither a leaf nor internal is a region the bounding excluded (a base cell, or a child of a
  // refined cell).
  thread_local std::vector<std::int32_t> at;
  at.assign(index.begin(), index.end());
  for (int l = base_; l <= level; ++l) {
    for (int j = 0; j < n_; ++j) at[j] = index[j] >> (level - l);
    const CellKey key = grid(l).pack(at);
    if (const std::int32_t* leaf = leafAt(l, key)) {
      out.kind = Occupant::Kind::kLeaf;
      out.leaf = *leaf;
      return out;
    }
    if (!internal_[l - base_].contains(key)) {
      out.kind = Occupant::Kind::kEmpty;
      out.level = l;
      out.key = key;
      return out;
    }
  }
  out.kind = Occupant::Kind::kFiner;
  return out;
}

}  // namespace ndc
