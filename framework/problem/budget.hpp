/// \file budget.hpp
/// Memory budgets of a run (`--max-memory`): the default share of the machine, a model of the
/// bytes a run needs per solution cell, byte sizes as the command line spells them, and the
/// address-space limit that turns an underestimate into a clear refusal instead of the kernel's
/// out-of-memory killer. The estimate itself (a trial subdivision) is in pipeline.cpp; the
/// limits and why they are where they are: docs/input-limits.md.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "framework/problem/problem.hpp"

namespace ndc {

/// The share of the machine's memory a run may use when `--max-memory` is not given.
inline constexpr double kDefaultMemoryShare = 0.75;

/// The memory a run may use by default: kDefaultMemoryShare of the physical memory, or of the
/// control group's limit when that is lower (a container or a Slurm job).
std::uint64_t defaultMemoryBudget();

/// Bytes a run holds per solution cell of the final grid, measured on this build (docs/
/// input-limits.md, "Budgets"): the cell list, projections, classes, the connection's vertices
/// and simplices, the welded mesh and the formatted outputs, in double; `--scalar mpfr` scales
/// with the precision. An estimate, not a bound: the address-space limit catches the rest.
double bytesPerSolutionCell(int n, int k, const std::string& scalar, unsigned precisionBits);

/// Bytes a run holds whatever its size (the program, the problem's Bernstein forms, buffers).
double baseRunBytes(int n);

/// The time model (docs/input-limits.md, "Time"): the operations a run spends per solution
/// cell, dominated by restricting each equation's Bernstein form to the cell (de Casteljau along
/// each axis): the sum over equations of coefficients x (sum of degrees + n); for an equation
/// that needs no dense form (densityFree), at most 8 n^2 (its quadratic form's evaluation).
double workPerCell(const Problem& problem);

/// Seconds per unit of workPerCell per solution cell for a whole run on this build (two
/// threads), measured on x^512 + y^2 + z^2 - 1 at depth 3 (512 cells of 2.4e6 units: 10.1 s);
/// high for low degrees (the torus at depth 8, 3.5e5 cells of 1875 units: 3.7 s, 6.0 s
/// estimated), where fixed costs per cell weigh more.
inline constexpr double kSecondsPerWork = 9e-9;

/// The refinement of the crossing connection spends at most this many seconds of the time model
/// on its solution leaves (their count times workPerCell times kSecondsPerWork): for the usual
/// degrees the leaf budget binds long before (65,536 torus leaves are 1.1 s of it).
inline constexpr double kRefineSeconds = 60;

/// A run estimated (cells x workPerCell x kSecondsPerWork) to take longer than this many
/// seconds is announced before its work (`solve` prints the estimate on standard error).
inline constexpr double kAnnounceSeconds = 60;

/// A run estimated to take more than this many times its `--timeout` is refused before its
/// work (the estimate is a model, so a run near its limit is left to the timeout).
inline constexpr double kRefuseOverTimeout = 10;

/// A byte count as `--max-memory` accepts it: a positive number with an optional suffix K, M, G
/// or T (powers of 1024, optionally followed by "B" or "iB": `512M`, `1.5G`, `16GiB`); nullopt
/// when the text is not one or the value is below 1 MiB or above 2^60 bytes.
std::optional<std::uint64_t> parseByteSize(const std::string& text);

/// `bytes` for people: "512 MiB", "35.2 GiB".
std::string formatBytes(double bytes);

/// Limits the process's address space to `bytes` plus slack for the program's own mappings, so
/// that a run that outgrows its estimate gets std::bad_alloc (reported as exit 2 by the CLI)
/// rather than the kernel's out-of-memory killer. Does nothing under AddressSanitizer, which
/// reserves terabytes of address space, or when the current limit is already lower.
void limitAddressSpace(std::uint64_t bytes);

}  // namespace ndc
