#include "strategies/subdivision/subdivision.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace ndc {

//! [subdivision-registry]
Registry<SubdivisionFactory>& subdivisionRegistry() {
  static Registry<SubdivisionFactory> registry(
      "subdivision",
      {{{"uniform",
         "As in the paper: 2^n children per level, a box is bounded after every n halvings.",
         {}},
        [](const Parameters&) { return Subdivision(UniformSubdivision{}); }},
       {{"binary", "One axis per level: every box is bounded after every halving.", {}},
        [](const Parameters&) { return Subdivision(BinarySubdivision{}); }}});
  return registry;
}
//! [subdivision-registry]

Subdivision createSubdivision(const StrategyChoice& choice) {
  return subdivisionRegistry().find(choice.name).create(choice.parameters);
}

Subdivision createSubdivision(std::string_view spec) {
  return createSubdivision(subdivisionRegistry().parse(spec));
}

namespace {

/// The depth-first traversal for one concrete bounding B and subdivision D (monomorphic: the
/// strategies are resolved once, by subdivide's std::visit).
template <class B, class D>
class Traversal {
 public:
  Traversal(const B& bounding, const D& subdivision, const Grid& grid, const Progress& progress,
            SolutionCells& cells, std::int64_t maxCells)
      : maxCells_(maxCells),
        bounding_(bounding),
        subdivision_(subdivision),
        n_(grid.n),
        depth_(grid.n * grid.depth),
        progress_(progress),
        cells_(cells),
        index_(static_cast<std::size_t>(grid.n), 0),
        // children_[d] holds the two children of the box of depth d - 1 being expanded.
        children_(static_cast<std::size_t>(depth_) + 1) {}

  void run() {
    typename B::State root;
    bounding_.root(root);
    if (keep(root, 0)) descend(root, 0);
    report(1.0);
  }

 private:
  //! [zerosetsubdiv]
  // Bounds the box of depth d if the subdivision says so; false: the box is discarded.
  bool keep(const typename B::State& state, int d) {
    if (!subdivision_.boundsAfter(d, n_)) return true;
    ++cells_.visited;
    if (bounding_.mayContainZero(state)) return true;
    done(d);
    return false;
  }

  // Expands a kept box of depth d: a leaf is a solution cell, an inner box is halved along
  // axis d mod n and its children (lower first) are visited depth first.
  void descend(const typename B::State& state, int d) {
    if (d == depth_) {
      if (maxCells_ > 0 && static_cast<std::int64_t>(cells_.size()) >= maxCells_) {
        throw CellBudgetExceeded("more than " + std::to_string(maxCells_) +
                                 " solution cells: the budget for this depth and k");
      }
      cells_.add(index_);
      done(d);
      return;
    }
    const int axis = d % n_;
    auto& [lower, upper] = children_[static_cast<std::size_t>(d) + 1];
    bounding_.halve(state, axis, lower, upper);
    // The child's multi-index along `axis` gains one bit: 2 i (lower) or 2 i + 1 (upper).
    index_[axis] *= 2;
    if (keep(lower, d + 1)) descend(lower, d + 1);
    ++index_[axis];
    if (keep(upper, d + 1)) descend(upper, d + 1);
    index_[axis] /= 2;
  }
  //! [zerosetsubdiv]

  // A box of depth d is finished (discarded or a solution cell): its share of the domain's
  // volume is done.
  void done(int d) {
    if (!progress_) return;
    doneVolume_ += std::ldexp(1.0, -d);
    if (doneVolume_ >= nextReport_) report(doneVolume_);
  }

  void report(double fraction) {
    if (!progress_) return;
    progress_("subdivision", std::min(fraction, 1.0));
    nextReport_ = std::floor(fraction * 100.0 + 1.0) / 100.0;
  }

  const std::int64_t maxCells_;  // 0: no budget
  const B& bounding_;
  const D& subdivision_;
  const int n_;
  const int depth_;  // n L halvings
  const Progress& progress_;
  SolutionCells& cells_;
  std::vector<std::int32_t> index_;  // multi-index of the current box at its own resolution
  std::vector<std::pair<typename B::State, typename B::State>> children_;
  double doneVolume_ = 0.0;
  double nextReport_ = 0.01;
};

}  // namespace

template <class S>
SolutionCells subdivide(const Bounding<S>& bounding, const Subdivision& subdivision,
                        const Grid& grid, const Progress& progress, std::int64_t maxCells) {
  if (!Grid::fits(grid.n, grid.depth) || grid.depth < 0 || grid.n < 1)
    throw InputError("depth " + std::to_string(grid.depth) + " is too large for " +
                     std::to_string(grid.n) +
                     " variables (n * depth must be at most 128, n at most 64)");
  const int n = std::visit([](const auto& b) { return b.dim(); }, bounding);
  if (n != grid.n)
    throw std::invalid_argument("subdivide: the grid has " + std::to_string(grid.n) +
                                " axes, the bounding " + std::to_string(n));
  SolutionCells cells;
  cells.grid = grid;
  // Dispatch once: the whole traversal is monomorphic in (bounding, subdivision).
  std::visit(
      [&](const auto& b, const auto& d) {
        Traversal<std::decay_t<decltype(b)>, std::decay_t<decltype(d)>> traversal(
            b, d, grid, progress, cells, maxCells);
        traversal.run();
      },
      bounding, subdivision);
  return cells;
}

template SolutionCells subdivide<double>(const Bounding<double>&, const Subdivision&, const Grid&,
                                         const Progress&, std::int64_t);
template SolutionCells subdivide<Mpfr>(const Bounding<Mpfr>&, const Subdivision&, const Grid&,
                                       const Progress&, std::int64_t);

}  // namespace ndc
