#include "strategies/subdivision/subdivision.hpp"

#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "framework/numeric/parallel.hpp"

namespace ndc {
namespace {

/// A model's registry entry: its own spec, and the model (it takes no parameters).
template <class M>
Registry<SubdivisionFactory>::Entry entryOf() {
  return {M::spec(), [](const Parameters&) { return Subdivision(M{}); }};
}

}  // namespace

//! [subdivision-registry]
Registry<SubdivisionFactory>& subdivisionRegistry() {
  static Registry<SubdivisionFactory> registry(
      "subdivision", {entryOf<UniformSubdivision>(), entryOf<BinarySubdivision>()});
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

/// The solution cells of one subtree of a parallel traversal: their indices, n per cell.
struct CellList {
  explicit CellList(int dim) : n(dim) {}

  int n = 0;
  std::int64_t visited = 0;
  std::vector<std::int32_t> index;

  std::size_t size() const { return index.size() / static_cast<std::size_t>(n); }
  void add(std::span<const std::int32_t> cell) {
    index.insert(index.end(), cell.begin(), cell.end());
  }
};

/// A kept box where the sequential top of a parallel traversal stops: its state, depth and
/// multi-index; its subtree is one task.
template <class State>
struct Subtree {
  State state;
  std::vector<std::int32_t> index;
};

/// The depth-first traversal for one concrete bounding B and subdivision D (monomorphic: the
/// strategies are resolved once, by subdivide's std::visit), writing the solution cells into
/// `Out` (SolutionCells, or a CellList for one subtree of a parallel traversal).
template <class B, class D, class Out>
class Traversal {
 public:
  using State = typename B::State;

  Traversal(const B& bounding, const D& subdivision, const Grid& grid, const Progress& progress,
            Out& cells, std::int64_t maxCells)
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
    State root;
    bounding_.root(root);
    if (keep(root, 0)) descend(root, 0);
    report(1.0);
  }

  /// A stage of the top of a parallel traversal: like run() from the root (`from` null) or
  /// from the kept box `from` of depth `fromDepth`, but the kept boxes of depth `depth` (below
  /// the final one) are not expanded; they go to `subtrees` in depth-first order.
  void runTop(const Subtree<State>* from, int fromDepth, int depth,
              std::vector<Subtree<State>>& subtrees) {
    stopAt_ = depth;
    subtrees_ = &subtrees;
    if (from) {
      index_ = from->index;
      descend(from->state, fromDepth);
      return;
    }
    State root;
    bounding_.root(root);
    if (keep(root, 0)) descend(root, 0);
  }

  /// One subtree of a parallel traversal: the kept box `top` of depth `depth`, expanded as
  /// run() would; `found` counts the solution cells of every subtree (the budget).
  void runSubtree(const Subtree<State>& top, int depth, std::atomic<std::int64_t>& found) {
    found_ = &found;
    index_ = top.index;
    descend(top.state, depth);
  }

 private:
  //! [zerosetsubdiv]
  // Bounds the box of depth d if the subdivision says so; false: the box is discarded.
  bool keep(const State& state, int d) {
    if (!subdivision_.boundsAfter(d, n_)) return true;
    ++cells_.visited;
    if (bounding_.mayContainZero(state)) return true;
    done(d);
    return false;
  }

  // Expands a kept box of depth d: a leaf is a solution cell, an inner box is halved along
  // axis d mod n and its children (lower first) are visited depth first.
  void descend(const State& state, int d) {
    if (d == stopAt_) {
      subtrees_->push_back({state, index_});
      return;
    }
    if (d == depth_) {
      addCell();
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

  // A solution cell, within the budget (of this traversal, or of all subtrees: found_).
  void addCell() {
    const std::int64_t before = found_ ? found_->fetch_add(1, std::memory_order_relaxed)
                                       : static_cast<std::int64_t>(cells_.size());
    if (maxCells_ > 0 && before >= maxCells_) {
      throw CellBudgetExceeded("more than " + std::to_string(maxCells_) +
                               " solution cells: the budget for this depth and k");
    }
    cells_.add(index_);
  }

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
  Out& cells_;
  std::vector<std::int32_t> index_;  // multi-index of the current box at its own resolution
  std::vector<std::pair<State, State>> children_;
  double doneVolume_ = 0.0;
  double nextReport_ = 0.01;
  int stopAt_ = -1;                                  // runTop: where the subtrees start
  std::vector<Subtree<State>>* subtrees_ = nullptr;  // runTop: the subtrees found
  std::atomic<std::int64_t>* found_ = nullptr;       // runSubtree: cells of every subtree
};

/// The depth where a parallel traversal hands its subtrees to tasks: about 2^kTopLevels boxes
/// per axis, so that a k-manifold leaves some hundreds of subtrees (enough to balance 64
/// threads; each subtree's cost grows with its share of M). -1: the tree is too shallow to
/// split (then the traversal is sequential).
int topDepth(const Grid& grid) {
  constexpr int kTopLevels = 3;
  const int depth = grid.n * std::min(kTopLevels, grid.depth - 2);
  return depth > 0 ? depth : -1;
}

/// The kept boxes of depth `top`, in depth-first order, by stages of n halvings: the first
/// from the root in the calling thread, each later one with the boxes of the stage before as
/// parallel tasks (their lists appended in order). So the top is sequential only down to
/// depth n; `visited` counts its bounded boxes.
template <class B, class D>
std::vector<Subtree<typename B::State>> topSubtrees(const B& bounding, const D& subdivision,
                                                    const Grid& grid, int top,
                                                    std::int64_t& visited) {
  using State = typename B::State;
  const Progress none;
  std::vector<Subtree<State>> subtrees;
  CellList head{grid.n};
  Traversal<B, D, CellList> first(bounding, subdivision, grid, none, head, 0);
  first.runTop(nullptr, 0, std::min(grid.n, top), subtrees);
  visited += head.visited;
  for (int from = grid.n; from < top; from += grid.n) {
    const int to = std::min(from + grid.n, top);
    std::vector<std::vector<Subtree<State>>> next(subtrees.size());
    std::vector<std::int64_t> counts(subtrees.size(), 0);
    parallelFor(subtrees.size(), [&](std::size_t i) {
      const B local = bounding;  // the bounding's scratch is per instance
      CellList part{grid.n};
      Traversal<B, D, CellList> t(local, subdivision, grid, none, part, 0);
      t.runTop(&subtrees[i], from, to, next[i]);
      counts[i] = part.visited;
    });
    subtrees.clear();
    for (std::size_t i = 0; i < next.size(); ++i) {
      visited += counts[i];
      for (Subtree<State>& box : next[i]) subtrees.push_back(std::move(box));
    }
  }
  return subtrees;
}

/// The subtrees' cells appended to `cells` in the order of the parts, each part's in parallel
/// (its index copied and its keys put into the lookup: the cells are distinct).
void appendParts(const std::vector<CellList>& parts, SolutionCells& cells) {
  const auto n = static_cast<std::size_t>(cells.grid.n);
  std::vector<std::size_t> first(parts.size() + 1, cells.size());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    first[i + 1] = first[i] + parts[i].size();
    cells.visited += parts[i].visited;
  }
  cells.index.resize(first.back() * n);
  cells.lookup.reserve(first.back());  // room for every key: no rehash while they go in
  parallelFor(parts.size(), [&](std::size_t i) {
    const std::vector<std::int32_t>& index = parts[i].index;
    std::copy(index.begin(), index.end(), cells.index.begin() + std::ptrdiff_t(first[i] * n));
    for (std::size_t c = 0; c < parts[i].size(); ++c) {
      const std::span<const std::int32_t> cell(index.data() + c * n, n);
      cells.lookup.insertNewConcurrently(cells.grid.pack(cell),
                                         static_cast<std::int32_t>(first[i] + c));
    }
  });
  cells.lookup.addCount(first.back() - first.front());
}

/// ZeroSetSubdiv with the subtrees below topDepth as parallel tasks (framework/numeric/
/// parallel.hpp): the top is traversed in stages (topSubtrees), each subtree writes its own
/// CellList, and the lists are appended in depth-first order of their roots. So the cells,
/// their order and `visited` are those of the sequential traversal, and the budget is exceeded
/// in the same runs (the cells are counted across subtrees; the top holds none).
template <class B, class D>
void parallelTraversal(const B& bounding, const D& subdivision, const Grid& grid,
                       const Progress& progress, SolutionCells& cells, std::int64_t maxCells,
                       int top) {
  const auto subtrees = topSubtrees(bounding, subdivision, grid, top, cells.visited);
  std::vector<CellList> parts(subtrees.size(), CellList{grid.n});
  std::atomic<std::int64_t> found{0};
  std::atomic<std::size_t> finished{0};
  const auto caller = std::this_thread::get_id();
  // The top finished all of the domain but the subtrees' boxes.
  const double share = std::ldexp(1.0, -top), before = 1 - double(subtrees.size()) * share;
  const Progress none;
  parallelFor(subtrees.size(), [&](std::size_t i) {
    const B local = bounding;  // the bounding's scratch is per instance
    Traversal<B, D, CellList> t(local, subdivision, grid, none, parts[i], maxCells);
    t.runSubtree(subtrees[i], top, found);
    const std::size_t done = finished.fetch_add(1, std::memory_order_relaxed) + 1;
    // Progress from the caller's thread only (the callback need not be thread safe).
    if (progress && std::this_thread::get_id() == caller)
      progress("subdivision", std::min(1.0, before + double(done) * share));
  });
  appendParts(parts, cells);
  if (progress) progress("subdivision", 1.0);
}

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
  const int top = topDepth(grid);
  std::visit(
      [&](const auto& b, const auto& d) {
        using B = std::decay_t<decltype(b)>;
        using D = std::decay_t<decltype(d)>;
        if (top > 0) {
          parallelTraversal(b, d, grid, progress, cells, maxCells, top);
          return;
        }
        Traversal<B, D, SolutionCells> traversal(b, d, grid, progress, cells, maxCells);
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
