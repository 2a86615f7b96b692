// `ndcontour view RESULT_DIR [--out FILE]` (commands.hpp, docs/viewer.md).
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>
#include <string>

#include "experiments/cli/commands.hpp"
#include "experiments/view/view.hpp"

namespace ndc::cli {

void addViewOptions(CLI::App& view, ViewOptions& options) {
  view.add_option("result", options.resultDir, "Result folder of `ndcontour solve --out DIR`")
      ->required()
      ->type_name("RESULT_DIR");
  view.add_option("--out", options.out, "The page to write (default: RESULT_DIR/view.html)")
      ->type_name("FILE");
}

int runView(const ViewOptions& options) {
  const std::filesystem::path dir = options.resultDir;
  const std::filesystem::path out =
      options.out.empty() ? dir / "view.html" : std::filesystem::path(options.out);
  const ndc::view::ViewerStats s = ndc::view::writeViewer(dir, out);
  // The simplices by their name: segments, triangles, tetrahedra, then k-simplices.
  const std::string simplices = s.k == 1   ? " segments"
                                : s.k == 2 ? " triangles"
                                : s.k == 3 ? " tetrahedra"
                                           : " " + std::to_string(s.k) + "-simplices";
  std::cout << "wrote " << out.string() << ": n = " << s.n << ", " << s.vertices << " vertices, "
            << s.simplices << simplices << ", " << s.singular << " singular points, "
            << s.uncertified << " uncertified simplices in " << s.uncertifiedCells
            << " uncertified cells\n";
  return kExitOk;
}

}  // namespace ndc::cli
