/// \file commands.hpp
/// The subcommands of the `ndcontour` command-line tool.
#pragma once

#include <ostream>

#include "cli/solve_options.hpp"
#include "problem.hpp"

namespace ndc::cli {

/// `ndcontour info`: prints the problem (name, n, k, m, variables and domain, each equation
/// with its degrees per variable and Bernstein coefficient count, and the expectations).
void printInfo(const Problem& problem, std::ostream& out);

/// `ndcontour solve`: runs the pipeline with the options' settings, writes summary.json,
/// mesh.ply and cells.csv into `--out DIR` and prints the summary (JSON with `--json`).
/// Returns the exit status.
int runSolve(SolveOptions options, const Problem& problem);

}  // namespace ndc::cli
