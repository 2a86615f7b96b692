// Betti numbers of a pure simplicial complex (homology.hpp).
//
// Notation: a d-cell is a d-face of the complex, its vertices sorted; its i-th facet omits its
// i-th vertex and has the sign (-1)^i in the boundary, so the boundary matrices need no
// orientation of the input. S is the set of cells still alive; the boundary of a cell in S is
// its boundary restricted to S (an S-complex: d∂ = 0 stays true under the removals below).
//
// 1. The lattice: the cells of each dimension numbered in lexicographic order, each cell with
//    its facets, each with its cofaces.
// 2. One vertex of each component is removed: each is a class of H_0 of its own.
// 3. Reductions (a cell with one coface in S, removed with it) and coreductions (a cell with one
//    facet in S, removed with it) until none is left; neither changes the homology of S, over
//    any coefficients (the coefficient of the pair is +-1).
// 4. The boundary matrices of what is left, reduced column by column from dimension k down,
//    with a pivot table (the column whose lowest row is r) and clearing: a (d-1)-cell that is a
//    pivot row of the d-th matrix is the lowest cell of a cycle, so its own column in the
//    (d-1)-th matrix reduces to zero and is skipped. b_d = |S_d| - rank d_d - rank d_{d+1}.
// The only place where the field matters is step 4, run once over Z/2 and once over Z/p.
#include "framework/mesh/homology.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstdint>
#include <functional>
#include <numeric>
#include <span>
#include <utility>
#include <vector>

#include "framework/numeric/parallel.hpp"
#include "framework/util/disjoint_sets.hpp"

namespace ndc {

std::int64_t Homology::eulerCharacteristic() const {
  std::int64_t chi = 0;
  for (std::size_t d = 0; d < faces.size(); ++d) chi += d % 2 == 0 ? faces[d] : -faces[d];
  return chi;
}

namespace {

/// Every face of the complex by dimension; d-cells are numbered 0 .. count[d] - 1 in the
/// lexicographic order of their vertices (0-cells: the vertex numbers).
struct Lattice {
  int k = 0;
  std::vector<std::int64_t> count;  ///< cells per dimension 0 .. k
  /// facets[d], d >= 1: per d-cell its d + 1 facets, the i-th omitting its i-th vertex.
  std::vector<std::vector<std::int32_t>> facets;
  /// coStart[d], cofaces[d], d < k: the (d+1)-cells on each d-cell (compressed rows).
  std::vector<std::vector<std::int64_t>> coStart;
  std::vector<std::vector<std::int32_t>> cofaces;

