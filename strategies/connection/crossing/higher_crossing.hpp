/// \file higher_crossing.hpp
/// The crossing connection for manifolds of dimension k >= 3 (docs/crossing.md, "Any k"): the
/// crossings of M_c with every minimal m-face of the uniform grid at `--depth`, the dual k-cube
/// of each crossed face split into k-simplices by Kuhn's rule, and the certificate of every
/// cell: its crossings proven, the graph test on every face of dimension above m, and the
/// crossings on every such face forming a sphere (kuhn.hpp). No adaptive refinement: a cell that
/// fails is reported, and a finer `--depth` is the remedy. Internal to the crossing connection.
#pragma once

#include "framework/numeric/scalar.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc::crossing_detail {

/// The mesh and certificate of a run with k >= 3 (n > k), faces halved at most `maxFaceDepth`
/// times per free axis.
template <class S>
ConnectionOutput<S> higherCrossing(const ConnectionInput<S>& in, int maxFaceDepth);

extern template ConnectionOutput<double> higherCrossing(const ConnectionInput<double>&, int);
extern template ConnectionOutput<Mpfr> higherCrossing(const ConnectionInput<Mpfr>&, int);

}  // namespace ndc::crossing_detail
