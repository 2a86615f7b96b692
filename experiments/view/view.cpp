// `ndcontour view` (view.hpp): the page of a result folder, three.js and the data inlined.
#include "experiments/view/view.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

#include "experiments/runner/csv.hpp"
#include "experiments/view/embedded.hpp"
#include "framework/io/io.hpp"
#include "framework/problem/problem.hpp"
#include "framework/util/base64.hpp"
#include "framework/util/errors.hpp"
#include "framework/util/json.hpp"

namespace ndc::view {
namespace {

namespace fs = std::filesystem;

/// What the page needs from summary.json: its text (the page reads the rest itself), n and k.
struct Summary {
  std::string text;
  int n = 0, k = 0;
  std::size_t singular = 0;  ///< entries of diagnostics.singular_points
};

/// The mesh as the page draws it: per vertex `dims` coordinates, the simplices' vertex indices
/// and per simplex whether it lies in an uncertified cell.
struct PageMesh {
  std::vector<std::string> names;  ///< of the coordinates: u0 .. u{n-1} (x y z first for an
                                   ///< application whose 3-D image is not the first three)
  std::vector<float> coordinates;  ///< vertex-major
  std::vector<std::uint32_t> indices;
  std::vector<std::uint8_t> uncertified;
  std::vector<float> cells;  ///< the centres of the uncertified cells, n coordinates each
};

/// An integer field of the flattened summary; throws when it is absent or not an integer.
int summaryInt(const std::vector<std::pair<std::string, std::string>>& fields,
               const std::string& key, const fs::path& file) {
  for (const auto& [path, value] : fields) {
    if (path != key) continue;
    try {
      std::size_t used = 0;
      const int v = std::stoi(value, &used);
      if (used == value.size()) return v;
    } catch (const std::exception&) {
    }
    throw InputError(file.string() + ": '" + key + "' is not an integer");
  }
  throw InputError(file.string() + ": no field '" + key + "' (not a summary of ndcontour solve)");
}

Summary readSummary(const fs::path& file) {
  if (!fs::is_regular_file(file))
    throw InputError(file.string() + ": missing (not a finished run of ndcontour solve --out)");
  Summary s;
  s.text = readInputFile(file, "summary");
  std::vector<std::pair<std::string, std::string>> fields;
  try {
    fields = flattenJsonNumbers(s.text);
  } catch (const std::runtime_error& e) {
    throw InputError(file.string() + ": " + e.what());
  }
  s.n = summaryInt(fields, "n", file);
  s.k = summaryInt(fields, "k", file);
  if (s.n < 2 || s.n > 64 || s.k < 1 || s.k >= s.n)
    throw InputError(file.string() + ": n = " + std::to_string(s.n) +
                     ", k = " + std::to_string(s.k) + " (expected 2 <= n <= 64 and 1 <= k < n)");
  const std::string prefix = "diagnostics.singular_points.";
  for (const auto& field : fields)
    if (field.first.starts_with(prefix) && field.first.ends_with(".sigma_min")) ++s.singular;
  return s;
}

/// Whether the 3-D image `x y z` differs from the first three coordinates (an application).
bool separateImage(const PlyMesh& mesh) {
  for (std::size_t v = 0; v < mesh.xyz.size(); ++v)
    for (std::size_t j = 0; j < 3; ++j) {
      const double a = mesh.xyz[v][j], b = j < mesh.u[v].size() ? mesh.u[v][j] : 0.0;
      if (a != b && !(std::isnan(a) && std::isnan(b))) return true;
    }
  return false;
}

/// The vertex coordinates of the page, checked against n.
void pageCoordinates(const PlyMesh& mesh, int n, const fs::path& file, PageMesh& page) {
  for (std::size_t v = 0; v < mesh.u.size(); ++v)
    if (mesh.u[v].size() != static_cast<std::size_t>(n))
      throw InputError(file.string() + ": vertex " + std::to_string(v + 1) + " has " +
                       std::to_string(mesh.u[v].size()) +
                       " coordinates u0.., summary.json says n = " + std::to_string(n));
  const bool image = separateImage(mesh);
  if (image) page.names = {"x", "y", "z"};
  for (int j = 0; j < n; ++j) {
    std::string name = "u";  // not "u" + ...: GCC 12 warns falsely (-Wrestrict) on that
    page.names.push_back(name += std::to_string(j));
  }
  page.coordinates.reserve(mesh.u.size() * page.names.size());
  for (std::size_t v = 0; v < mesh.u.size(); ++v) {
    if (image)
      for (double x : mesh.xyz[v]) page.coordinates.push_back(static_cast<float>(x));
    for (double x : mesh.u[v]) page.coordinates.push_back(static_cast<float>(x));
  }
}

/// The simplices, checked against k.
void pageSimplices(const PlyMesh& mesh, int k, const fs::path& file, PageMesh& page) {
  const std::size_t size = static_cast<std::size_t>(k) + 1;
  page.indices.reserve(mesh.simplices.size() * size);
  for (std::size_t s = 0; s < mesh.simplices.size(); ++s) {
    if (mesh.simplices[s].size() != size)
      throw InputError(file.string() + ": simplex " + std::to_string(s + 1) + " has " +
                       std::to_string(mesh.simplices[s].size()) + " vertices (k = " +
                       std::to_string(k) + " in summary.json needs " + std::to_string(size) + ")");
    for (int v : mesh.simplices[s]) page.indices.push_back(static_cast<std::uint32_t>(v));
  }
}

/// A box of uncertified.csv: lo and hi per coordinate.
using Box = std::vector<std::pair<double, double>>;

/// The boxes of the `cell` rows of uncertified.csv (none when the file is absent).
std::vector<Box> uncertifiedBoxes(const fs::path& file, int n) {
  std::vector<Box> boxes;
  if (!fs::exists(file)) return boxes;
  const CsvTable csv = readCsv(file);
  for (std::size_t row = 0; row < csv.size(); ++row) {
    if (csv.cell(row, "kind") != "cell") continue;
    Box box(static_cast<std::size_t>(n));
    for (int j = 0; j < n; ++j) {
      const std::string i = std::to_string(j);
      box[static_cast<std::size_t>(j)] = {csv.number(row, "lo" + i), csv.number(row, "hi" + i)};
    }
    boxes.push_back(std::move(box));
  }
  return boxes;
}

bool inside(const Box& box, const std::vector<double>& x) {
  for (std::size_t j = 0; j < box.size(); ++j)
    if (!(x[j] >= box[j].first && x[j] <= box[j].second)) return false;
  return true;
}

/// Per simplex: 1 when its centroid (in u0 ..) lies in an uncertified box (as mesh.vtu's
/// `uncertified`).
std::vector<std::uint8_t> uncertifiedFlags(const PlyMesh& mesh, const std::vector<Box>& boxes,
                                           int n) {
  std::vector<std::uint8_t> flags(mesh.simplices.size(), 0);
  if (boxes.empty()) return flags;
  // The boxes' hull first: most simplices lie far from every uncertified cell.
  Box hull = boxes.front();
  for (const Box& b : boxes)
    for (std::size_t j = 0; j < hull.size(); ++j)
      hull[j] = {std::min(hull[j].first, b[j].first), std::max(hull[j].second, b[j].second)};
  std::vector<double> c(static_cast<std::size_t>(n));
  for (std::size_t s = 0; s < mesh.simplices.size(); ++s) {
    std::fill(c.begin(), c.end(), 0.0);
    for (int v : mesh.simplices[s])
      for (std::size_t j = 0; j < c.size(); ++j)
        c[j] +=
            mesh.u[static_cast<std::size_t>(v)][j] / static_cast<double>(mesh.simplices[s].size());
    flags[s] = inside(hull, c) &&
               std::any_of(boxes.begin(), boxes.end(), [&](const Box& b) { return inside(b, c); });
  }
  return flags;
}

/// The bytes of `data` in base64.
template <class T>
std::string base64(const std::vector<T>& data) {
  return ndc::base64(data.data(), data.size() * sizeof(T));
}

/// The mesh as the JSON the page reads (`ndc-mesh`).
std::string meshJson(const PageMesh& page, const Summary& summary, const std::string& source) {
  std::ostringstream out;
  out << "{\"n\": " << summary.n << ", \"k\": " << summary.k
      << ", \"source\": " << jsonQuoted(source) << ", \"coordinates\": [";
  for (std::size_t j = 0; j < page.names.size(); ++j)
    out << (j ? ", " : "") << jsonQuoted(page.names[j]);
  out << "], \"vertices\": " << page.coordinates.size() / page.names.size()
      << ", \"simplices\": " << page.uncertified.size() << ", \"positions\": \""
      << base64(page.coordinates) << "\", \"indices\": \"" << base64(page.indices)
      << "\", \"uncertified\": \"" << base64(page.uncertified) << "\", \"cells\": \""
      << base64(page.cells) << "\"}";
  return out.str();
}

/// `text` safe inside a <script> element: no `</` (JSON allows `<\/` in strings, where alone
/// summary.json can hold a `<`).
std::string scriptSafe(std::string text) {
  for (std::size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3))
    text.replace(at, 2, "<\\/");
  return text;
}

/// Replaces the marker `<!--NAME-->` of the page by `text`.
void fill(std::string& page, std::string_view marker, const std::string& text) {
  const std::size_t at = page.find(marker);
  if (at == std::string::npos)
    throw std::logic_error("viewer.html lacks the marker " + std::string(marker));
  page.replace(at, marker.size(), text);
}

std::string pageText(const std::string& meshData, const Summary& summary) {
  std::string page(embedded::pageHtml());
  fill(page, "<!--NDC_THREE-->", "<script>" + std::string(embedded::threeJs()) + "</script>");
  fill(page, "<!--NDC_DATA-->",
       "<script type=\"application/json\" id=\"ndc-summary\">" + scriptSafe(summary.text) +
           "</script>\n<script type=\"application/json\" id=\"ndc-mesh\">" + meshData +
           "</script>");
  fill(page, "<!--NDC_VIEWER-->", "<script>" + std::string(embedded::pageJs()) + "</script>");
  return page;
}

/// Reads mesh.ply and uncertified.csv of `resultDir`, checked against the summary, into the
/// page's mesh; `stats` says what it holds.
PageMesh readPage(const fs::path& resultDir, const Summary& summary, ViewerStats& stats) {
  const fs::path plyFile = resultDir / "mesh.ply";
  const PlyMesh mesh = readPly(plyFile);
  PageMesh page;
  pageCoordinates(mesh, summary.n, plyFile, page);
  pageSimplices(mesh, summary.k, plyFile, page);
  const std::vector<Box> boxes = uncertifiedBoxes(resultDir / "uncertified.csv", summary.n);
  page.uncertified = uncertifiedFlags(mesh, boxes, summary.n);
  for (const Box& box : boxes)
    for (const auto& [lo, hi] : box) page.cells.push_back(static_cast<float>((lo + hi) / 2));
  stats.n = summary.n;
  stats.k = summary.k;
  stats.vertices = mesh.xyz.size();
  stats.simplices = mesh.simplices.size();
  if (summary.k <= 2) (summary.k == 2 ? stats.triangles : stats.segments) = stats.simplices;
  stats.uncertified = static_cast<std::size_t>(
      std::count(page.uncertified.begin(), page.uncertified.end(), std::uint8_t{1}));
  stats.singular = summary.singular;
  stats.uncertifiedCells = boxes.size();
  return page;
}

}  // namespace