  std::span<const std::int32_t> facetsOf(int d, std::int64_t c) const {
    return {facets[d].data() + c * (d + 1), static_cast<std::size_t>(d + 1)};
  }
  std::span<const std::int32_t> cofacesOf(int d, std::int64_t c) const {
    if (d >= k) return {};
    return {cofaces[d].data() + coStart[d][c],
            static_cast<std::size_t>(coStart[d][c + 1] - coStart[d][c])};
  }
};

/// Sorts (key, record) pairs, records in ascending order, by their keys below 2^keyBits: a
/// least-significant-digit radix sort, stable, so equal keys keep their records' order (the
/// order of a comparison sort of the pairs, in a few passes over the data).
void radixSort(std::vector<std::pair<std::uint64_t, std::uint32_t>>& items, int keyBits) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kDigits = std::size_t{1} << kDigitBits;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> scratch(items.size());
  for (int shift = 0; shift < keyBits; shift += kDigitBits) {
    // Count each digit, then place every item after the items of smaller digits.
    std::vector<std::size_t> at(kDigits + 1, 0);
    for (const auto& item : items) ++at[((item.first >> shift) & (kDigits - 1)) + 1];
    std::partial_sum(at.begin(), at.end(), at.begin());
    for (const auto& item : items) scratch[at[(item.first >> shift) & (kDigits - 1)]++] = item;
    items.swap(scratch);
  }
}

/// Numbers the tuples of `flat` (`width` vertex numbers each, each below 2^bits) by their
/// distinct values in lexicographic order into id (one per tuple); returns the distinct tuples.
std::vector<std::int32_t> numberTuples(const std::vector<std::int32_t>& flat, int width, int bits,
                                       std::vector<std::int32_t>& id) {
  const std::size_t w = static_cast<std::size_t>(width), count = flat.size() / w;
  const auto tuple = [&](std::size_t r) { return flat.begin() + std::ptrdiff_t(r * w); };
  std::vector<std::uint32_t> order(count);
  if (width * bits <= 64) {
    // Packed keys (first vertex in the high bits: their order is the lexicographic one).
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(count);
    parallelFor(
        count,
        [&](std::size_t r) {
          std::uint64_t key = 0;
          for (std::size_t i = 0; i < w; ++i)
            key = (key << bits) | static_cast<std::uint32_t>(flat[r * w + i]);
          keyed[r] = {key, static_cast<std::uint32_t>(r)};
        },
        4096);
    radixSort(keyed, width * bits);
    for (std::size_t r = 0; r < count; ++r) order[r] = keyed[r].second;
  } else {
    std::iota(order.begin(), order.end(), std::uint32_t{0});
    // Ties broken by the tuple's number: parallelSort needs a strict total order.
    parallelSort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      const auto [x, y] = std::mismatch(tuple(a), tuple(a) + width, tuple(b));
      return x == tuple(a) + width ? a < b : *x < *y;
    });
  }
  // A new number wherever the sorted tuple changes.
  id.assign(count, 0);
  std::vector<std::int32_t> distinct;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t r = order[i];
    if (i == 0 || !std::equal(tuple(r), tuple(r) + width, tuple(order[i - 1])))
      distinct.insert(distinct.end(), tuple(r), tuple(r) + width);
    id[r] = static_cast<std::int32_t>(distinct.size() / w - 1);
  }
  return distinct;
}

/// The facets of the d-cells `cells` (d + 1 vertices each): their numbers into facets, and the
/// (d-1)-cells (d vertices each) returned.
std::vector<std::int32_t> facetsOfCells(const std::vector<std::int32_t>& cells, int d, int bits,
                                        std::vector<std::int32_t>& facets) {
  const std::size_t w = static_cast<std::size_t>(d + 1), count = cells.size() / w;
  if (d == 1) {
    // Facet 0 of an edge [a, b] is b, facet 1 is a.
    facets.resize(cells.size());
    for (std::size_t c = 0; c < count; ++c)
      facets[2 * c] = cells[2 * c + 1], facets[2 * c + 1] = cells[2 * c];
    return {};
  }
  std::vector<std::int32_t> sub(count * w * (w - 1));
  parallelFor(
      count,
      [&](std::size_t c) {
        auto out = sub.begin() + std::ptrdiff_t(c * w * (w - 1));
        for (std::size_t i = 0; i < w; ++i)
          for (std::size_t j = 0; j < w; ++j)
            if (j != i) *out++ = cells[c * w + j];
      },
      4096);
  return numberTuples(sub, d, bits, facets);
}

