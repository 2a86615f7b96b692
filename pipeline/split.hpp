/// \file split.hpp
/// One solve cut into pieces (docs/split.md, `ndcontour solve --split S`): the domain is cut into
/// S boxes on planes of the grid, each box is solved on its own (as a process, on this machine or
/// as a task of a Slurm job array), and the pieces' meshes are glued along the faces they share
/// (framework/mesh/glue.hpp) into one mesh whose summary merges theirs.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "framework/io/result.hpp"
#include "framework/mesh/glue.hpp"
#include "framework/numeric/box.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"

namespace ndc {

/// The most pieces of a split solve (a Slurm job array of that many tasks fits the default
/// MaxArraySize of 1001).
inline constexpr int kMaxSplitPieces = 512;

/// How the domain is cut: S = 2^h pieces, the domain halved h times with the axes taken in turn
/// (axis 0, 1, .., n - 1, 0, ..), so each piece is a box of the grid of depth t = floor(h / n)
/// on the last n - e axes and t + 1 on the first e = h mod n. Each piece is solved at depth
/// `depth - t`, so its cells are the whole solve's where e = 0 and half as wide on the first e
/// axes otherwise (finer, never coarser, than asked).
struct SplitPlan {
  int halvings = 0;                ///< h
  int levels = 0;                  ///< t: the depth a piece's grid lies below the whole grid
  int pieceDepth = 0;              ///< `--depth` of each piece
  int pieceMaxDepth = 0;           ///< `--max-depth` of each piece
  std::vector<Box<double>> boxes;  ///< the pieces, axis 0 fastest
};

/// The plan of `--split pieces` for a problem and its settings. Throws UsageError (one line) when
/// `pieces` is not a power of two in 1..kMaxSplitPieces or leaves a piece less than one level
/// of depth, and InputError for a problem the pieces cannot reproduce (jitter, B-spline or
/// application input).
SplitPlan planSplit(const Problem& problem, const Settings& settings, int pieces);

/// `--domain` text for a box: `lo:hi` per axis, comma-separated, each number in the shortest text
/// that reads back to the same double.
std::string domainText(const Box<double>& box);

/// Reads `--domain` text for n variables. Throws UsageError (one line) when it is not n pairs
/// `lo:hi` of finite numbers with lo < hi.
Box<double> parseDomainText(const std::string& text, int n);

/// What one piece left in its output folder (`mesh.ply`, `summary.json`, `uncertified.csv`).
struct PieceOutput {
  MeshPiece mesh;
  std::string summaryJson;     ///< the text of its summary.json
  std::string uncertifiedCsv;  ///< the text of its uncertified.csv ("" when certified)
};

/// Reads a piece's output folder. Throws InputError naming the file when a file is missing or
/// malformed.
PieceOutput readPiece(const std::filesystem::path& dir, const Box<double>& box);

/// The whole solve from its pieces: their meshes glued (framework/mesh/glue.hpp), the mesh and
/// accuracy analysed again on the glued mesh in the run's scalar, the counts, times and
/// certificates merged (docs/split.md, "The merged summary"); `wallSeconds` is the split solve's
/// own time. The topology is certified only when every piece's is and the pieces meet on every
/// shared face.
RunResult mergePieces(const Problem& problem, const Settings& settings, const SplitPlan& plan,
                      const std::vector<PieceOutput>& pieces, double wallSeconds);

}  // namespace ndc