bool viewerAvailable() { return !embedded::threeJs().empty(); }

std::string viewerMissingMessage() {
  return "ndcontour view: this build has no three.js: run scripts/setup.sh (npm ci in "
         "experiments/view/web), then rebuild";
}

ViewerStats writeViewer(const fs::path& resultDir, const fs::path& out) {
  if (!fs::is_directory(resultDir))
    throw InputError(resultDir.string() +
                     ": not a folder (give the --out folder of ndcontour solve)");
  const fs::path plyFile = resultDir / "mesh.ply";
  if (!fs::is_regular_file(plyFile))
    throw InputError(plyFile.string() + ": missing (not a result folder of ndcontour solve --out)");
  const Summary summary = readSummary(resultDir / "summary.json");
  ViewerStats stats;
  const PageMesh page = readPage(resultDir, summary, stats);
  if (!viewerAvailable()) throw InputError(viewerMissingMessage());
  fs::path name = fs::absolute(resultDir).lexically_normal();
  if (name.filename().empty()) name = name.parent_path();
  writeAtomically(out, pageText(meshJson(page, summary, name.filename().string()), summary));
  return stats;
}

std::string writeRunViewers(const fs::path& runsDir, const std::string& linkPrefix) {
  std::error_code error;
  if (!viewerAvailable() || !fs::is_directory(runsDir, error)) return "";
  std::vector<fs::path> runs;
  for (const fs::directory_entry& e : fs::directory_iterator(runsDir, error))
    if (fs::exists(e.path() / "mesh.ply") && fs::exists(e.path() / "summary.json"))
      runs.push_back(e.path());
  std::sort(runs.begin(), runs.end());
  std::vector<std::string> links;
  for (const fs::path& run : runs) {
    try {
      writeViewer(run, run / "view.html");
    } catch (const InputError&) {
      continue;
    }
    const std::string name = run.filename().string();
    links.push_back("[" + name + "](" + linkPrefix + name + "/view.html)");
  }
  if (links.empty()) return "";
  std::string line = "\n3-D views of the meshes (`ndcontour view`): ";
  for (std::size_t i = 0; i < links.size(); ++i) line += (i ? ", " : "") + links[i];
  return line + ".\n";
}

}  // namespace ndc::view