/// Step 1: the lattice of the complex.
Lattice buildLattice(std::size_t vertexCount, int k, std::span<const std::int32_t> simplices) {
  Lattice l;
  l.k = k;
  l.count.assign(std::size_t(k + 1), 0);
  l.facets.resize(std::size_t(k + 1));
  l.count[0] = static_cast<std::int64_t>(vertexCount);
  const int bits = std::max(1, int(std::bit_width(vertexCount > 0 ? vertexCount - 1 : 0)));
  if (k >= 1) {
    // The k-cells: each simplex sorted, those with a repeated vertex left out, repeats merged.
    const std::size_t w = std::size_t(k + 1);
    std::vector<std::int32_t> flat;
    flat.reserve(simplices.size());
    for (std::size_t s = 0; s + w <= simplices.size(); s += w) {
      const std::size_t at = flat.size();
      flat.insert(flat.end(), simplices.begin() + std::ptrdiff_t(s),
                  simplices.begin() + std::ptrdiff_t(s + w));
      std::sort(flat.begin() + std::ptrdiff_t(at), flat.end());
      if (std::adjacent_find(flat.begin() + std::ptrdiff_t(at), flat.end()) != flat.end())
        flat.resize(at);
    }
    std::vector<std::int32_t> id;
    std::vector<std::int32_t> cells = numberTuples(flat, k + 1, bits, id);
    // Each dimension's facets, from the top down.
    for (int d = k; d >= 1; --d) {
      l.count[d] = static_cast<std::int64_t>(cells.size() / std::size_t(d + 1));
      cells = facetsOfCells(cells, d, bits, l.facets[d]);
    }
  }
  // The cofaces, inverted from the facets.
  l.coStart.resize(std::size_t(std::max(k, 0)));
  l.cofaces.resize(std::size_t(std::max(k, 0)));
  for (int d = 0; d < k; ++d) {
    auto& start = l.coStart[d];
    start.assign(std::size_t(l.count[d] + 1), 0);
    for (std::int32_t f : l.facets[d + 1]) ++start[f + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    l.cofaces[d].resize(l.facets[d + 1].size());
    std::vector<std::int64_t> next(start.begin(), start.end() - 1);
    for (std::int64_t c = 0; c < l.count[d + 1]; ++c)
      for (std::int32_t f : l.facetsOf(d + 1, c)) l.cofaces[d][next[f]++] = std::int32_t(c);
  }
  return l;
}

/// The cells left by steps 2 and 3, and the vertices removed in step 2 (one per component).
struct Remainder {
  std::vector<std::vector<std::uint8_t>> alive;  ///< per dimension, per cell
  std::int64_t components = 0;
};

/// Steps 2 and 3: removes one vertex per component, then reduction and coreduction pairs.
class Shrink {
 public:
  explicit Shrink(const Lattice& l) : l_(l), k_(l.k) {
    // Every cell alive, with all its facets and cofaces.
    r_.alive.resize(std::size_t(k_ + 1));
    facetsLeft_.resize(std::size_t(k_ + 1));
    cofacesLeft_.resize(std::size_t(k_ + 1));
    for (int d = 0; d <= k_; ++d) {
      r_.alive[d].assign(std::size_t(l.count[d]), 1);
      facetsLeft_[d].assign(std::size_t(l.count[d]), std::uint8_t(d == 0 ? 0 : d + 1));
      cofacesLeft_[d].resize(std::size_t(l.count[d]));
      for (std::int64_t c = 0; c < l.count[d]; ++c)
        cofacesLeft_[d][c] = static_cast<std::int32_t>(l.cofacesOf(d, c).size());
    }
  }

  Remainder run() {
    removeComponents();
    // Free faces from the start (the boundary of a complex with boundary).
    for (int d = 0; d < k_; ++d)
      for (std::int64_t c = 0; c < l_.count[d]; ++c)
        if (cofacesLeft_[d][c] == 1) push(d, c);
    // Step 3, first in first out: a coreduction grows from the removed vertices as a tree.
    for (std::size_t head = 0; head < queue_.size(); ++head) {
      const int d = int(queue_[head] >> 32);
      const auto x = static_cast<std::int64_t>(queue_[head] & 0xffffffffULL);
      if (!r_.alive[d][x]) continue;
      if (d >= 1 && facetsLeft_[d][x] == 1)
        coreduce(d, x);
      else if (d < k_ && cofacesLeft_[d][x] == 1)
        reduce(d, x);
    }
    return std::move(r_);
  }

 private:
  void push(int d, std::int64_t c) { queue_.push_back(std::uint64_t(d) << 32 | std::uint64_t(c)); }

  /// Step 2: one vertex per component (the smallest), a class of H_0 of its own.
  void removeComponents() {
    DisjointSets sets(std::size_t(l_.count[0]));
    for (std::int64_t e = 0; k_ >= 1 && e < l_.count[1]; ++e)
      sets.unite(l_.facets[1][2 * e], l_.facets[1][2 * e + 1]);
    for (std::int64_t v = 0; v < l_.count[0]; ++v) {
      if (sets.find(std::int32_t(v)) != v) continue;
      r_.alive[0][v] = 0;
      ++r_.components;
      for (std::int32_t e : l_.cofacesOf(0, v))
        if (--facetsLeft_[1][e] == 1) push(1, e);
    }
  }

  /// Coreduction (a, x): a is x's only facet left; a has no facet left (dd = 0 on S), so only
  /// the cofaces of both lose a facet.
  void coreduce(int d, std::int64_t x) {
    std::int32_t a = -1;
    for (std::int32_t f : l_.facetsOf(d, x))
      if (r_.alive[d - 1][f]) a = f;
    assert(d == 1 || facetsLeft_[d - 1][a] == 0);
    r_.alive[d][x] = r_.alive[d - 1][a] = 0;
    for (std::int32_t y : l_.cofacesOf(d, x))
      if (r_.alive[d + 1][y] && --facetsLeft_[d + 1][y] == 1) push(d + 1, y);
    for (std::int32_t y : l_.cofacesOf(d - 1, a))
      if (r_.alive[d][y] && --facetsLeft_[d][y] == 1) push(d, y);
  }

  /// Reduction (x, b): b is x's only coface left; b has no coface left (dd = 0 on S), so only
  /// the facets of both lose a coface.
  void reduce(int d, std::int64_t x) {
    std::int32_t b = -1;
    for (std::int32_t y : l_.cofacesOf(d, x))
      if (r_.alive[d + 1][y]) b = y;
    r_.alive[d][x] = r_.alive[d + 1][b] = 0;
    for (std::int32_t f : l_.facetsOf(d + 1, b))
      if (r_.alive[d][f] && --cofacesLeft_[d][f] == 1) push(d, f);
    if (d == 0) return;
    for (std::int32_t f : l_.facetsOf(d, x))
      if (r_.alive[d - 1][f] && --cofacesLeft_[d - 1][f] == 1) push(d - 1, f);
  }

  const Lattice& l_;
  const int k_;
  Remainder r_;
  std::vector<std::vector<std::uint8_t>> facetsLeft_;   ///< alive facets per cell
  std::vector<std::vector<std::int32_t>> cofacesLeft_;  ///< alive cofaces per cell
  std::vector<std::uint64_t> queue_;                    ///< (dimension, cell) to look at
};

/// Arithmetic modulo the prime P (2, or kHomologyPrime).
template <std::uint32_t P>
struct Mod {
  static std::uint32_t mul(std::uint32_t a, std::uint32_t b) {
    return static_cast<std::uint32_t>(std::uint64_t(a) * b % P);
  }
  static std::uint32_t neg(std::uint32_t a) { return a == 0 ? 0 : P - a; }
  static std::uint32_t inverse(std::uint32_t a) {
    // Fermat: a^(P-2).
    std::uint32_t result = 1;
    for (std::uint64_t e = P - 2; e > 0; e >>= 1, a = mul(a, a))
      if (e & 1) result = mul(result, a);
    return result;
  }
};

/// A nonzero entry of a sparse column.
struct Entry {
  std::int32_t row;
  std::uint32_t coef;
};
using Column = std::vector<Entry>;

/// column += factor * other (both sorted by row), dropping zeros, into scratch then swapped.
template <std::uint32_t P>
void addTo(Column& column, const Column& other, std::uint32_t factor, Column& scratch) {
  scratch.clear();
  std::size_t i = 0, j = 0;
  while (i < column.size() || j < other.size()) {
    if (j == other.size() || (i < column.size() && column[i].row < other[j].row)) {
      scratch.push_back(column[i++]);
    } else if (i == column.size() || other[j].row < column[i].row) {
      scratch.push_back({other[j].row, Mod<P>::mul(factor, other[j].coef)});
      ++j;
    } else {
      const std::uint32_t sum = (column[i].coef + Mod<P>::mul(factor, other[j].coef)) % P;
      if (sum != 0) scratch.push_back({column[i].row, sum});
      ++i, ++j;
    }
  }
  column.swap(scratch);
}

/// Step 4 over Z/P: the rank of each boundary matrix d_d (d = 0 .. k + 1) of the cells left.
template <std::uint32_t P>
std::vector<std::int64_t> ranks(const Lattice& l, const Remainder& r) {
  const int k = l.k;
  std::vector<std::int64_t> rank(std::size_t(k + 2), 0);
  std::vector<std::uint8_t> cleared;  // d-cells that were pivot rows of d_{d+1}
  Column column, scratch;
  for (int d = k; d >= 1; --d) {
    // The pivot table of d_d: per (d-1)-cell, the reduced column whose lowest row it is.
    std::vector<std::int32_t> pivotOf(std::size_t(l.count[d - 1]), -1);
    std::vector<Column> reduced;
    std::vector<std::uint8_t> pivotRows(std::size_t(l.count[d - 1]), 0);
    for (std::int64_t c = 0; c < l.count[d]; ++c) {
      if (!r.alive[d][c] || (!cleared.empty() && cleared[c])) continue;
      // The column of c: its facets left, with signs (-1)^i, sorted by row.
      column.clear();
      const auto facets = l.facetsOf(d, c);
      for (std::size_t i = 0; i < facets.size(); ++i)
        if (r.alive[d - 1][facets[i]])
          column.push_back({facets[i], i % 2 == 0 ? 1u % P : Mod<P>::neg(1)});
      std::sort(column.begin(), column.end(),
                [](const Entry& a, const Entry& b) { return a.row < b.row; });
      // Reduce: cancel the lowest entry against the pivot column of its row while there is one.
      while (!column.empty() && pivotOf[column.back().row] >= 0) {
        const Column& pivot = reduced[std::size_t(pivotOf[column.back().row])];
        addTo<P>(column, pivot, Mod<P>::neg(column.back().coef), scratch);
      }
      if (column.empty()) continue;
      // A new pivot, normalised to a lowest coefficient of 1.
      const std::uint32_t scale = Mod<P>::inverse(column.back().coef);
      for (Entry& e : column) e.coef = Mod<P>::mul(e.coef, scale);
      pivotOf[column.back().row] = static_cast<std::int32_t>(reduced.size());
      pivotRows[column.back().row] = 1;
      reduced.push_back(column);
      ++rank[d];
    }
    cleared.swap(pivotRows);
  }
  return rank;
}

/// The Betti numbers from the ranks of the cells left and the components.
std::vector<std::int64_t> bettiOf(const Lattice& l, const Remainder& r,
                                  const std::vector<std::int64_t>& rank) {
  std::vector<std::int64_t> betti(std::size_t(l.k + 1));
  for (int d = 0; d <= l.k; ++d) {
    const auto left = std::count(r.alive[d].begin(), r.alive[d].end(), std::uint8_t{1});
    betti[d] = left - rank[d] - rank[d + 1];
  }
  betti[0] += r.components;
  return betti;
}

}  // namespace

