#include "strategies/connection/crossing.hpp"

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "bernstein.hpp"
#include "interval.hpp"

namespace ndc {
namespace {

template <class S>
using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// Outcome of the Krawczyk test on a face box.
enum class Krawczyk { kUnique, kNone, kUnknown };

/// Finds the crossings of M with one m-face: the roots of the m constraints restricted to the
/// face, a square system in the face's m free variables.
template <class S>
class FaceSolver {
 public:
  FaceSolver(const System<S>& system, int maxDepth)
      : system_(system), n_(system.n()), m_(system.m()), maxDepth_(maxDepth) {
    f_.resize(m_);
    jacobian_.resize(std::size_t(m_) * n_);
  }

  /// Solves on the face whose fixed coordinates are given in `point` (free ones are
  /// overwritten); `patches` are the face slices (m variables, domain = the face box);
  /// `closedUpper[j]` closes the face at the upper end of free axis j (the domain's end).
  /// Appends the roots (full n-dim points) to `roots`; returns false if some root could not
  /// be proven unique.
  bool solve(std::vector<S> point, std::vector<int> freeAxes,
             const std::vector<Bernstein<S>>& patches, std::vector<bool> closedUpper,
             std::vector<std::vector<S>>& roots) {
    point_ = std::move(point);
    free_ = std::move(freeAxes);
    certain_ = true;
    recurse(patches, closedUpper, 0, roots);
    return certain_;
  }

 private:
  void recurse(const std::vector<Bernstein<S>>& patches, const std::vector<bool>& closedUpper,
               int depth, std::vector<std::vector<S>>& roots) {
    // Exclusion: a coefficient hull of one sign on the face means no root.
    for (const auto& p : patches) {
      if (p.excludesZero()) return;
    }
    const Box<S>& box = patches.front().domain();
    std::vector<S> root;
    const bool found = newton(box, root) && inside(box, closedUpper, root);
    const Krawczyk k = krawczyk(patches);
    if (k == Krawczyk::kNone) return;
    if (found && (k == Krawczyk::kUnique || krawczykAround(root, box) == Krawczyk::kUnique)) {
      roots.push_back(fullPoint(root));
      return;
    }
    if (k == Krawczyk::kUnique && !found) {
      // The unique root lies in the closed face; if Newton did not reach it inside the
      // half-open face, it is on an upper boundary owned by the next face, or Newton strayed.
      std::vector<S> y;
      if (newton(box, y) && insideClosed(box, y)) return;  // owned by the neighbour face
    }
    if (depth >= maxDepth_ * m_) {
      // Undecided at the smallest face size: keep Newton's root, flag the face uncertain.
      certain_ = false;
      if (found) roots.push_back(fullPoint(root));
      return;
    }
    // Subdivide the face along its free axes in turn (half-open children).
    const int axis = depth % m_;
    std::vector<Bernstein<S>> lower(patches.size()), upper(patches.size());
    for (std::size_t i = 0; i < patches.size(); ++i) patches[i].halve(axis, lower[i], upper[i]);
    std::vector<bool> closedLower = closedUpper;
    closedLower[axis] = false;
    recurse(lower, closedLower, depth + 1, roots);
    recurse(upper, closedUpper, depth + 1, roots);
  }

  std::vector<S> fullPoint(const std::vector<S>& y) const {
    std::vector<S> x = point_;
    for (int j = 0; j < m_; ++j) x[free_[j]] = y[j];
    return x;
  }

  bool insideClosed(const Box<S>& box, const std::vector<S>& y) const {
    for (int j = 0; j < m_; ++j) {
      if (y[j] < box.lo[j] || y[j] > box.hi[j]) return false;
    }
    return true;
  }

  bool inside(const Box<S>& box, const std::vector<bool>& closedUpper,
              const std::vector<S>& y) const {
    for (int j = 0; j < m_; ++j) {
      if (y[j] < box.lo[j]) return false;
      if (closedUpper[j] ? y[j] > box.hi[j] : y[j] >= box.hi[j]) return false;
    }
    return true;
  }

