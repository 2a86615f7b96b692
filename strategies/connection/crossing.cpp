#include "strategies/connection/crossing.hpp"

#include <Eigen/Dense>
#include <boost/multiprecision/eigen.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
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
    if (m_ == 1) {
      edge(patches.front().domain(), roots);
      return true;
    }
    recurse(patches, closedUpper, 0, roots);
    return certain_;
  }

 private:
  void recurse(const std::vector<Bernstein<S>>& patches, const std::vector<bool>& closedUpper,
               int depth, std::vector<std::vector<S>>& roots) {
    //! [crossing-face]
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
    //! [crossing-face]
  }

  /// m = 1 (hypersurfaces, k = n - 1): the face is a grid edge, and the parity of its roots is
  /// the sign change of F between its ends (sign 0 counts as +), exactly as in 3-D dual
  /// contouring. The grid vertices are shared by all their edges, so the result is closed
  /// whatever the roots inside do. An odd edge gets one crossing, found by safeguarded Newton.
  void edge(const Box<S>& box, std::vector<std::vector<S>>& roots) {
    using std::abs;
    std::vector<S> x = point_;
    const auto value = [&](const S& t) {
      x[free_[0]] = t;
      system_.evaluate(x, f_, jacobian_);
      return f_[0];
    };
    S a = box.lo[0], b = box.hi[0];
    const S fa = value(a), fb = value(b);
    const bool negativeA = fa < 0, negativeB = fb < 0;
    if (negativeA == negativeB) return;
    // Keep a bracket [a, b] with the sign change; Newton steps that leave it are bisections.
    S t = (a + b) / 2;
    const S eps = ScalarTraits<S>::epsilon();
    for (int iteration = 0; iteration < 200; ++iteration) {
      const S ft = value(t);
      if (ft == 0) break;
      if ((ft < 0) == negativeA) {
        a = t;
      } else {
        b = t;
      }
      const S slope = jacobian_[free_[0]];
      S next = slope != 0 ? t - ft / slope : (a + b) / 2;
      if (!(next > a && next < b)) next = (a + b) / 2;
      const S step = abs(next - t);
      t = next;
      if (step <= 4 * eps * (1 + abs(t)) || b - a <= 4 * eps * (1 + abs(t))) break;
    }
    x[free_[0]] = t;
    roots.push_back(x);
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

/// The m x n Jacobian of the system at x.
template <class S>
Matrix<S> jacobianAt(const System<S>& system, std::span<const S> x) {
  const int m = system.m(), n = system.n();
  std::vector<S> f(m), j(std::size_t(m) * n);
  system.evaluate(x, f, j);
  Matrix<S> out(m, n);
  for (int r = 0; r < m; ++r) {
    for (int c = 0; c < n; ++c) out(r, c) = j[std::size_t(r) * n + c];
  }
  return out;
}

/// Singular values of the Jacobian at x, largest first.
template <class S>
Vector<S> singularValuesAt(const System<S>& system, std::span<const S> x) {
  return Eigen::JacobiSVD<Matrix<S>>(jacobianAt(system, x)).singularValues();
}

/// A dual k-cell: the 2^k cells around a crossed m-face, in cyclic order (k = 2).
struct DualCell {
  std::array<std::int32_t, 4> cells{-1, -1, -1, -1};
  std::int32_t root = -1;  ///< first root of its face, in the root list
};

/// Union-find over small integer sets (the link of one vertex).
struct UnionFind {
  std::vector<int> parent;
  int find(int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
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
  // The Bernstein forms each cell's are restricted from: of the domain, or (B-spline input) of
  // the patch holding the cell, built when first needed.
  const Problem& problem = in.problem;
  std::map<CellKey, std::vector<Bernstein<S>>> patchForms;
  std::vector<std::int32_t> patchIndex(n);
  const auto formsFor = [&](std::span<const std::int32_t> ci) -> const std::vector<Bernstein<S>>& {
    const int below = grid.depth - problem.rootLevel;
    CellKey key = 0;
    for (int j = 0; j < n; ++j) {
      patchIndex[j] = ci[j] >> below;
      key = key * (CellKey{1} << problem.rootLevel) + static_cast<CellKey>(patchIndex[j]);
    }
    auto it = patchForms.find(key);
    if (it != patchForms.end()) return it->second;
    Box<S> patch;
    const S cells = S(static_cast<double>(std::int64_t{1} << problem.rootLevel));
    for (int j = 0; j < n; ++j) {
      const S w = (domain.hi[j] - domain.lo[j]) / cells;
      patch.lo.push_back(domain.lo[j] + w * S(static_cast<double>(patchIndex[j])));
      patch.hi.push_back(domain.lo[j] + w * S(static_cast<double>(patchIndex[j] + 1)));
    }
    std::vector<Bernstein<S>> forms;
    for (const auto& e : in.system.equations())
      forms.push_back(e.template toBernstein<S>(problem.roots.empty() ? domain : patch));
    return patchForms.emplace(key, std::move(forms)).first->second;
  };

  const std::size_t count = cells.size();
  std::vector<std::uint8_t> uncertain(count, 0);
  std::vector<DualCell> duals;
  std::vector<S> rootPoints;  // n per recorded dual cell: the crossing it stands for
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
    std::vector<int> faceFree;  // the free axes of the face being solved
    // Sign of the determinant of the face Jacobian (columns of the free axes) at a root.
    const auto orientation = [&](const std::vector<S>& r) {
      const Matrix<S> full = jacobianAt<S>(in.system, r);
      Matrix<S> j(m, m);
      for (int col = 0; col < m; ++col) j.col(col) = full.col(faceFree[col]);
      const S det = Eigen::FullPivLU<Matrix<S>>(j).determinant();
      return det > 0 ? 1 : (det < 0 ? -1 : 0);
    };
    // Whether the full Jacobian at a root is nearly rank-deficient (sigma_min < 0.1 sigma_max).
    const auto nearSingular = [&](const std::vector<S>& r) {
      const Vector<S> sigma = singularValuesAt<S>(in.system, r);
      return sigma(m - 1) < sigma(0) / 10;
    };
    const auto solveFace = [&](std::initializer_list<int> fixed) {
      if (!restricted) {
        const std::vector<Bernstein<S>>& rootPatches = formsFor(ci);
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
      faceFree = freeAxes;
      std::vector<S> point(box.lo);
      roots.clear();
      return solver.solve(point, freeAxes, facePatches, closedUpper, roots);
    };
    const auto record = [&](const DualCell& dual) {
      // The dual complex counts roots with orientation (the sign of the face Jacobian's
      // determinant, i.e. the local degree): a piece of M that dips through the face and back
      // gives two roots of opposite sign that cancel, while two strands crossing the face the
      // same way (a self-intersection) add up and keep the curve connected. The count is
      // odd exactly when the number of roots is odd, so closedness mod 2 is kept.
      int degree = 0;
      for (const auto& r : roots) degree += orientation(r);
      if (roots.size() % 2 == 1 && degree == 0) degree = 1;  // a root of unknown orientation
      // Near a singular point (self-intersection) the orientation of M is undefined and two
      // strands may cross one face with opposite signs: keep them all rather than cut M.
      if (roots.size() >= 2 && std::abs(degree) < static_cast<int>(roots.size()) &&
          std::any_of(roots.begin(), roots.end(), nearSingular)) {
        degree = static_cast<int>(roots.size());
        for (int i = 0; i < (k == 1 ? 2 : 4); ++i) uncertain[dual.cells[i]] = 1;
      }
      for (int copy = 0; copy < std::abs(degree); ++copy) {
        DualCell d = dual;
        d.root = static_cast<std::int32_t>(rootPoints.size() / n);
        rootPoints.insert(rootPoints.end(), roots.front().begin(), roots.front().end());
        duals.push_back(d);
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
        record(dual);
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
          record(dual);
        }
      }
    }
  }

  ConnectionOutput<S> out;
  out.complex.n = n;
  out.complex.k = k;

  // Pieces of M per cell: for k = 2 the link of a cell's vertex (one edge per incident quad,
  // between the quad's two cells that are face neighbours of the cell) splits into connected
  // components, one per sheet of M in the cell; each gets its own dual vertex, so two sheets
  // in one cell do not make a non-manifold vertex. For k = 1 a cell has one piece.
  std::vector<std::vector<std::int32_t>> incident(count);  // dual cells at each cell
  for (std::size_t d = 0; d < duals.size(); ++d) {
    for (int i = 0; i < (k == 1 ? 2 : 4); ++i)
      incident[duals[d].cells[i]].push_back(std::int32_t(d));
  }
  // piece[d * 4 + i]: the piece of cell duals[d].cells[i] that dual cell d belongs to.
  std::vector<std::int32_t> piece(duals.size() * 4, 0);
  std::vector<std::int32_t> pieceCount(count, 0);
  const auto onDomainBoundary = [&](std::size_t c) {
    const auto ci = cells.cell(c);
    return std::any_of(ci.begin(), ci.end(),
                       [&](std::int32_t i) { return i == 0 || i + 1 == top; });
  };
  const auto slotOf = [&](std::int32_t d, std::size_t c) {
    int at = 0;
    while (duals[d].cells[at] != static_cast<std::int32_t>(c)) ++at;
    return at;
  };
  for (std::size_t c = 0; c < count; ++c) {
    const auto& ds = incident[c];
    if (ds.empty()) continue;
    const bool boundary = onDomainBoundary(c);
    if (k == 1) {
      pieceCount[c] = 1;
      for (std::int32_t d : ds) piece[d * 4 + slotOf(d, c)] = 0;
      const auto degree = ds.size();
      if (degree != 2 && !(boundary && degree == 1)) ++out.ambiguousCells;
      continue;
    }
    // Link nodes: the neighbour cells; link edges: the quads.
    std::vector<std::int32_t> nodes;
    std::vector<std::array<int, 2>> edges;
    for (std::int32_t d : ds) {
      const int at = slotOf(d, c);
      std::array<int, 2> e{};
      for (int side = 0; side < 2; ++side) {
        const std::int32_t cell = duals[d].cells[(at + (side ? 3 : 1)) % 4];
        auto it = std::find(nodes.begin(), nodes.end(), cell);
        e[side] = static_cast<int>(it - nodes.begin());
        if (it == nodes.end()) nodes.push_back(cell);
      }
      edges.push_back(e);
    }
    UnionFind uf{std::vector<int>(nodes.size())};
    for (std::size_t i = 0; i < nodes.size(); ++i) uf.parent[i] = static_cast<int>(i);
    for (const auto& e : edges) uf.unite(e[0], e[1]);
    std::vector<int> componentOf(nodes.size(), -1), degree(nodes.size(), 0);
    int components = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const int r = uf.find(static_cast<int>(i));
      if (componentOf[r] < 0) componentOf[r] = components++;
    }
    for (const auto& e : edges) ++degree[e[0]], ++degree[e[1]];
    for (std::size_t q = 0; q < ds.size(); ++q) {
      piece[ds[q] * 4 + slotOf(ds[q], c)] = componentOf[uf.find(edges[q][0])];
    }
    pieceCount[c] = components;
    // One simple piece: one component that is a cycle (or a path on the domain boundary).
    int ends = 0;
    bool simple = components == 1;
    for (int d : degree) {
      if (d == 1) ++ends;
      simple = simple && d <= 2;
    }
    simple = simple && (ends == 0 || (boundary && ends == 2));
    if (!simple) ++out.ambiguousCells;
  }

  // Dual vertices: the Newton projection of the mean of each piece's crossings.
  std::vector<std::int32_t> firstVertex(count, -1);
  std::vector<S> sums, x(n);
  std::vector<std::int32_t> counts;
  const S widest = S(grid.cellWidth(0));
  for (std::size_t c = 0; c < count; ++c) {
    if (pieceCount[c] == 0) continue;
    sums.assign(std::size_t(pieceCount[c]) * n, S(0));
    counts.assign(pieceCount[c], 0);
    for (std::int32_t d : incident[c]) {
      const std::int32_t p = piece[d * 4 + slotOf(d, c)];
      for (int j = 0; j < n; ++j)
        sums[std::size_t(p) * n + j] += rootPoints[std::size_t(duals[d].root) * n + j];
      ++counts[p];
    }
    for (int p = 0; p < pieceCount[c]; ++p) {
      for (int j = 0; j < n; ++j) x[j] = sums[std::size_t(p) * n + j] / counts[p];
      const std::vector<S> mean = x;
      if (!in.project(x).converged) x = mean;
      const std::int32_t v = out.complex.addVertex(x, static_cast<std::int32_t>(c));
      if (p == 0) firstVertex[c] = v;
      // Singular cells: the Jacobian at the vertex is (nearly) rank-deficient relative to the
      // cell size, as at self-intersections and cone points.
      const Vector<S> sigma = singularValuesAt<S>(in.system, x);
      if (p == 0 && (uncertain[c] || sigma(0) == 0 || sigma(m - 1) <= sigma(0) * widest * 1e-3)) {
        ++out.singularCells;
      }
    }
  }

  // Dual k-cells on the pieces' vertices.
  for (std::size_t d = 0; d < duals.size(); ++d) {
    const DualCell& dual = duals[d];
    std::array<std::int32_t, 4> v{};
    for (int i = 0; i < (k == 1 ? 2 : 4); ++i) v[i] = firstVertex[dual.cells[i]] + piece[d * 4 + i];
    if (k == 1) {
      out.complex.addSimplex(std::array<std::int32_t, 2>{v[0], v[1]});
      continue;
    }
    const auto distance = [&](int p, int q) {
      S sum = 0;
      for (int j = 0; j < n; ++j) {
        const S diff = out.complex.vertices[std::size_t(v[p]) * n + j] -
                       out.complex.vertices[std::size_t(v[q]) * n + j];
        sum += diff * diff;
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
  }
  return out;
}

template ConnectionOutput<double> CrossingConnection::connect(const ConnectionInput<double>&) const;
template ConnectionOutput<Mpfr> CrossingConnection::connect(const ConnectionInput<Mpfr>&) const;

}  // namespace ndc
