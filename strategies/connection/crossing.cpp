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

/// Which ends of a face's free axes lie on the domain boundary. There the face has no
/// neighbour to share a crossing with, so it is closed, and it keeps crossings up to `slack`
/// outside (the perturbed level set F = c leaves the domain by that much where M touches it).
struct FaceEnds {
  std::vector<bool> lower, upper;
};

/// Finds the crossings of the level set F = c with one m-face: the roots of the m constraints
/// minus the level c (docs/crossing.md, "General position"), restricted to the face, a square
/// system in the face's m free variables. For m = 1 the level is 0 and the sign rule decides.
template <class S>
class FaceSolver {
 public:
  FaceSolver(const System<S>& system, int maxDepth, std::vector<S> level, S slack)
      : system_(system),
        n_(system.n()),
        m_(system.m()),
        maxDepth_(maxDepth),
        level_(std::move(level)),
        slack_(std::move(slack)) {
    f_.resize(m_);
    jacobian_.resize(std::size_t(m_) * n_);
  }

  /// Solves on the face whose fixed coordinates are given in `point` (free ones are
  /// overwritten); `patches` are the face slices of F (m variables, domain = the face box),
  /// shifted here by the level; `ends` marks the free axes' domain ends. Appends the roots
  /// (full n-dim points) to `roots`; returns false if some root could not be proven unique.
  bool solve(std::vector<S> point, std::vector<int> freeAxes, std::vector<Bernstein<S>>& patches,
             FaceEnds ends, std::vector<std::vector<S>>& roots) {
    point_ = std::move(point);
    free_ = std::move(freeAxes);
    certain_ = true;
    boxes_ = 0;
    if (m_ == 1) {
      edge(patches.front().domain(), roots);
      return true;
    }
    for (int i = 0; i < m_; ++i) {
      for (S& c : patches[i].coefficients()) c -= level_[i];
    }
    recurse(patches, ends, 0, roots);
    return certain_;
  }

 private:
  void recurse(const std::vector<Bernstein<S>>& patches, const FaceEnds& ends, int depth,
               std::vector<std::vector<S>>& roots) {
    //! [crossing-face]
    // Exclusion: a coefficient hull of one sign on the face means no root.
    const Box<S>& box = patches.front().domain();
    for (const auto& p : patches) {
      if (p.excludesZero()) return;
    }
    std::vector<S> root;
    const bool found = newton(box, root) && inside(box, ends, root);
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
      // Newton failed, but K inside int X proves one root strictly inside this box (so inside
      // the half-open face): keep it, at the box centre (a fold of F = c, where the face
      // Jacobian is nearly singular, can stall Newton's convergence test).
      for (int j = 0; j < m_; ++j) y[j] = (box.lo[j] + box.hi[j]) / 2;
      roots.push_back(fullPoint(y));
      return;
    }
    // Undecided at the smallest face size, or after the face's budget of boxes (where F = c
    // has a continuum of roots on the face, as on a degenerate surface patch, the recursion
    // would otherwise visit up to 2^(maxDepth m) boxes): keep Newton's root, flag the face
    // uncertain.
    if (depth >= maxDepth_ * m_ || ++boxes_ > kMaxBoxes) {
      certain_ = false;
      if (found) roots.push_back(fullPoint(root));
      return;
    }
    // Subdivide the face along its free axes in turn (half-open children).
    const int axis = depth % m_;
    std::vector<Bernstein<S>> lower(patches.size()), upper(patches.size());
    for (std::size_t i = 0; i < patches.size(); ++i) patches[i].halve(axis, lower[i], upper[i]);
    FaceEnds lowerEnds = ends, upperEnds = ends;
    lowerEnds.upper[axis] = false;
    upperEnds.lower[axis] = false;
    recurse(lower, lowerEnds, depth + 1, roots);
    recurse(upper, upperEnds, depth + 1, roots);
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

  /// Half-open `[lo, hi)` inside the grid, closed and widened by the slack at domain ends.
  bool inside(const Box<S>& box, const FaceEnds& ends, const std::vector<S>& y) const {
    for (int j = 0; j < m_; ++j) {
      if (ends.lower[j] ? y[j] < box.lo[j] - slack_ : y[j] < box.lo[j]) return false;
      if (ends.upper[j] ? y[j] > box.hi[j] + slack_ : y[j] >= box.hi[j]) return false;
    }
    return true;
  }

