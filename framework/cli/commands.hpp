/// \file commands.hpp
/// The subcommands of the `ndcontour` command-line tool.
#pragma once

#include <ostream>

#include "problem.hpp"

namespace ndc::cli {

/// `ndcontour info`: prints the problem (name, n, k, m, variables and domain, each equation
/// with its degrees per variable and Bernstein coefficient count, and the expectations).
void printInfo(const Problem& problem, std::ostream& out);

}  // namespace ndc::cli
