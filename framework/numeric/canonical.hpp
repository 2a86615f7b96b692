/// \file canonical.hpp
/// The canonical form of an equation: its program expanded into sparse monomials with exact
/// decimal coefficients, like terms collected, and compiled back into a Tape. An equation is
/// written by people or generated (by a computer algebra system, an implicitisation), and a
/// generated one may spell a few coefficients in megabytes of text (166,666 copies of `x*y*z`
/// is `166666*x*y*z`); every evaluation of its program would pay for the text. The parser
/// compiles each equation once, and Expression::parse keeps the canonical program when it is
/// much shorter (docs/input-limits.md, "Long equations").
///
/// The coefficients stay exact: sums and products of decimal literals are decimals, and so is a
/// quotient by a constant whose digits have no prime factor but 2 and 5 (`/ 4`, `/ 0.8`); each
/// coefficient is written as one decimal literal, so `--scalar mpfr` reads it exactly as it
/// reads the text's literals and form_rounding.hpp proves the same bounds.
#pragma once

#include <cstddef>
#include <optional>

#include "framework/numeric/tape.hpp"

namespace ndc {

/// The limits of an expansion; past any of them canonicalTape gives up (nullopt).
struct CanonicalLimits {
  /// Most monomials of any intermediate polynomial.
  std::size_t maxTerms = 0;
  /// Most monomial products and merges over the whole expansion (the work of the expansion).
  std::size_t maxWork = 0;
  /// Most decimal digits of a coefficient (a power of a long literal grows them).
  std::size_t maxDigits = 200;
};

/// The canonical program of `tape`: sum over monomials c * x_0^a_0 * ... in a fixed order
/// (graded, then lexicographic in the exponents), with a positive literal per coefficient;
/// nullopt when `tape` has piecewise leaves, a divisor whose reciprocal is not a finite
/// decimal, or exceeds `limits`. The polynomial is the same, exactly.
std::optional<Tape> canonicalTape(const Tape& tape, const CanonicalLimits& limits);

/// The limits Expression::parse uses for a program of `ops` instructions: at most as many
/// monomials as instructions, and work linear in them (the expansion costs no more than a few
/// evaluations of the program would).
CanonicalLimits canonicalLimitsFor(std::size_t ops);

}  // namespace ndc
