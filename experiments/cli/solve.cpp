// `ndcontour solve`: runs the pipeline, compares the mesh with [expect] and writes the outputs
// of docs/contracts.md 4.2-4.5.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/cli/commands.hpp"
#include "framework/io/io.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/budget.hpp"
#include "framework/problem/expectation.hpp"
#include "pipeline/pipeline.hpp"

namespace ndc::cli {

void checkWritable(const std::filesystem::path& dir) {
  createDirectories(dir, "output directory");
  const auto probe = dir / (".ndcontour-probe" + std::to_string(::getpid()));
  // The reason read at once: a later call may set errno again.
  if (!std::ofstream(probe))
    throw InputError(dir.string() + ": the output directory is not writable: " + failureReason());
  std::error_code ignored;
  std::filesystem::remove(probe, ignored);
}

Progress terminalProgress(bool quiet) {
  if (quiet || !::isatty(STDERR_FILENO)) return {};
  using Clock = std::chrono::steady_clock;
  return [last = Clock::time_point(), shown = std::string(), ended = false](
             const char* stage, double fraction) mutable {
    // Redrawn when the stage changes, at its end (once), or a tenth of a second after the last
    // time.
    const auto now = Clock::now();
    if (stage == shown &&
        (ended || (fraction < 1.0 && now - last < std::chrono::milliseconds(100))))
      return;
    last = now, shown = stage, ended = fraction >= 1.0;
    fraction = std::clamp(fraction, 0.0, 1.0);
    const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
    // \033[K clears what a longer stage text left on the line.
    std::fprintf(stderr, "\r%-12s [%.*s%*s] %3d%%\033[K", stage, filled,
                 "##############################", width - filled, "",
                 static_cast<int>(fraction * 100 + 0.5));
    if (fraction >= 1.0) std::fputs("\n", stderr);
    std::fflush(stderr);
  };
}

namespace {

/// Numbers as `(a, b, c)` (or between other brackets) in the stream's default precision.
std::string listText(const std::vector<double>& values, char open = '(', char close = ')') {
  std::ostringstream text;
  text << open;
  for (std::size_t j = 0; j < values.size(); ++j) text << (j ? ", " : "") << values[j];
  text << close;
  return text.str();
}

/// Warnings on standard error, one line each naming the problem file: differences from
/// `[expect]` (and keys that could not be compared), an empty zero set, dual vertices off M,
/// and crossings left within rounding of a grid face.
void warn(const Problem& problem, const Summary& s, bool check) {
  const std::string& file = problem.path;
  for (const ExpectCheck& c : s.expect)
    if (!c.ok) std::cerr << file << ": " << describeCheck(c) << '\n';
  const Expectation& x = problem.expect;
  if (check && x.empty()) std::cerr << file << ": --check: the problem has no [expect] to check\n";
  if (emptyZeroSet(s))
    std::cerr << file << ": the zero set does not meet the domain (every cell is excluded by "
              << "its bounds): the mesh is empty\n";
  if (s.offManifoldVertices > 0)
    std::cerr << file << ": " << s.offManifoldVertices
              << " dual vertices could not be projected onto M\n";
  if (s.settings.tolerance > 0 && s.mesh.maxChordError > s.settings.tolerance)
    std::cerr << file << ": --tolerance " << s.settings.tolerance
              << " not reached: max chord error " << s.mesh.maxChordError << " (limit: --max-depth "
              << s.topology.maxDepth << " or the leaf budget, docs/certificate.md)\n";
  if (s.perturbation.degenerateCrossings > 0)
    std::cerr << file << ": " << s.perturbation.degenerateCrossings
              << " crossings are within rounding of a grid face after " << s.perturbation.attempts
              << " attempts: general position is not verified\n";
}

/// The one line on the topology certificate: certified, or not and why.
void printTopology(const TopologyRecord& t, bool empty) {
  if (t.certified && empty) {
    std::cout << "topology: certified (empty: M does not meet the domain)\n";
  } else if (t.certified) {
    std::cout << "topology: certified (" << t.certifiedCells << " cells";
    if (t.blockCells > 0) std::cout << ", " << t.blockCells << " in blocks";
    if (t.refinedCells > 0)
      std::cout << ", " << t.refinedCells << " refined, down to level " << t.maxLevel;
    std::cout << ")\n";
  } else {
    std::cout << "topology: not certified: " << t.reason << '\n';
  }
}

/// The human summary's lines for `[expect]`, singular points, off-manifold vertices and the
/// perturbation.
void printDiagnostics(const Summary& s) {
  if (!s.expect.empty()) {
    std::cout << "expect:";
    for (std::size_t i = 0; i < s.expect.size(); ++i) {
      const ExpectCheck& c = s.expect[i];
      std::cout << (i ? ", " : " ") << c.key << " = " << expectedText(c);
      if (!c.notComparable.empty())
        std::cout << " not comparable";
      else if (c.ok)
        std::cout << " ok";
      else
        std::cout << " got " << gotText(c);
    }
    std::cout << '\n';
  }
  // Singular points: the count and the first few.
  constexpr std::size_t kShown = 3;
  std::cout << "singular points: " << s.singularPoints.size();
  for (std::size_t i = 0; i < std::min(kShown, s.singularPoints.size()); ++i)
    std::cout << (i ? "; " : ": ") << listText(s.singularPoints[i].point) << " sigma_min "
              << s.singularPoints[i].sigmaMin;
  if (s.singularPoints.size() > kShown)
    std::cout << "; ... (" << s.singularPoints.size() - kShown << " more)";
  std::cout << '\n';
  if (s.offManifoldVertices > 0)
    std::cout << "off-manifold vertices: " << s.offManifoldVertices
              << " (dual vertices Newton could not project onto M)\n";
  printTopology(s.topology, emptyZeroSet(s));
  const PerturbationRecord& q = s.perturbation;
  if (!q.level.empty() || q.attempts > 0) {
    std::cout << "general position: ";
    if (q.level.empty())
      std::cout << "no level offset";
    else
      std::cout << "level offset c = " << listText(q.level, '[', ']');
    std::cout << " (" << q.attempts << (q.attempts == 1 ? " attempt" : " attempts");
    if (q.degenerateCrossings > 0)
      std::cout << "; " << q.degenerateCrossings
                << " crossings within rounding of a grid face: not verified";
    std::cout << ")\n";
  }
}

/// The pipeline, with running out of memory (the estimate was low, or the address-space limit
/// was reached) reported as bad input that names the budget.
RunResult solveWithin(const Problem& problem, const Settings& settings, bool quiet) {
  try {
    // A long run says so before its work (a progress bar may be on the line: start anew).
    const Notice notice = [](const std::string& line) {
      std::cerr << (::isatty(STDERR_FILENO) ? "\n" : "") << line << std::endl;
    };
    return runPipeline(problem, settings, terminalProgress(quiet), notice);
  } catch (const std::bad_alloc&) {
    const double budget = static_cast<double>(settings.maxMemoryBytes ? settings.maxMemoryBytes
                                                                      : defaultMemoryBudget());
    throw InputError(problem.path + ": depth " + std::to_string(settings.depth) +
                     " ran out of memory (the budget is " + formatBytes(budget) +
                     "): use a smaller depth, or set --max-memory if the machine has more");
  }
}

/// The run's limits: `--timeout` as an alarm that ends the process, and the memory budget as
/// the address-space limit that turns an underestimate into std::bad_alloc (exit 2, main.cpp).
void armBudgets(const SolveOptions& options, const Problem& problem) {
  const Settings& s = options.settings;
  // Each worker thread maps its own malloc arena (64 MB of address space, little of it
  // resident) and stack: slack for them on top of the budget.
  const auto perThread = std::uint64_t{68} << 20;
  limitAddressSpace((s.maxMemoryBytes ? s.maxMemoryBytes : defaultMemoryBudget()) +
                    perThread * static_cast<std::uint64_t>(effectiveThreads(s.threads)));
  if (!s.timeoutSeconds) return;
  std::ostringstream line;
  line << problem.path << ": stopped by --timeout after " << *s.timeoutSeconds << " s";
  if (options.outDir) line << " (" << *options.outDir << " keeps its previous run)";
  armTimeout(*s.timeoutSeconds, line.str(), kExitTimeout);
}

}  // namespace

int runSolve(SolveOptions options, const Problem& problem) {
  if (options.outDir) checkWritable(*options.outDir);
  installInterruptCleanup();
  armBudgets(options, problem);
  RunResult result = solveWithin(problem, options.settings, options.json);
  if (!options.outDir) disarmTimeout();
  return reportSolve(options, problem, result);
}

int reportSolve(const SolveOptions& options, const Problem& problem, RunResult& result) {
  // docs/contracts.md 4.5: the mesh against the problem's [expect] (none: no `expect` in the
  // summary).
  result.summary.expect = checkExpectation(problem.expect, result.summary.mesh, result.k);
  const int status =
      options.check && expectationMismatch(result.summary.expect) ? kExitExpectMismatch : kExitOk;
  std::vector<std::string> written;
  if (options.outDir) {
    OutputOptions output;
    output.format = options.ascii ? PlyFormat::ascii : PlyFormat::binary;
    output.cells = options.cells;
    output.vtk = options.vtk;
    output.legacyVtk = options.legacyVtk;
    output.obj = options.obj;
    written = writeOutputs(*options.outDir, result, output);
  }
  warn(problem, result.summary, options.check);
  if (options.json) {
    std::cout << toJson(result.summary);
    return status;
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
            // The mesh's boundary (M ∩ ∂D for crossing, docs/crossing.md): in the field names of
            // summary.json, so the two read the same.
            << "boundary: " << m.boundaryComponents << " boundary components (" << m.boundaryEdges
            << " boundary edges), " << m.openEnds << " open ends\n"
            << "defects: " << m.branchVertices << " branch vertices, " << m.nonmanifoldEdges
            << " non-manifold edges\n"
            << "homology: betti " << bettiText(m.betti) << ", over Z/2 " << bettiText(m.bettiZ2)
            << "\n"
            << "accuracy: max residual " << m.maxResidual << ", max chord error " << m.maxChordError
            << "\n"
            << "time: " << s.tTotal << " s\n";
  printDiagnostics(s);
  if (options.outDir) {
    std::cout << "wrote";
    for (std::size_t i = 0; i < written.size(); ++i)
      std::cout << (i ? ", " : " ")
                << (std::filesystem::path(*options.outDir) / written[i]).string();
    std::cout << '\n';
  }
  return status;
}

}  // namespace ndc::cli
