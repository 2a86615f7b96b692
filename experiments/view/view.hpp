/// \file view.hpp
/// `ndcontour view` (docs/viewer.md): one self-contained HTML page that shows the mesh of a
/// result folder of `ndcontour solve --out DIR` in a web browser, with three.js (WebGL) inlined,
/// so that the page needs no network and no other file. The page projects R^n to 3-D (three
/// chosen coordinates, or a rotation of R^n in chosen planes, or an animated grand tour),
/// colours by any coordinate, and marks the singular points of summary.json and the simplices
/// that lie in an uncertified cell of uncertified.csv. A k-manifold for k >= 3 is shown by a
/// slice (its k-simplices cut by a hyperplane u_j = t the reader moves) or by its edges.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

namespace ndc::view {

/// What writeViewer put into the page.
struct ViewerStats {
  int n = 0;                         ///< the dimension of the ambient space
  int k = 0;                         ///< the manifold's dimension: 1 curve, 2 surface, ..
  std::size_t vertices = 0;          ///< vertices of mesh.ply
  std::size_t simplices = 0;         ///< k-simplices of mesh.ply (any k)
  std::size_t triangles = 0;         ///< faces of mesh.ply (k = 2)
  std::size_t segments = 0;          ///< edges of mesh.ply (k = 1)
  std::size_t uncertified = 0;       ///< simplices whose centroid lies in a box of uncertified.csv
  std::size_t singular = 0;          ///< singular points of summary.json
  std::size_t uncertifiedCells = 0;  ///< `cell` rows of uncertified.csv
};

/// Whether this build holds three.js (the build embeds it from `experiments/view/web/` after
/// `scripts/setup.sh` has run `npm ci` there).
bool viewerAvailable();

/// The one line that says how to get three.js into the build.
std::string viewerMissingMessage();

/// Writes the page for the result folder `resultDir` (`mesh.ply`, `summary.json`, and
/// `uncertified.csv` when present) to `out`, atomically (a temporary file renamed into place:
/// a failure leaves an earlier page alone). Vertex coordinates (float32), simplex indices
/// (uint32), the uncertified flags (uint8) and the centres of the uncertified cells (float32)
/// go into the page as base64, summary.json as it is. Throws ndc::InputError
/// (one line naming the file) when the folder, mesh.ply or summary.json is missing or
/// malformed, when they disagree (n, k, vertex coordinates), or when this build has no three.js
/// (viewerMissingMessage).
ViewerStats writeViewer(const std::filesystem::path& resultDir, const std::filesystem::path& out);

/// For the report: writes `view.html` into every run folder under `runsDir` (an experiment's
/// `results/<id>/runs/`) that holds a finished run with a mesh (`mesh.ply` and `summary.json`),
/// and returns one Markdown line linking the pages, each as `linkPrefix` + `RUN/view.html`
/// (runs in name order). A run whose page cannot be made is left out. Empty when no page was
/// written, or when this build has no three.js.
std::string writeRunViewers(const std::filesystem::path& runsDir, const std::string& linkPrefix);

}  // namespace ndc::view
