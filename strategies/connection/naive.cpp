// NaiveConnection: the paper's "thick volume" baseline (Sec. 4.1, Fig. 3(b)).
#include <array>

#include "strategies/connection/connection.hpp"
#include "strategies/connection/connection_detail.hpp"

namespace ndc {

ModelSpec NaiveConnection::spec() {
  return {"naive",
          "The thick-volume baseline (Sec. 4.1, Fig. 3(b)): every solution cell joined to its "
          "face neighbours, no classification.",
          {},
          {.certifies = false, .refines = false, .minK = 1, .maxK = 2}};
}

NaiveConnection NaiveConnection::create(const Parameters&) { return {}; }

template <class S>
ConnectionOutput<S> NaiveConnection::connect(const ConnectionInput<S>& input) const {
  using namespace connection_detail;
  requireBuildsK(spec(), input.k);
  const SolutionCells& cells = input.cells;
  ConnectionOutput<S> out;
  Complex<S>& complex = out.complex;
  complex.n = cells.grid.n;
  complex.k = input.k;

  // Every solution cell is a vertex: its projected point, or its centroid if Newton failed.
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const auto cell = static_cast<std::int32_t>(c);
    if (input.projections.converged[c]) {
      complex.addVertex(input.projections.at(c), cell);
    } else {
      const std::vector<S> centroid = cellCentroid<S>(cells, c);
      complex.addVertex(centroid, cell);
    }
  }

  if (input.k == 1) {
    // Every face-adjacent pair of solution cells is an edge (no classification).
    for (std::size_t c = 0; c < cells.size(); ++c) {
      for (int a = 0; a < cells.grid.n; ++a) {
        const std::int32_t d = cells.neighbour(c, a, +1);
        if (d < 0) continue;
        const std::array<std::int32_t, 2> e{static_cast<std::int32_t>(c), d};
        complex.addSimplex(e);
      }
    }
  } else {
    // Every plaquette of four solution cells is a quad, split along the shorter diagonal.
    forEachPlaquette(
        cells, [](std::int32_t) { return true; },
        [&](std::int32_t c0, std::int32_t c1, std::int32_t c2, std::int32_t c3) {
          splitQuad(complex, c0, c1, c2, c3, [&](std::int32_t a, std::int32_t b, std::int32_t c) {
            const std::array<std::int32_t, 3> t{a, b, c};
            complex.addSimplex(t);
          });
        });
  }
  return out;
}

template ConnectionOutput<double> NaiveConnection::connect(const ConnectionInput<double>&) const;
template ConnectionOutput<Mpfr> NaiveConnection::connect(const ConnectionInput<Mpfr>&) const;

}  // namespace ndc