  /// Square Newton on the face from its centre; true if it converged.
  bool newton(const Box<S>& box, std::vector<S>& y) {
    using std::abs;
    y.resize(m_);
    S width = 0;
    for (int j = 0; j < m_; ++j) {
      y[j] = (box.lo[j] + box.hi[j]) / 2;
      width = std::max<S>(width, box.hi[j] - box.lo[j]);
    }
    const S eps = ScalarTraits<S>::epsilon();
    Matrix<S> jf(m_, m_);
    Vector<S> rhs(m_);
    std::vector<S> x = point_;
    for (int iteration = 0; iteration < 40; ++iteration) {
      for (int j = 0; j < m_; ++j) x[free_[j]] = y[j];
      system_.evaluate(x, f_, jacobian_);
      bool zero = true;
      for (int i = 0; i < m_; ++i) {
        rhs(i) = f_[i];
        zero = zero && f_[i] == 0;
        for (int j = 0; j < m_; ++j) jf(i, j) = jacobian_[std::size_t(i) * n_ + free_[j]];
      }
      if (zero) return true;
      Eigen::FullPivLU<Matrix<S>> lu(jf);
      if (lu.rank() < m_) return false;
      const Vector<S> step = lu.solve(rhs);
      S size = 0, scale = 1;
      for (int j = 0; j < m_; ++j) {
        y[j] -= step(j);
        size = std::max<S>(size, abs(step(j)));
        scale = std::max<S>(scale, abs(y[j]));
        // A root far outside the face is not this face's root.
        if (y[j] < box.lo[j] - 2 * width || y[j] > box.hi[j] + 2 * width) return false;
      }
      if (size <= 64 * eps * scale) return true;
    }
    return false;
  }

  /// Krawczyk operator on the face box X with y = mid X, Y = J(y)^-1:
  /// K = y - Y F(y) + (I - Y J(X)) (X - y). K inside int X proves one root in X;
  /// K disjoint from X proves none. J(X) comes from the Bernstein derivative hulls.
  Krawczyk krawczyk(const std::vector<Bernstein<S>>& patches) {
    // J(X) from the hulls of the derivative patches of the face.
    const Box<S>& box = patches.front().domain();
    jx_.resize(std::size_t(m_) * m_);
    for (int i = 0; i < m_; ++i) {
      for (int j = 0; j < m_; ++j) {
        const auto [lo, hi] = patches[i].derivative(j).coefficientRange();
        jx_[std::size_t(i) * m_ + j] = Interval<S>(lo, hi);
      }
    }
    return krawczyk(box);
  }

  /// Krawczyk on the box `root +- width` around a Newton root, with J(X) from the interval
  /// gradient; it contains the whole current face when `width` is the face's width, so
  /// kUnique proves the root is the face's only one even when it lies near the face boundary.
  Krawczyk krawczykAround(const std::vector<S>& root, const Box<S>& face) {
    using I = Interval<S>;
    Box<S> box{root, root};
    for (int j = 0; j < m_; ++j) {
      const S w = face.hi[j] - face.lo[j];
      box.lo[j] -= w;
      box.hi[j] += w;
    }
    std::vector<I> x;
    x.reserve(n_);
    for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
    for (int j = 0; j < m_; ++j) x[free_[j]] = I(box.lo[j], box.hi[j]);
    std::vector<I> gradient(n_);
    jx_.resize(std::size_t(m_) * m_);
    for (int i = 0; i < m_; ++i) {
      system_.equations()[i].template evaluate<S>(std::span<const I>(x), std::span<I>(gradient));
      for (int j = 0; j < m_; ++j) jx_[std::size_t(i) * m_ + j] = gradient[free_[j]];
    }
    return krawczyk(box);
  }

