// `ndcontour bench`: times each pipeline stage on problem files (median of repeated runs).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <limits>
#include <vector>

#include "applications/load.hpp"
#include "experiments/cli/commands.hpp"
#include "pipeline/pipeline.hpp"

namespace ndc::cli {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

void addBenchOptions(CLI::App& bench, BenchOptions& o) {
  bench.add_option("problems", o.problems, "Problem files (TOML)")->required();
  bench.add_option("--depth", o.settings.depth, "Subdivision depth L")->capture_default_str();
  bench.add_option("--bounding", o.settings.bounding, "Bounding strategy")->capture_default_str();
  bench.add_option("--subdivision", o.settings.subdivision, "Subdivision strategy")
      ->capture_default_str();
  bench.add_option("--connection", o.settings.connection, "Connection strategy")
      ->capture_default_str();
  bench.add_option("--scalar", o.settings.scalar, "Scalar type")->capture_default_str();
  bench.add_option("--precision", o.settings.precisionBits, "MPFR precision in bits");
  bench.add_option("--jitter", o.jitter, "Grid jitter seed")
      ->check(unsignedUpTo(std::numeric_limits<std::uint64_t>::max()))
      ->type_name("SEED");
  addThreadsOption(bench, o.settings.threads);
  bench.add_option("--repeat", o.repeat, "Runs per problem (the median is reported)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
}

int runBench(BenchOptions o) {
  if (o.settings.scalar == "mpfr" && o.settings.precisionBits == 53) o.settings.precisionBits = 128;
  if (o.jitter) o.settings.jitter = *o.jitter;
  // Check every name, value and file before the table starts, so bad input prints nothing.
  SolveOptions check;
  check.settings = o.settings;
  if (o.settings.scalar == "mpfr") check.precision = o.settings.precisionBits;
  validateSolveOptions(check);
  std::vector<Problem> problems;
  for (const std::string& path : o.problems) {
    problems.push_back(loadProblem(path));
    validateSolveOptions(check, problems.back());
  }
  std::cout << "| problem | n | k | depth | bounding | subdivision | connection | scalar | "
               "solution cells | subdivision s | projection s | connection s | analysis s | "
               "total s |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Problem& problem : problems) {
    std::vector<double> sub, proj, conn, ana, total;
    std::int64_t cells = 0;
    for (int r = 0; r < o.repeat; ++r) {
      const Summary s = runPipeline(problem, o.settings).summary;
      sub.push_back(s.tSubdivision);
      proj.push_back(s.tProjection);
      conn.push_back(s.tConnection);
      ana.push_back(s.tAnalysis);
      total.push_back(s.tTotal);
      cells = s.solution;
    }
    std::cout << std::fixed << std::setprecision(3) << "| " << problem.name << " | " << problem.n()
              << " | " << problem.k() << " | " << o.settings.depth << " | " << o.settings.bounding
              << " | " << o.settings.subdivision << " | " << o.settings.connection << " | "
              << o.settings.scalar << " | " << cells << " | " << median(sub) << " | "
              << median(proj) << " | " << median(conn) << " | " << median(ana) << " | "
              << median(total) << " |" << std::endl;
  }
  return 0;
}

}  // namespace ndc::cli