  /// Square Newton on the face from its centre, damped (the step is halved until the residual
  /// drops, and the iterate stays within two face widths), so that it also converges near a
  /// fold of M where the face Jacobian is nearly singular; true if it converged.
  bool newton(const Box<S>& box, std::vector<S>& y) {
    using std::abs;
    using std::sqrt;
    y.resize(m_);
    S width = 0;
    for (int j = 0; j < m_; ++j) {
      y[j] = (box.lo[j] + box.hi[j]) / 2;
      width = std::max<S>(width, box.hi[j] - box.lo[j]);
    }
    const S eps = ScalarTraits<S>::epsilon();
    Matrix<S> jf(m_, m_);
    Vector<S> rhs(m_);
    std::vector<S> x = point_, trial(m_);
    // max_i |F_i - c_i| at the free coordinates `at`; the Jacobian columns into jf.
    const auto residual = [&](const std::vector<S>& at) {
      for (int j = 0; j < m_; ++j) x[free_[j]] = at[j];
      system_.evaluate(x, f_, jacobian_);
      S r = 0;
      for (int i = 0; i < m_; ++i) {
        rhs(i) = f_[i] - level_[i];
        r = std::max<S>(r, abs(rhs(i)));
      }
      return r;
    };
    S r = residual(y);
    for (int iteration = 0; iteration < 60; ++iteration) {
      if (r == 0) return true;
      for (int i = 0; i < m_; ++i) {
        for (int j = 0; j < m_; ++j) jf(i, j) = jacobian_[std::size_t(i) * n_ + free_[j]];
      }
      Eigen::FullPivLU<Matrix<S>> lu(jf);
      if (lu.rank() < m_) return false;
      const Vector<S> step = lu.solve(rhs);
      S size = 0, scale = 1;
      for (int j = 0; j < m_; ++j) {
        size = std::max<S>(size, abs(step(j)));
        scale = std::max<S>(scale, abs(y[j]));
      }
      if (size <= 64 * eps * scale) return true;
      // Where the face Jacobian is nearly singular the steps stall above 64 eps: stop when the
      // residual is at rounding level.
      if (size <= 1e-3 * width && residualWithinRounding(y)) return true;
      // Damping: halve the step until it stays near the face and lowers the residual.
      S lambda = 1;
      bool accepted = false;
      for (int halving = 0; halving < 30 && !accepted; ++halving, lambda /= 2) {
        bool near = true;
        for (int j = 0; j < m_; ++j) {
          trial[j] = y[j] - lambda * step(j);
          near = near && trial[j] >= box.lo[j] - 2 * width && trial[j] <= box.hi[j] + 2 * width;
        }
        if (!near) continue;
        const S rt = residual(trial);
        // Near the root the residual is at rounding level: accept the full step there.
        if (rt < r || (halving == 0 && size <= 1e-6 * width)) {
          y = trial;
          r = rt;
          accepted = true;
        }
      }
      // No step lowers the residual: converged iff it is at rounding level (the interval value
      // of F - c at y contains 0), as happens where the face Jacobian is nearly singular.
      if (!accepted) return residualWithinRounding(y);
      if (lambda * 2 * size <= 64 * eps * scale) return true;
    }
    return false;
  }

