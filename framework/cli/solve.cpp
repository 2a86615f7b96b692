// `ndcontour solve`: runs the pipeline and writes the outputs of design.md 4.2-4.4.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli/commands.hpp"
#include "io.hpp"
#include "pipeline.hpp"

namespace ndc::cli {
namespace {

/// Fails early (before minutes of work) if `dir` cannot receive the outputs.
void checkWritable(const std::filesystem::path& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error || !std::filesystem::is_directory(dir)) {
    throw InputError(dir.string() + ": cannot create the output directory");
  }
  const auto probe = dir / (".ndcontour-probe" + std::to_string(::getpid()));
  std::ofstream(probe) << "";
  if (!std::filesystem::exists(probe)) {
    throw InputError(dir.string() + ": the output directory is not writable");
  }
  std::filesystem::remove(probe, error);
}

/// A one-line progress bar on standard error, only when it is a terminal.
Progress terminalProgress() {
  if (!::isatty(STDERR_FILENO)) return {};
  return [](const char* stage, double fraction) {
    const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
    std::fprintf(stderr, "\r%-12s [%.*s%*s] %3d%%", stage, filled, "##############################",
                 width - filled, "", static_cast<int>(fraction * 100 + 0.5));
    if (fraction >= 1.0) std::fputs("\n", stderr);
    std::fflush(stderr);
  };
}

}  // namespace

int runSolve(SolveOptions options, const Problem& problem) {
  if (options.tolerance) options.settings.depth = depthForTolerance(problem, *options.tolerance);
  if (options.outDir) checkWritable(*options.outDir);
  const RunResult result = runPipeline(problem, options.settings, terminalProgress());
  if (options.outDir) writeOutputs(*options.outDir, result);
  if (options.json) {
    std::cout << toJson(result.summary);
    return 0;
  }
  const Summary& s = result.summary;
  const MeshStats& m = s.mesh;
  std::cout << "problem " << s.problem << ": n = " << s.n << ", k = " << s.k << ", depth "
            << s.settings.depth << "\n"
            << "cells: visited " << s.visited << ", solution " << s.solution << " (normal "
            << s.normal << ", abnormal " << s.abnormal << ", failed " << s.failed << ")\n"
            << "mesh: " << m.vertices << " vertices, " << m.edges << " edges, " << m.triangles
            << " triangles, " << m.components << " components, euler " << m.eulerCharacteristic
            << "\n"
            << "defects: " << m.openEnds << " open ends, " << m.branchVertices
            << " branch vertices, " << m.boundaryEdges << " boundary edges, " << m.nonmanifoldEdges
            << " non-manifold edges\n"
            << "accuracy: max residual " << m.maxResidual << ", max chord error " << m.maxChordError
            << "\n"
            << "time: " << s.tTotal << " s\n";
  if (options.outDir) std::cout << "wrote " << options.outDir->c_str() << "/summary.json\n";
  return 0;
}

}  // namespace ndc::cli