Homology homology(std::size_t vertexCount, int k, std::span<const std::int32_t> simplices) {
  Homology h;
  if (k < 0) return h;
  const Lattice l = buildLattice(vertexCount, k, simplices);
  h.faces = l.count;
  // Facets of one and of three or more k-simplices.
  for (std::int64_t c = 0; k >= 1 && c < l.count[k - 1]; ++c) {
    const std::size_t on = l.cofacesOf(k - 1, c).size();
    if (on == 1) ++h.boundaryFacets;
    if (on >= 3) ++h.nonmanifoldFacets;
  }
  const Remainder r = Shrink(l).run();
  h.bettiZ2 = bettiOf(l, r, ranks<2>(l, r));
  h.betti = bettiOf(l, r, ranks<kHomologyPrime>(l, r));
  // Euler-Poincare: the alternating sums of the Betti numbers and of the face counts agree.
  [[maybe_unused]] const auto alternating = [](const std::vector<std::int64_t>& b) {
    std::int64_t sum = 0;
    for (std::size_t d = 0; d < b.size(); ++d) sum += d % 2 == 0 ? b[d] : -b[d];
    return sum;
  };
  assert(alternating(h.betti) == h.eulerCharacteristic());
  assert(alternating(h.bettiZ2) == h.eulerCharacteristic());
  return h;
}

}  // namespace ndc