  /// Whether F - c on the free coordinates y, widened by rounding, encloses 0 in outward-rounded
  /// interval arithmetic.
  bool residualWithinRounding(const std::vector<S>& y) const {
    using I = Interval<S>;
    std::vector<I> xi;
    xi.reserve(n_);
    for (int j = 0; j < n_; ++j) xi.emplace_back(point_[j]);
    // The free coordinates widened by two units in the last place: the root itself need not
    // be representable (F - c is then never exactly 0 at a floating-point y).
    const S ulp = 2 * ScalarTraits<S>::epsilon();
    for (int j = 0; j < m_; ++j) {
      using std::abs;
      xi[free_[j]] = I(y[j] - ulp * abs(y[j]), y[j] + ulp * abs(y[j]));
    }
    for (int i = 0; i < m_; ++i) {
      const I f =
          system_.equations()[i].template evaluate<S>(std::span<const I>(xi)) - I(level_[i]);
      // Twice the enclosure's width: the evaluation order of F differs from the tape's.
      const S slack = f.upper() - f.lower();
      if (f.lower() - slack > 0 || f.upper() + slack < 0) return false;
    }
    return true;
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
      fy.push_back(system_.equations()[i].template evaluate<S>(std::span<const I>(xi)) -
                   I(level_[i]));
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
  std::vector<S> level_;  ///< c: the crossings are those of F = c
  S slack_;               ///< how far outside the domain a crossing is still kept
  std::vector<S> point_;
  std::vector<int> free_;
  std::vector<S> f_, jacobian_;
  std::vector<Interval<S>> jx_;
  bool certain_ = true;
  /// Boxes of the current face subdivided so far, and the most one face may take: an isolated
  /// root needs about 2 maxDepth m boxes, a fold a few times that.
  long boxes_ = 0;
  static constexpr long kMaxBoxes = 4096;
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

/// The local degree of F on a face from its roots: the sum of the signs of the face Jacobian's
/// determinant (columns of the free axes). A piece of M that dips through the face and back
/// gives two roots of opposite sign that cancel; two strands crossing the face the same way (a
/// self-intersection) add up and keep the curve connected. The count is odd exactly when the
/// number of roots is odd, so closedness mod 2 is kept. Near a singular point, where the
/// orientation of M is undefined and two strands may cross one face with opposite signs, every
/// root counts, rather than cut M.
template <class S>
int faceDegree(const System<S>& system, const std::vector<std::vector<S>>& roots,
               const std::vector<int>& freeAxes) {
  const int m = system.m();
  int degree = 0;
  bool singular = false;
  for (const auto& r : roots) {
    const Matrix<S> full = jacobianAt<S>(system, r);
    Matrix<S> j(m, m);
    for (int col = 0; col < m; ++col) j.col(col) = full.col(freeAxes[col]);
    const S det = Eigen::FullPivLU<Matrix<S>>(j).determinant();
    degree += det > 0 ? 1 : (det < 0 ? -1 : 0);
    const Vector<S> sigma = Eigen::JacobiSVD<Matrix<S>>(full).singularValues();
    singular = singular || sigma(m - 1) < sigma(0) / 10;
  }
  const int count = static_cast<int>(roots.size());
  if (count % 2 == 1 && degree == 0) degree = 1;  // a root of unknown orientation
  if (count >= 2 && std::abs(degree) < count && singular) degree = count;
  return degree;
}

/// A dual k-cell: the 2^k cells around a crossed m-face, in cyclic order (k = 2).
struct DualCell {
  std::array<std::int32_t, 4> cells{-1, -1, -1, -1};
  std::int32_t root = -1;  ///< first root of its face, in the root list
};

/// The level c of the perturbed system F = c whose crossings with the grid faces decide the
/// dual cells (docs/crossing.md, "General position"). M itself may pass through vertices,
/// edges and faces of the grid; by Sard's theorem almost every nearby level set meets every
/// face of the grid transversally and misses its lower-dimensional faces. c_i is a fixed
/// irrational fraction of `kRelative` times the cell width times the gradient scale of F_i,
/// so F = c lies about 1e-8 cell widths from M: far above rounding, far below any feature
/// the grid resolves. The grid, the domain and the B-spline knot planes stay where they are.
template <class S>
struct GeneralPosition {
  static constexpr int kAttempts = 4;
  static constexpr double kRelative = 1.0 / (1 << 26);

  GeneralPosition(const ConnectionInput<S>& in, const Grid& grid) {
    using std::abs;
    using std::sqrt;
    const int n = grid.n, m = in.system.m();
    S width = S(grid.cellWidth(0));
    for (int j = 1; j < n; ++j) width = std::min<S>(width, S(grid.cellWidth(j)));
    // Gradient scale of each F_i: the median gradient norm at (a sample of) the projected cell
    // points that Newton brought onto M. Points where it failed can lie far off M, with
    // gradients orders of magnitude larger (interval bounding keeps many such cells).
    const std::size_t count = in.cells.size();
    std::vector<std::size_t> onM;
    for (std::size_t c = 0; c < count; ++c) {
      if (in.projections.converged[c]) onM.push_back(c);
    }
    if (onM.empty()) {
      for (std::size_t c = 0; c < count; ++c) onM.push_back(c);
    }
    const std::size_t stride = std::max<std::size_t>(1, onM.size() / 256);
    std::vector<std::vector<S>> norms(m);
    std::vector<S> f(m), jacobian(std::size_t(m) * n);
    for (std::size_t t = 0; t < onM.size(); t += stride) {
      in.system.evaluate(in.projections.at(onM[t]), f, jacobian);
      for (int i = 0; i < m; ++i) {
        S norm = 0;
        for (int j = 0; j < n; ++j)
          norm += jacobian[std::size_t(i) * n + j] * jacobian[std::size_t(i) * n + j];
        norms[i].push_back(sqrt(norm));
      }
    }
    scale.assign(m, S(0));
    for (int i = 0; i < m; ++i) {
      auto middle = norms[i].begin() + norms[i].size() / 2;
      std::nth_element(norms[i].begin(), middle, norms[i].end());
      if (middle != norms[i].end()) scale[i] = *middle;
    }
    for (S& g : scale) {
      if (!(g > 0)) g = 1;
      g *= width * S(kRelative);
    }
    slack = 64 * width * S(kRelative);
    tolerance = width * S(kRelative) / 64;
  }

  /// The level of attempt a: c_i = theta_{a,i} * scale_i with theta in [0.5, 1) from the
  /// golden-ratio sequence (no two attempts or equations share a ratio).
  std::vector<S> level(int attempt) const {
    std::vector<S> c(scale.size());
    for (std::size_t i = 0; i < scale.size(); ++i) {
      const double t = std::fmod(0.6180339887498949 * double(attempt * 7 + i + 1), 1.0);
      c[i] = S(0.5 + 0.5 * t) * scale[i];
    }
    return c;
  }

  /// How many of a face's roots lie within the tolerance of one of its grid (not domain)
  /// boundaries: there the face and its neighbour could disagree about the root.
  std::int64_t nearBoundary(const std::vector<std::vector<S>>& roots, const Box<S>& box,
                            const std::vector<int>& freeAxes, const FaceEnds& ends) const {
    using std::abs;
    std::int64_t near = 0;
    for (const auto& r : roots) {
      for (std::size_t t = 0; t < freeAxes.size(); ++t) {
        const int j = freeAxes[t];
        if ((!ends.lower[t] && abs(r[j] - box.lo[j]) < tolerance) ||
            (!ends.upper[t] && abs(box.hi[j] - r[j]) < tolerance)) {
          ++near;
          break;
        }
      }
    }
    return near;
  }

  std::vector<S> scale;  ///< kRelative * cell width * gradient scale, per equation
  S slack;               ///< crossings kept this far outside the domain
  S tolerance;           ///< a root this close to a face boundary is degenerate
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

  std::vector<std::uint8_t> uncertain;
  std::vector<DualCell> duals;
  std::vector<S> rootPoints;  // n per recorded dual cell: the crossing it stands for
  // The cells the dual complex is built on: the solution cells, and the cells that the level
  // set F = c enters where M only touches them (added when a crossed face needs them).
  SolutionCells set;
  std::vector<Bernstein<S>> cellPatches(m), facePatches(m);
  std::vector<std::vector<S>> roots;
  std::vector<std::int32_t> index(n);
  const std::int64_t top = grid.cellsPerAxis();
  const GeneralPosition<S> position(in, grid);
  // The k-subsets of the axes: the fixed axes of the m-faces.
  std::vector<std::array<int, 2>> fixedAxes;
  for (int a = 0; a < n; ++a) {
    if (k == 1) fixedAxes.push_back({a, -1});
    for (int b = a + 1; k == 2 && b < n; ++b) fixedAxes.push_back({a, b});
  }

  // One pass over the faces for the level set F = c; returns the crossings that lie within
  // rounding of their face's boundary (0: c puts M in general position for this grid).
  const auto crossFaces = [&](const std::vector<S>& level) -> std::int64_t {
    std::int64_t degenerate = 0;
    set = cells;
    uncertain.assign(set.size(), 0);
    duals.clear();
    rootPoints.clear();
    FaceSolver<S> solver(in.system, maxFaceDepth, level, position.slack);
    std::vector<std::int32_t> corner(n);
    std::array<CellKey, 4> around{};
    std::array<std::int32_t, 4> aroundCell{};
    FaceEnds ends;
    std::vector<int> freeAxes;
    // Every m-face of every cell, once (the set grows while it is walked).
    for (std::size_t c = 0; c < set.size(); ++c) {
      const std::vector<std::int32_t> ci(set.cell(c).begin(), set.cell(c).end());
      const Box<S> box = cellBox(grid, domain, ci);
      bool restricted = false;
      for (const auto& axes : fixedAxes) {
        for (int side = 0; side < (1 << k); ++side) {
          // The face's lowest vertex; faces on the domain boundary have no cells beyond.
          std::copy(ci.begin(), ci.end(), corner.begin());
          bool interior = true;
          for (int t = 0; t < k; ++t) {
            corner[axes[t]] += (side >> t) & 1;
            interior = interior && corner[axes[t]] > 0 && corner[axes[t]] < top;
          }
          if (!interior) continue;
          // The 2^k cells around the face, in cyclic order (k = 2): (-a,-b), (+a,-b), (+a,+b),
          // (-a,+b). The face belongs to the first of them in the walk: skip it if another
          // one came earlier (it was solved there).
          bool owner = true;
          for (int q = 0; q < (1 << k) && owner; ++q) {
            const int bits = k == 1 ? q : (q == 0 ? 0 : q == 1 ? 1 : q == 2 ? 3 : 2);
            std::copy(corner.begin(), corner.end(), index.begin());
            for (int t = 0; t < k; ++t) index[axes[t]] += ((bits >> t) & 1) - 1;
            around[q] = grid.pack(index);
            const auto it = set.lookup.find(around[q]);
            aroundCell[q] = it == set.lookup.end() ? -1 : it->second;
            owner = aroundCell[q] < 0 || aroundCell[q] >= static_cast<std::int32_t>(c);
          }
          if (!owner) continue;
          if (!restricted) {
            const std::vector<Bernstein<S>>& rootPatches = formsFor(ci);
            for (int i = 0; i < m; ++i) cellPatches[i] = rootPatches[i].restrict(box);
            restricted = true;
          }
          ends.lower.clear();
          ends.upper.clear();
          freeAxes.clear();
          std::vector<S> point(box.lo);
          for (int j = 0; j < n; ++j) {
            if (j == axes[0] || j == axes[1]) continue;
            freeAxes.push_back(j);
            ends.lower.push_back(ci[j] == 0);
            ends.upper.push_back(ci[j] + 1 == top);
          }
          // Slice the highest fixed axis first so the lower axis numbers stay valid.
          for (int i = 0; i < m; ++i) {
            facePatches[i] = cellPatches[i];
            for (int t = k - 1; t >= 0; --t) {
              const bool upper = (side >> t) & 1;
              facePatches[i] = facePatches[i].faceSlice(axes[t], upper);
              point[axes[t]] = upper ? box.hi[axes[t]] : box.lo[axes[t]];
            }
          }
          roots.clear();
          const bool certain = solver.solve(point, freeAxes, facePatches, ends, roots);
          if (m > 1) degenerate += position.nearBoundary(roots, box, freeAxes, ends);
          if (roots.empty()) continue;
          const int degree = faceDegree(in.system, roots, freeAxes);
          if (degree == 0) continue;
          // A cell around a crossed face that M only touches is added.
          DualCell dual;
          for (int q = 0; q < (1 << k); ++q) {
            if (aroundCell[q] < 0) {
              aroundCell[q] = static_cast<std::int32_t>(set.size());
              set.lookup.emplace(around[q], aroundCell[q]);
              grid.unpack(around[q], index);
              set.index.insert(set.index.end(), index.begin(), index.end());
              uncertain.push_back(0);
            }
            dual.cells[q] = aroundCell[q];
          }
          if (!certain || std::abs(degree) > 1) {
            for (int q = 0; q < (1 << k); ++q) uncertain[dual.cells[q]] = 1;
          }
          for (int copy = 0; copy < std::abs(degree); ++copy) {
            dual.root = static_cast<std::int32_t>(rootPoints.size() / n);
            rootPoints.insert(rootPoints.end(), roots.front().begin(), roots.front().end());
            duals.push_back(dual);
          }
        }
      }
    }
    return degenerate;
  };

  // General position: try levels until no crossing is within rounding of a face boundary.
  ConnectionOutput<S> out;
  out.complex.n = n;
  out.complex.k = k;
  for (int attempt = 0;; ++attempt) {
    const std::vector<S> level = position.level(attempt);
    const std::int64_t degenerate = crossFaces(level);
    out.perturbation.attempts = attempt + 1;
    out.perturbation.degenerateCrossings = degenerate;
    out.perturbation.level.clear();
    if (m > 1) {
      for (const S& c : level) out.perturbation.level.push_back(toDouble(c));
    }
    if (degenerate == 0 || m == 1 || attempt + 1 == GeneralPosition<S>::kAttempts) break;
  }
  const std::size_t count = set.size();

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
    const auto ci = set.cell(c);
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
      if (!in.project(x).converged) {
        // Reported, never written silently off M (the analysis measures its residual too).
        x = mean;
        ++out.offManifoldVertices;
      }
      const std::int32_t v = out.complex.addVertex(
          x, c < cells.size() ? static_cast<std::int32_t>(c) : std::int32_t{-1});
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