  /// Krawczyk operator on the box X with y = mid X, Y = J(y)^-1 and J(X) enclosed by jx_:
  /// K = y - Y F(y) + (I - Y J(X)) (X - y). K inside int X proves one root in X;
  /// K disjoint from X proves none.
  Krawczyk krawczyk(const Box<S>& box) {
    using I = Interval<S>;
    std::vector<S> y(m_);
    for (int j = 0; j < m_; ++j) y[j] = (box.lo[j] + box.hi[j]) / 2;
    std::vector<S> x = point_;
    for (int j = 0; j < m_; ++j) x[free_[j]] = y[j];
    system_.evaluate(x, f_, jacobian_);
    Matrix<S> jy(m_, m_);
    for (int i = 0; i < m_; ++i) {
      for (int j = 0; j < m_; ++j) jy(i, j) = jacobian_[std::size_t(i) * n_ + free_[j]];
    }
    Eigen::FullPivLU<Matrix<S>> lu(jy);
    if (lu.rank() < m_) return Krawczyk::kUnknown;
    const Matrix<S> inverse = lu.inverse();
    // F(y) by interval evaluation at the point, so its rounding is enclosed.
    std::vector<I> xi;
    xi.reserve(n_);
    for (int j = 0; j < n_; ++j) xi.emplace_back(x[j]);
    std::vector<I> fy;
    for (int i = 0; i < m_; ++i) {
      fy.push_back(system_.equations()[i].template evaluate<S>(std::span<const I>(xi)));
    }
    bool unique = true;
    for (int i = 0; i < m_; ++i) {
      I k(y[i]);
      for (int l = 0; l < m_; ++l) k -= I(inverse(i, l)) * fy[l];
      for (int j = 0; j < m_; ++j) {
        I c(S(i == j ? 1 : 0));
        for (int l = 0; l < m_; ++l) c -= I(inverse(i, l)) * jx_[std::size_t(l) * m_ + j];
        k += c * I(box.lo[j] - y[j], box.hi[j] - y[j]);
      }
      if (k.upper() < box.lo[i] || k.lower() > box.hi[i]) return Krawczyk::kNone;
      if (!(k.lower() > box.lo[i] && k.upper() < box.hi[i])) unique = false;
    }
    return unique ? Krawczyk::kUnique : Krawczyk::kUnknown;
  }

