/// \file enclosure.hpp
/// Midpoint-radius enclosures of a system over a box, by runs of the equations' programs with
/// per-thread evaluators: the face solver's, the leaf certificate's and the domain boundary's
/// (docs/crossing.md, "Faces by evaluation"). Internal to the crossing connection.
#pragma once

#include <span>
#include <vector>

#include "framework/numeric/interval.hpp"
#include "framework/numeric/midrad.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/system.hpp"

namespace ndc::crossing_detail {

/// The midpoint-radius evaluators of `system`'s equations for the calling thread, built on first
/// use and kept while the same programs (at the same MPFR precision) come back: faces are
/// solved on the pool's threads, and an evaluator's scratch must not be shared.
template <class S>
std::vector<MidRadEvaluator<S>>& threadEvaluators(const System<S>& system);

/// An interval holding [mid - rad, mid + rad] although both ends are rounded to nearest: widened
/// by two units of the arithmetic relative to each end and by the smallest normal double.
template <class S>
Interval<S> enclosingInterval(const S& mid, const S& rad);

/// Midpoint-radius enclosures of the system F over the box centre +- radius (radius 0 on the
/// axes it fixes), with the thread's `evaluators`: J(X) restricted to the variables `columns`
/// into `jacobian` (m x columns.size(), row-major) and F(centre) - level into `fy`. `excluded`
/// tells whether some F_i - level_i provably has no zero on the box: its value over the box, or
/// its mean-value form F_i(centre) + sum_j J_ij(X) (X_j - centre_j), excludes 0 (the columns
/// must then hold every axis the box is wide in). With `stopWhenExcluded` it returns at the first
/// such equation with `jacobian` and `fy` incomplete. False when a run fails (a value that is not
/// finite): then nothing is proven.
template <class S>
bool encloseSystem(std::vector<MidRadEvaluator<S>>& evaluators, std::span<const S> centre,
                   std::span<const S> radius, std::span<const S> level,
                   std::span<const int> columns, std::vector<Interval<S>>& jacobian,
                   std::vector<Interval<S>>& fy, bool& excluded, bool stopWhenExcluded);

extern template std::vector<MidRadEvaluator<double>>& threadEvaluators(const System<double>&);
extern template std::vector<MidRadEvaluator<Mpfr>>& threadEvaluators(const System<Mpfr>&);
extern template Interval<double> enclosingInterval(const double&, const double&);
extern template Interval<Mpfr> enclosingInterval(const Mpfr&, const Mpfr&);
extern template bool encloseSystem(std::vector<MidRadEvaluator<double>>&, std::span<const double>,
                                   std::span<const double>, std::span<const double>,
                                   std::span<const int>, std::vector<Interval<double>>&,
                                   std::vector<Interval<double>>&, bool&, bool);
extern template bool encloseSystem(std::vector<MidRadEvaluator<Mpfr>>&, std::span<const Mpfr>,
                                   std::span<const Mpfr>, std::span<const Mpfr>,
                                   std::span<const int>, std::vector<Interval<Mpfr>>&,
                                   std::vector<Interval<Mpfr>>&, bool&, bool);

}  // namespace ndc::crossing_detail
