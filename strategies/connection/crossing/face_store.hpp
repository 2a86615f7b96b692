/// \file face_store.hpp
/// The solved minimal m-faces of the crossing connection, kept across the refinement's rounds:
/// a face is solved once per level c. Internal to the crossing connection.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "framework/numeric/scalar.hpp"
#include "strategies/connection/crossing/function_ref.hpp"

namespace ndc::crossing_detail {

/// What the face solver found on one minimal m-face (cached: a face is solved once per level c).
template <class S>
struct FaceResult {
  std::vector<S> root;          ///< the first root (n coordinates), if any
  int roots = 0;                ///< how many roots
  int degree = 0;               ///< faceDegree
  bool certain = true;          ///< every root decided (else its cells are singular cells)
  bool proven = true;           ///< every decision a proof (FaceSolver::proven)
  bool withinRounding = false;  ///< FaceSolver::withinRounding
  std::int64_t degenerate = 0;  ///< roots within rounding of the face's boundary
};

/// A solved face as FaceStore keeps it: a FaceResult whose root lies in the store's pool.
struct FaceRecord {
  std::int64_t root = -1;  ///< offset of the first root's coordinates in its chunk's pool, or -1
  std::int64_t degenerate = 0;  ///< as FaceResult
  std::uint32_t kind = 0;       ///< which face of its leaf (AdaptiveCrossing::faceKind)
  int roots = 0, degree = 0;
  bool certain = true, proven = true, withinRounding = false;
};

/// The solved faces of every leaf, kept across the refinement's rounds. A leaf's faces are
/// solved together (one task of a window), so its records form one block, sorted by kind:
/// finding one is a binary search of its leaf's block (up to 4 C(n, 2) records: 60 in R^6).
/// Each window's blocks go into a chunk of their own, sized exactly (nothing is allocated per
/// face, nothing is hashed, and no growing array is copied), with the roots in the chunk's pool.
/// A leaf that gets new faces in a later round moves its block to the first chunk, which grows.
template <class S>
class FaceStore {
 public:
  /// The new faces of one leaf: (kind, FaceResult) in kind order.
  using Solved = std::vector<std::pair<std::uint32_t, FaceResult<S>>>;

  explicit FaceStore(int n) : n_(n) {}

  /// No faces.
  void clear();

  /// Face `kind` of `leaf`, or null. The pointer stays valid until the next add.
  const FaceRecord* find(std::int32_t leaf, std::uint32_t kind) const;

  /// Face `kind` of `leaf` (kept) as the face solver gave it.
  FaceResult<S> result(std::int32_t leaf, const FaceRecord& r) const;

  /// Keeps face `kind` of `leaf` (not kept yet), in the first chunk.
  void add(std::int32_t leaf, std::uint32_t kind, const FaceResult<S>& r);

  /// Keeps the faces a window of leaves solved: `solved(i)` are the new faces of leaves[i]
  /// (ascending). A leaf with faces of an earlier round takes add; the others' blocks go into a
  /// new chunk, placed by prefix sums and filled in parallel, each task writing only its leaf's
  /// block.
  void addBlocks(std::span<const std::int32_t> leaves,
                 FunctionRef<const Solved&(std::size_t)> solved);

 private:
  struct Block {
    std::int32_t chunk = 0;
    std::int32_t count = 0;
    std::int64_t first = 0;
  };
  struct Chunk {
    std::vector<FaceRecord> records;
    std::vector<S> roots;
  };
  static bool byKind(const FaceRecord& r, std::uint32_t kind) { return r.kind < kind; }
  /// The record of face `kind` solved as `r`, its root at `root` in its chunk's pool (-1: none).
  static FaceRecord record(std::uint32_t kind, const FaceResult<S>& r, std::int64_t root) {
    return FaceRecord{root,     r.degenerate, kind,     r.roots,
                      r.degree, r.certain,    r.proven, r.withinRounding};
  }
  int n_;
  std::vector<Block> blocks_;                          ///< per leaf
  std::vector<Chunk> chunks_ = std::vector<Chunk>(1);  ///< the first grows (add); then per window
};

extern template class FaceStore<double>;
extern template class FaceStore<Mpfr>;

}  // namespace ndc::crossing_detail