  const System<S>& system_;
  int n_, m_, maxDepth_;
  std::vector<S> point_;
  std::vector<int> free_;
  std::vector<S> f_, jacobian_;
  std::vector<Interval<S>> jx_;
  bool certain_ = true;
};

/// A dual k-cell: the 2^k cells around a crossed m-face, in cyclic order (k = 2).
struct DualCell {
  std::array<std::int32_t, 4> cells{-1, -1, -1, -1};
};

}  // namespace

template <class S>
ConnectionOutput<S> CrossingConnection::connect(const ConnectionInput<S>& in) const {
  using std::abs;
  using std::sqrt;
  const SolutionCells& cells = in.cells;
  const Grid& grid = cells.grid;
  const int n = grid.n, k = in.k, m = n - k;
  if (k != 1 && k != 2) {
    throw InputError("connection 'crossing' supports k = 1 and k = 2, not k = " +
                     std::to_string(k));
  }
  Box<S> domain;
  for (int j = 0; j < n; ++j) {
    domain.lo.push_back(S(grid.domain.lo[j]));
    domain.hi.push_back(S(grid.domain.hi[j]));
  }
  std::vector<Bernstein<S>> rootPatches;
  for (const auto& e : in.system.equations())
    rootPatches.push_back(e.template toBernstein<S>(domain));

  const std::size_t count = cells.size();
  std::vector<S> crossingSum(count * n, S(0));
  std::vector<std::int32_t> crossingCount(count, 0);
  std::vector<std::uint8_t> uncertain(count, 0);
  std::vector<DualCell> duals;
  FaceSolver<S> solver(in.system, maxFaceDepth);
  std::vector<Bernstein<S>> cellPatches(m), facePatches(m);
  std::vector<std::vector<S>> roots;
  std::vector<std::int32_t> index(n);
  const std::int64_t top = grid.cellsPerAxis();

  // The m-faces at each cell's lower corner: every interior m-face exactly once.
  for (std::size_t c = 0; c < count; ++c) {
    const auto ci = cells.cell(c);
    const Box<S> box = cellBox(grid, domain, ci);
    bool restricted = false;
    const auto neighbourAt = [&](std::initializer_list<int> axes) -> std::int32_t {
      std::copy(ci.begin(), ci.end(), index.begin());
      for (int a : axes) --index[a];
      auto it = cells.lookup.find(grid.pack(index));
      return it == cells.lookup.end() ? -1 : it->second;
    };
    const auto solveFace = [&](std::initializer_list<int> fixed) {
      if (!restricted) {
        for (int i = 0; i < m; ++i) cellPatches[i] = rootPatches[i].restrict(box);
        restricted = true;
      }
      std::vector<int> freeAxes;
      std::vector<bool> closedUpper;
      for (int j = 0; j < n; ++j) {
        if (std::find(fixed.begin(), fixed.end(), j) != fixed.end()) continue;
        freeAxes.push_back(j);
        closedUpper.push_back(ci[j] + 1 == top);
      }
      // Slice the highest fixed axis first so the lower axis numbers stay valid.
      std::vector<int> order(fixed);
      std::sort(order.rbegin(), order.rend());
      for (int i = 0; i < m; ++i) {
        facePatches[i] = cellPatches[i];
        for (int a : order) facePatches[i] = facePatches[i].faceSlice(a, false);
      }
      std::vector<S> point(box.lo);
      roots.clear();
      return solver.solve(point, freeAxes, facePatches, closedUpper, roots);
    };
    const auto record = [&](const DualCell& dual, int members) {
      for (const auto& r : roots) {
        for (int i = 0; i < members; ++i) {
          const std::int32_t cell = dual.cells[i];
          for (int j = 0; j < n; ++j) crossingSum[std::size_t(cell) * n + j] += r[j];
          ++crossingCount[cell];
        }
        duals.push_back(dual);
      }
    };
    if (k == 1) {
      for (int a = 0; a < n; ++a) {
        if (ci[a] == 0) continue;  // on the domain boundary
        const std::int32_t below = neighbourAt({a});
        if (below < 0) continue;  // a crossing would make it a solution cell
        DualCell dual;
        dual.cells = {below, static_cast<std::int32_t>(c), -1, -1};
        const bool certain = solveFace({a});
        if (!certain) uncertain[c] = uncertain[below] = 1;
        record(dual, 2);
      }
    } else {
      for (int a = 0; a < n; ++a) {
        for (int b = a + 1; b < n; ++b) {
          if (ci[a] == 0 || ci[b] == 0) continue;
          const std::int32_t q0 = neighbourAt({a, b}), q1 = neighbourAt({b}), q3 = neighbourAt({a});
          if (q0 < 0 || q1 < 0 || q3 < 0) continue;
          // Cyclic order around the face: (-a,-b), (+a,-b), (+a,+b), (-a,+b).
          DualCell dual;
          dual.cells = {q0, q1, static_cast<std::int32_t>(c), q3};
          const bool certain = solveFace({a, b});
          if (!certain) {
            for (auto q : dual.cells) uncertain[q] = 1;
          }
          record(dual, 4);
        }
      }
    }
  }

  // Dual vertices: the Newton projection of the mean of each cell's crossings.
  ConnectionOutput<S> out;
  out.complex.n = n;
  out.complex.k = k;
  std::vector<std::int32_t> vertexOf(count, -1);
  std::vector<S> x(n), f(m), jacobian(std::size_t(m) * n);
  for (std::size_t c = 0; c < count; ++c) {
    if (crossingCount[c] == 0) continue;
    for (int j = 0; j < n; ++j) x[j] = crossingSum[c * n + j] / crossingCount[c];
    std::vector<S> mean = x;
    if (!in.project(x).converged) x = mean;
    vertexOf[c] = out.complex.addVertex(x, static_cast<std::int32_t>(c));
    // Singular cells: the Jacobian at the vertex is (nearly) rank-deficient relative to the
    // cell size, as at self-intersections and cone points.
    in.system.evaluate(x, f, jacobian);
    Matrix<S> j(m, n);
    for (int r = 0; r < m; ++r) {
      for (int col = 0; col < n; ++col) j(r, col) = jacobian[std::size_t(r) * n + col];
    }
    Eigen::JacobiSVD<Matrix<S>> svd(j);
    const auto& sigma = svd.singularValues();
    const S widest = S(grid.cellWidth(0));
    if (uncertain[c] || sigma(m - 1) <= sigma(0) * widest * 1e-3 || sigma(0) == 0) {
      ++out.singularCells;
    }
  }

  // Dual k-cells.
  std::vector<std::vector<std::int32_t>> quadsOf(k == 2 ? count : 0);
  for (const DualCell& dual : duals) {
    if (k == 1) {
      const std::array<std::int32_t, 2> e{vertexOf[dual.cells[0]], vertexOf[dual.cells[1]]};
      out.complex.addSimplex(e);
      continue;
    }
    std::array<std::int32_t, 4> v;
    for (int i = 0; i < 4; ++i) v[i] = vertexOf[dual.cells[i]];
    const auto distance = [&](int p, int q) {
      S sum = 0;
      for (int j = 0; j < n; ++j) {
        const S d = out.complex.vertices[std::size_t(v[p]) * n + j] -
                    out.complex.vertices[std::size_t(v[q]) * n + j];
        sum += d * d;
      }
      return sum;
    };
    // Split the quad along its shorter diagonal.
    if (distance(0, 2) <= distance(1, 3)) {
      out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[1], v[2]});
      out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[2], v[3]});
    } else {
      out.complex.addSimplex(std::array<std::int32_t, 3>{v[0], v[1], v[3]});
      out.complex.addSimplex(std::array<std::int32_t, 3>{v[1], v[2], v[3]});
    }
    for (int i = 0; i < 4; ++i)
      quadsOf[dual.cells[i]].push_back(static_cast<std::int32_t>(&dual - duals.data()));
  }

  // Ambiguous cells: the crossings do not form one simple piece. A cell on the domain
  // boundary may hold a piece of M that leaves the domain: an arc with one crossing (k = 1)
  // or a half-disk whose link is a path (k = 2).
  const auto onDomainBoundary = [&](std::size_t c) {
    const auto ci = cells.cell(c);
    return std::any_of(ci.begin(), ci.end(),
                       [&](std::int32_t i) { return i == 0 || i + 1 == top; });
  };
  for (std::size_t c = 0; c < count; ++c) {
    if (crossingCount[c] == 0) continue;
    const bool boundary = onDomainBoundary(c);
    if (k == 1) {
      if (crossingCount[c] != 2 && !(boundary && crossingCount[c] == 1)) ++out.ambiguousCells;
      continue;
    }
    // k = 2: the link of the vertex has one edge per quad, between the quad's two cells that
    // are face neighbours of c; one disk of M means the link is one cycle (or one path).
    std::unordered_map<std::int32_t, std::vector<std::int32_t>> link;
    for (std::int32_t q : quadsOf[c]) {
      const auto& cs = duals[q].cells;
      int at = 0;
      while (cs[at] != static_cast<std::int32_t>(c)) ++at;
      const std::int32_t p = cs[(at + 1) % 4], r = cs[(at + 3) % 4];
      link[p].push_back(r);
      link[r].push_back(p);
    }
    std::size_t ends = 0;
    bool simple = !link.empty();
    for (const auto& [node, adjacent] : link) {
      if (adjacent.size() == 1) ++ends;
      simple = simple && adjacent.size() <= 2;
    }
    simple = simple && (ends == 0 || (boundary && ends == 2));
    if (simple) {
      // Connected: a search from one node reaches them all.
      std::vector<std::int32_t> stack{link.begin()->first};
      std::unordered_map<std::int32_t, bool> seen{{link.begin()->first, true}};
      while (!stack.empty()) {
        const std::int32_t node = stack.back();
        stack.pop_back();
        for (std::int32_t next : link[node]) {
          if (seen.emplace(next, true).second) stack.push_back(next);
        }
      }
      simple = seen.size() == link.size();
    }
    if (!simple) ++out.ambiguousCells;
  }
  return out;
}

template ConnectionOutput<double> CrossingConnection::connect(const ConnectionInput<double>&) const;
template ConnectionOutput<Mpfr> CrossingConnection::connect(const ConnectionInput<Mpfr>&) const;

}  // namespace ndc
