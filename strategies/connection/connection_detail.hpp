// Private helpers of the connection strategies (not part of the public surface).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/system.hpp"

namespace ndc::connection_detail {

/// Squared Euclidean distance of two points of R^n.
template <class S>
S distance2(std::span<const S> a, std::span<const S> b) {
  S sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const S d = a[i] - b[i];
    sum += d * d;
  }
  return sum;
}

template <class S>
S dot(std::span<const S> a, std::span<const S> b) {
  S sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += a[i] * b[i];
  return sum;
}

/// The centroid of the closed box of cell c (the naive vertex of a cell where Newton failed).
template <class S>
std::vector<S> cellCentroid(const SolutionCells& cells, std::size_t c) {
  const Grid& g = cells.grid;
  Box<S> domain{std::vector<S>(g.n), std::vector<S>(g.n)};
  for (int j = 0; j < g.n; ++j) {
    domain.lo[j] = S(g.domain.lo[j]);
    domain.hi[j] = S(g.domain.hi[j]);
  }
  const Box<S> box = cellBox<S>(g, domain, cells.cell(c));
  std::vector<S> x(g.n);
  for (int j = 0; j < g.n; ++j) x[j] = (box.lo[j] + box.hi[j]) / 2;
  return x;
}

/// Calls `quad(c0, c1, c2, c3)` for every plaquette `c, c+e_a, c+e_a+e_b, c+e_b` (a < b, in
/// cyclic order) of four solution cells accepted by `keep`; each plaquette once, from its
/// lowest corner.
template <class Keep, class Quad>
void forEachPlaquette(const SolutionCells& cells, Keep&& keep, Quad&& quad) {
  const int n = cells.grid.n;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!keep(static_cast<std::int32_t>(c))) continue;
    for (int a = 0; a < n; ++a) {
      const std::int32_t c1 = cells.neighbour(c, a, +1);
      if (c1 < 0 || !keep(c1)) continue;
      for (int b = a + 1; b < n; ++b) {
        const std::int32_t c3 = cells.neighbour(c, b, +1);
        if (c3 < 0 || !keep(c3)) continue;
        const std::int32_t c2 = cells.neighbour(static_cast<std::size_t>(c1), b, +1);
        if (c2 < 0 || !keep(c2)) continue;
        quad(static_cast<std::int32_t>(c), c1, c2, c3);
      }
    }
  }
}

/// Splits the quad v0 v1 v2 v3 (cyclic) into two triangles along its shorter diagonal.
template <class S, class Tri>
void splitQuad(const Complex<S>& complex, std::int32_t v0, std::int32_t v1, std::int32_t v2,
               std::int32_t v3, Tri&& triangle) {
  const S d02 = distance2<S>(complex.vertex(v0), complex.vertex(v2));
  const S d13 = distance2<S>(complex.vertex(v1), complex.vertex(v3));
  if (d02 <= d13) {
    triangle(v0, v1, v2);
    triangle(v0, v2, v3);
  } else {
    triangle(v0, v1, v3);
    triangle(v1, v2, v3);
  }
}

/// Key of the undirected edge {a, b}.
inline std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

/// The paper's tangent space at a point x of M (Sec. 4.1, the equation after Fig. 4):
/// phi_1..phi_r = Gram-Schmidt of the gradients of F_i (dependent ones dropped);
/// e^_i = e_i - sum_j (e_i . phi_j) phi_j; the k of largest magnitude that are independent,
/// Gram-Schmidt orthonormalised, are v_1..v_k (`basis`, k rows of n).
template <class S>
struct TangentSpace {
  std::vector<S> basis;   ///< k x n, orthonormal rows
  int rank = 0;           ///< rank of the gradients found by Gram-Schmidt
  bool singular = false;  ///< rank < m: the normal space is degenerate at x
};

template <class S>
TangentSpace<S> tangentSpace(const System<S>& system, std::span<const S> x, int k) {
  using std::sqrt;
  const int n = system.n(), m = system.m();
  std::vector<S> f(m), jac(static_cast<std::size_t>(m) * n);
  system.evaluate(x, f, jac);

  // Gram-Schmidt of the gradients G = {grad F_i} -> phi_1..phi_r.
  std::vector<S> phi;
  int rank = 0;
  for (int i = 0; i < m; ++i) {
    std::vector<S> g(jac.begin() + std::ptrdiff_t(i) * n, jac.begin() + std::ptrdiff_t(i + 1) * n);
    const S norm0 = sqrt(dot<S>(g, g));
    for (int j = 0; j < rank; ++j) {
      std::span<const S> p(phi.data() + std::size_t(j) * n, n);
      const S proj = dot<S>(g, p);
      for (int t = 0; t < n; ++t) g[t] -= proj * p[t];
    }
    const S norm = sqrt(dot<S>(g, g));
    if (!(norm > S(1e-10) * norm0) || norm0 == 0) continue;  // dependent gradient
    for (int t = 0; t < n; ++t) phi.push_back(g[t] / norm);
    ++rank;
  }

  // e^_i = e_i - sum_j phi_j[i] phi_j, ordered by magnitude |e^_i|^2 = 1 - sum_j phi_j[i]^2.
  std::vector<std::pair<double, int>> order;
  for (int i = 0; i < n; ++i) {
    S mag = 1;
    for (int j = 0; j < rank; ++j) mag -= phi[std::size_t(j) * n + i] * phi[std::size_t(j) * n + i];
    order.emplace_back(toDouble(mag), i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });

  TangentSpace<S> ts;
  ts.rank = rank;
  ts.singular = rank < m;
  for (const auto& [mag, i] : order) {
    if (static_cast<int>(ts.basis.size()) / n == k) break;
    std::vector<S> e(n, S(0));
    e[i] = 1;
    for (int j = 0; j < rank; ++j) {
      const S pj = phi[std::size_t(j) * n + i];
      for (int t = 0; t < n; ++t) e[t] -= pj * phi[std::size_t(j) * n + t];
    }
    // Independent of the v's already chosen: Gram-Schmidt, keep if something is left.
    const S norm0 = sqrt(dot<S>(e, e));
    const int have = static_cast<int>(ts.basis.size()) / n;
    for (int j = 0; j < have; ++j) {
      std::span<const S> v(ts.basis.data() + std::size_t(j) * n, n);
      const S proj = dot<S>(e, v);
      for (int t = 0; t < n; ++t) e[t] -= proj * v[t];
    }
    const S norm = sqrt(dot<S>(e, e));
    if (!(norm > S(1e-6) * norm0) || !(norm0 > S(1e-12))) continue;
    for (int t = 0; t < n; ++t) ts.basis.push_back(e[t] / norm);
  }
  return ts;
}

}  // namespace ndc::connection_detail
