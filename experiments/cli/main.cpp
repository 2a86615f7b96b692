// The `ndcontour` command-line tool (docs/contracts.md 4.2). Every error ends the program with one
// line on standard error: status 2 for bad input or usage, 1 for an internal error; `solve
// --check` exits 3 when the mesh differs from the problem's [expect] (solve_options.hpp).
#include <CLI/CLI.hpp>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cctype>
#include <iostream>
#include <string>
#include <vector>

#include "applications/load.hpp"
#include "experiments/cli/commands.hpp"
#include "experiments/cli/experiment.hpp"
#include "experiments/cli/report.hpp"
#include "experiments/cli/solve_options.hpp"
#include "framework/problem/problem.hpp"
#include "framework/util/errors.hpp"
#include "pipeline/split.hpp"

namespace {

using ndc::oneLine;
using ndc::cli::kExitBadInput;
using ndc::cli::kExitInternal;

/// "unknown option '--depht' (did you mean '--depth'?)" for the first argument of the parsed
/// subcommand that looks like an option and is none of its own; empty when there is none.
std::string unknownOption(CLI::App& app) {
  for (CLI::App* sub : app.get_subcommands()) {
    std::vector<std::string> names;
    for (const CLI::Option* option : sub->get_options()) {
      for (const std::string& l : option->get_lnames()) names.push_back("--" + l);
      for (const std::string& s : option->get_snames()) names.push_back("-" + s);
    }
    for (const std::string& arg : sub->remaining()) {
      if (arg.size() < 2 || arg[0] != '-' || std::isdigit(static_cast<unsigned char>(arg[1])))
        continue;  // a value, or a negative number
      const std::string name = arg.substr(0, arg.find('='));
      return "unknown option '" + name + "' for " + sub->get_name() + ndc::didYouMean(name, names);
    }
  }
  return "";
}

int run(int argc, char** argv) {
  CLI::App app{"ndcontour: contouring 1- and 2-manifolds in arbitrary dimensions", "ndcontour"};
  app.set_version_flag("--version", std::string("ndcontour ") + NDC_VERSION);
  app.require_subcommand(1);
  app.footer(ndc::cli::kExitStatusHelp);

  std::string infoPath;
  CLI::App* info = app.add_subcommand("info", "Describe a problem file");
  info->add_option("problem", infoPath, "Problem file (TOML, docs/contracts.md 4.1)")
      ->required()
      ->type_name("PROBLEM.toml");

  ndc::cli::SolveOptions solveOptions;
  CLI::App* solve = app.add_subcommand("solve", "Contour the zero set of a problem");
  ndc::cli::addSolveOptions(*solve, solveOptions);

  ndc::cli::BenchOptions benchOptions;
  CLI::App* bench = app.add_subcommand("bench", "Time each pipeline stage on problem files");
  ndc::cli::addBenchOptions(*bench, benchOptions);

  ndc::cli::ExperimentCommandOptions experimentOptions;
  CLI::App* experiment =
      app.add_subcommand("experiment", "Run an experiment config: problems x settings x depths");
  ndc::cli::addExperimentOptions(*experiment, experimentOptions);

  // One task of the Slurm executor's job array; started by its batch script, not by hand.
  ndc::cli::ExperimentTaskOptions taskOptions;
  CLI::App* task = app.add_subcommand("experiment-task", "Run one task of a Slurm job array");
  task->group("");
  ndc::cli::addExperimentTaskOptions(*task, taskOptions);

  ndc::cli::ReportOptions reportOptions;
  CLI::App* report = app.add_subcommand("report", "Write the tables, figures and report.md");
  ndc::cli::addReportOptions(*report, reportOptions);

  ndc::cli::ViewOptions viewOptions;
  CLI::App* view = app.add_subcommand("view", "Write an HTML page that shows a result's mesh");
  ndc::cli::addViewOptions(*view, viewOptions);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version: CLI11 prints them and the status is 0.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::string message = e.what();
    const std::vector<std::string> extra = app.remaining();
    const std::vector<std::string> commands = {"info",       "solve",  "bench",
                                               "experiment", "report", "view"};
    if (app.get_subcommands().empty() && !extra.empty() && extra.front().starts_with("-"))
      message = "unknown option '" + extra.front() + "'";
    else if (app.get_subcommands().empty() && !extra.empty())
      message = "unknown subcommand '" + extra.front() + "'" +
                ndc::didYouMean(extra.front(), commands) +
                " (accepted: info, solve, bench, experiment, report, view)";
    else if (const std::string unknown = unknownOption(app); !unknown.empty())
      message = unknown;
    else if (app.get_subcommands().empty())
      message = "a subcommand is required (accepted: info, solve, bench, experiment, report, view)";
    std::cerr << "ndcontour: " << oneLine(message) << " (see ndcontour --help)\n";
    return kExitBadInput;
  }

  if (bench->parsed()) return ndc::cli::runBench(benchOptions);
  if (report->parsed()) return ndc::cli::runReport(reportOptions);
  if (view->parsed()) return ndc::cli::runView(viewOptions);
  if (task->parsed()) return ndc::cli::runExperimentTaskCommand(taskOptions);
  if (experiment->parsed()) {
    std::string commandLine = "ndcontour";
    for (int i = 1; i < argc; ++i) commandLine += std::string(" ") + argv[i];
    return ndc::cli::runExperimentCommand(experimentOptions, commandLine);
  }
  if (info->parsed()) {
    ndc::cli::printInfo(ndc::loadProblem(infoPath), std::cout);
    return 0;
  }

  // solve: options first (they need no file), then the problem, then both together.
  ndc::cli::validateSolveOptions(solveOptions);
  ndc::Problem problem = ndc::loadProblem(solveOptions.problemPath);
  if (solveOptions.domain) problem.domain = ndc::parseDomainText(*solveOptions.domain, problem.n());
  ndc::cli::validateSolveOptions(solveOptions, problem);
  if (solveOptions.split) return ndc::cli::runSplitSolve(solveOptions, problem);
  return ndc::cli::runSolve(solveOptions, problem);
}

/// glibc's allocator for a run that allocates and frees much (docs/performance.md,
/// "Allocator"): keep freed memory for reuse instead of returning it to the system and
/// faulting it in again (trim threshold and top pad), and serve blocks up to 32 MB from the
/// heap. Only the tool does this: the library leaves a host process's allocator alone.
void tuneAllocator() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_TOP_PAD, 64 << 20);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  tuneAllocator();
  try {
    return run(argc, argv);
  } catch (const ndc::UsageError& e) {
    // Before InputError, of which it is one: a usage error names no file.
    std::cerr << "ndcontour: " << oneLine(e.what()) << '\n';
    return kExitBadInput;
  } catch (const ndc::InputError& e) {
    std::cerr << oneLine(e.what()) << '\n';
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "ndcontour: internal error: " << oneLine(e.what()) << '\n';
    return kExitInternal;
  } catch (...) {
    std::cerr << "ndcontour: internal error: unknown exception\n";
    return kExitInternal;
  }
}
