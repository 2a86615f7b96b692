/// \file crossing_faces.cpp
/// The crossing connection, phase 1: the patches of F on a leaf, the level perturbation and the
/// crossings of F = c with the minimal m-faces of the tree (the face solver).
#include "strategies/connection/crossing_detail.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ndc::crossing_detail {
namespace {

/// Outcome of the Krawczyk test on a face box.
enum class Krawczyk { kUnique, kNone, kUnknown };

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
  /// `margins[i]`: coefficients of F_i smaller than this in magnitude may have the wrong sign
  /// (the rounding bound of the Bernstein forms, docs/certificate.md).
  bool solve(std::vector<S> point, std::vector<int> freeAxes, std::vector<Bernstein<S>>& patches,
             FaceEnds ends, std::vector<std::vector<S>>& roots, std::span<const S> margins) {
    point_ = std::move(point);
    free_ = std::move(freeAxes);
    margins_ = margins;
    certain_ = true;
    proven_ = true;
    withinRounding_ = false;
    boxes_ = 0;
    if (m_ == 1) {
      edge(patches.front().domain(), roots);
      proven_ = edgeProven(patches.front());
      return true;
    }
    for (int i = 0; i < m_; ++i) {
      for (S& c : patches[i].coefficients()) c -= level_[i];
    }
    recurse(patches, ends, 0, roots);
    return certain_;
  }

  /// Whether every decision of the last solve is a proof: exclusions by coefficient signs
  /// beyond the rounding margin or by interval evaluation, uniqueness and existence by the
  /// Krawczyk test in interval arithmetic, edge signs by interval values.
  bool proven() const { return proven_ && certain_; }
  /// Whether an exclusion of the last solve was left unproven because F comes within rounding
  /// of zero on the face (M touches it): no finer face can prove it either.
  bool withinRounding() const { return withinRounding_; }

 private:
  void recurse(const std::vector<Bernstein<S>>& patches, const FaceEnds& ends, int depth,
               std::vector<std::vector<S>>& roots) {
    //! [crossing-face]
    // Exclusion: a coefficient hull of one sign on the face means no root.
    const Box<S>& box = patches.front().domain();
    for (std::size_t i = 0; i < patches.size(); ++i) {
      if (!patches[i].excludesZero()) continue;
      // The exclusion is a proof when every coefficient clears the rounding margin, or when
      // interval evaluation confirms it; otherwise the decision stands but is not proven.
      if (!clearsRange(patches[i], S(0), S(0), margins_[i]) && !intervalExcludes(box, int(i)))
        proven_ = false, withinRounding_ = true;
      return;
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
      if (newton(box, y) && insideClosed(box, y)) {
        proven_ = false;  // K proves the root interior, Newton puts it on the boundary
        return;           // owned by the neighbour face
      }
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

  /// The sign rule on an edge is a proof when the signs of F at both ends are (the end
  /// coefficients clear the rounding margin, or interval values exclude 0 or are exactly 0,
  /// which counts as +) and the edge holds at most one root of F: the coefficients, or the
  /// differences of consecutive ones (the derivative), have one strict sign.
  bool edgeProven(const Bernstein<S>& patch) const {
    using I = Interval<S>;
    const S& margin = margins_[0];
    const auto c = patch.coefficients();
    std::vector<I> x;
    x.reserve(n_);
    for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
    const Box<S>& box = patch.domain();
    for (int end = 0; end < 2; ++end) {
      using std::abs;
      if (abs(end ? c.back() : c.front()) > margin) continue;
      x[free_[0]] = I(end ? box.hi[0] : box.lo[0]);
      const I v = system_.equations()[0].template evaluate<S>(std::span<const I>(x));
      if (v.containsZero() && !(v.lower() == 0 && v.upper() == 0)) return false;
    }
    if (clearsRange(patch, S(0), S(0), margin)) return true;
    if (!derivativeHull(patch, 0, margin).containsZero()) return true;
    // Monotone or root-free pieces with at most one sign change in all: as where the edge
    // ends on a plane of symmetry of F (dF = 0 there, the root lies inside).
    int pieces = 64;  // F = 0 along the whole edge would otherwise halve it 2^12 times
    const int roots = provenRoots(patch, 0, pieces);
    if (roots == 0 || roots == 1) return true;
    // F >= 0 on the whole edge (it may touch 0, as along a line of M on a grid line): the
    // level set F = -delta of the sign rule does not meet it.
    x[free_[0]] = I(box.lo[0], box.hi[0]);
    const I v = system_.equations()[0].template evaluate<S>(std::span<const I>(x));
    return v.lower() >= 0 || v.upper() < 0;
  }

  /// The number of roots of F on the edge patch, proven by halving into pieces that are root
  /// free (coefficients clear 0) or monotone (derivative hull clears 0; then the end signs
  /// count the root); -1 when a piece stays undecided at 2^-kMaxEdgeDepth of the edge or
  /// after `pieces` pieces.
  int provenRoots(const Bernstein<S>& patch, int depth, int& pieces) const {
    constexpr int kMaxEdgeDepth = 12;
    const S& margin = margins_[0];
    if (clearsRange(patch, S(0), S(0), margin)) return 0;
    if (!derivativeHull(patch, 0, margin).containsZero()) {
      using std::abs;
      const auto c = patch.coefficients();
      if (abs(c.front()) <= margin || abs(c.back()) <= margin) return -1;
      return (c.front() < 0) != (c.back() < 0) ? 1 : 0;
    }
    if (depth >= kMaxEdgeDepth || --pieces < 0) return -1;
    Bernstein<S> lower, upper;
    patch.halve(0, lower, upper);
    const int a = provenRoots(lower, depth + 1, pieces);
    if (a < 0) return -1;
    const int b = provenRoots(upper, depth + 1, pieces);
    return b < 0 ? -1 : a + b;
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
    // J(X) from the hulls of the derivative patches, widened by the rounding margin.
    const Box<S>& box = patches.front().domain();
    jx_.resize(std::size_t(m_) * m_);
    for (int i = 0; i < m_; ++i) {
      for (int j = 0; j < m_; ++j)
        jx_[std::size_t(i) * m_ + j] = derivativeHull(patches[i], j, margins_[i]);
    }
    return krawczyk(box);
  }

  /// J(X) on a box (free coordinates) into jx_, by interval evaluation of the gradients
  /// (outward rounded; for boxes that are not a face patch's).
  void intervalJacobian(const Box<S>& box) {
    using I = Interval<S>;
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
  }

  /// Whether F_i - c_i, evaluated in interval arithmetic over the face box, excludes 0.
  bool intervalExcludes(const Box<S>& box, int i) const {
    using I = Interval<S>;
    std::vector<I> x;
    x.reserve(n_);
    for (int j = 0; j < n_; ++j) x.emplace_back(point_[j]);
    for (int j = 0; j < m_; ++j) x[free_[j]] = I(box.lo[j], box.hi[j]);
    const I f = system_.equations()[i].template evaluate<S>(std::span<const I>(x)) - I(level_[i]);
    return !f.containsZero();
  }

  /// Krawczyk on the box `root +- width` around a Newton root, with J(X) from the interval
  /// gradient; it contains the whole current face when `width` is the face's width, so
  /// kUnique proves the root is the face's only one even when it lies near the face boundary.
  Krawczyk krawczykAround(const std::vector<S>& root, const Box<S>& face) {
    Box<S> box{root, root};
    for (int j = 0; j < m_; ++j) {
      const S w = face.hi[j] - face.lo[j];
      box.lo[j] -= w;
      box.hi[j] += w;
    }
    intervalJacobian(box);
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
  std::span<const S> margins_;
  bool certain_ = true;
  bool proven_ = true;
  bool withinRounding_ = false;
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

}  // namespace

template <class S>
Vector<S> singularValuesAt(const System<S>& system, std::span<const S> x) {
  return Eigen::JacobiSVD<Matrix<S>>(jacobianAt(system, x)).singularValues();
}

template <class S>
GeneralPosition<S>::GeneralPosition(const ConnectionInput<S>& in, const Grid& grid) {
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

template <class S>
std::vector<S> GeneralPosition<S>::level(int attempt) const {
  std::vector<S> c(scale.size());
  for (std::size_t i = 0; i < scale.size(); ++i) {
    const double t = std::fmod(0.6180339887498949 * double(attempt * 7 + i + 1), 1.0);
    c[i] = S(0.5 + 0.5 * t) * scale[i];
  }
  return c;
}

template <class S>
std::int64_t GeneralPosition<S>::nearBoundary(const std::vector<std::vector<S>>& roots,
                                              const Box<S>& box, const std::vector<int>& freeAxes,
                                              const FaceEnds& ends) const {
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

template <class S>
const typename AdaptiveCrossing<S>::RootForms& AdaptiveCrossing<S>::rootForms(
    std::span<const std::int32_t> index, int level) {
  const Problem& problem = in_.problem;
  const int patchLevel = problem.roots.empty() ? 0 : problem.rootLevel;
  CellKey key = 0;
  std::vector<std::int32_t> patch(n_);
  for (int j = 0; j < n_; ++j) {
    patch[j] = index[j] >> (level - patchLevel);
    key = key * (CellKey{1} << patchLevel) + static_cast<CellKey>(patch[j]);
  }
  auto it = rootForms_.find(key);
  if (it != rootForms_.end()) return it->second;
  Box<S> box = domain_;
  if (!problem.roots.empty()) {
    Grid patchGrid = grid_;
    patchGrid.depth = patchLevel;
    box = cellBox(patchGrid, domain_, patch);
  }
  RootForms rf;
  const S unit = ScalarTraits<S>::epsilon();
  for (std::size_t i = 0; i < in_.system.equations().size(); ++i) {
    rf.forms.push_back(in_.system.equations()[i].template toBernstein<S>(box));
    const auto [lo, hi] = rf.forms.back().coefficientRange();
    using std::abs;
    const double relative = i < in_.coefficientError.size() ? in_.coefficientError[i] : 0.0;
    rf.margins.push_back((S(relative) + 1024 * unit) * std::max<S>(abs(lo), abs(hi)));
  }
  return rootForms_.emplace(key, std::move(rf)).first->second;
}

template <class S>
Box<S> AdaptiveCrossing<S>::leafBox(std::int32_t leaf) const {
  return cellBox(tree_.grid(tree_.level(leaf)), domain_, tree_.index(leaf));
}

template <class S>
bool AdaptiveCrossing<S>::restrictTo(std::int32_t leaf) {
  const RootForms& rf = rootForms(tree_.index(leaf), tree_.level(leaf));
  const Box<S> box = leafBox(leaf);
  patches_.resize(m_);
  margins_ = rf.margins;
  bool empty = false, band = false;
  for (int i = 0; i < m_; ++i) {
    patches_[i] = rf.forms[i].restrict(box);
    const S c = level_[i];
    empty = empty || clearsRange(patches_[i], c, c, rf.margins[i]);
    band =
        band || clearsRange(patches_[i], std::min<S>(S(0), c), std::max<S>(S(0), c), rf.margins[i]);
  }
  bandEmpty_.resize(tree_.size(), 0);
  bandEmpty_[leaf] = band;
  return empty;
}

template <class S>
FaceResult<S> AdaptiveCrossing<S>::solveFace(std::int32_t leaf, const std::array<int, 2>& axes,
                                             int side) {
  const Box<S> box = leafBox(leaf);
  const auto ci = tree_.index(leaf);
  const std::int64_t top = tree_.grid(tree_.level(leaf)).cellsPerAxis();
  FaceEnds ends;
  std::vector<int> freeAxes;
  std::vector<S> point(box.lo);
  for (int j = 0; j < n_; ++j) {
    if (j == axes[0] || j == axes[1]) continue;
    freeAxes.push_back(j);
    ends.lower.push_back(ci[j] == 0);
    ends.upper.push_back(ci[j] + 1 == top);
  }
  // Slice the highest fixed axis first so the lower axis numbers stay valid.
  std::vector<Bernstein<S>> face(m_);
  for (int i = 0; i < m_; ++i) {
    face[i] = patches_[i];
    for (int t = k_ - 1; t >= 0; --t) {
      const bool upper = (side >> t) & 1;
      face[i] = face[i].faceSlice(axes[t], upper);
      point[axes[t]] = upper ? box.hi[axes[t]] : box.lo[axes[t]];
    }
  }
  std::vector<std::vector<S>> roots;
  FaceSolver<S> solver(in_.system, maxFaceDepth_, level_, position_.slack);
  FaceResult<S> r;
  r.certain = solver.solve(point, freeAxes, face, ends, roots, margins_);
  r.proven = solver.proven();
  r.withinRounding = solver.withinRounding();
  if (m_ > 1) r.degenerate = position_.nearBoundary(roots, box, freeAxes, ends);
  r.roots = static_cast<int>(roots.size());
  if (!roots.empty()) {
    r.degree = faceDegree(in_.system, roots, freeAxes);
    r.root = roots.front();
  }
  return r;
}

template <class S>
std::int64_t AdaptiveCrossing<S>::crossFaces() {
  polygons_.clear();
  rootPoints_.clear();
  unprovenFaces_.clear();
  unprovenOf_.clear();
  unprovenOfEmpty_.clear();
  std::int64_t degenerate = 0;
  std::vector<std::int32_t> corner(n_), position(n_);
  std::array<Occupant, 4> around;
  const int quadrants = 1 << k_;
  const auto faceTypes = static_cast<std::uint64_t>(fixedAxes_.size()) << k_;
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(tree_.size()); ++c) {
    if (!tree_.active(c)) continue;
    grow();
    bool restricted = false;
    if (empty_[c] < 0) {
      empty_[c] = restrictTo(c) ? 1 : 0;
      restricted = true;
    }
    if (empty_[c] == 1) continue;  // no level set between M and M_c meets it
    const int level = tree_.level(c);
    // A copy: touch leaves added below may move the tree's index storage.
    const std::vector<std::int32_t> ci(tree_.index(c).begin(), tree_.index(c).end());
    for (std::size_t a = 0; a < fixedAxes_.size(); ++a) {
      const auto& axes = fixedAxes_[a];
      for (int side = 0; side < quadrants; ++side) {
        std::copy(ci.begin(), ci.end(), corner.begin());
        for (int t = 0; t < k_; ++t) corner[axes[t]] += (side >> t) & 1;
        // The regions around the face in cyclic order (k = 2): (-a,-b), (+a,-b), (+a,+b),
        // (-a,+b). A finer region means the face is not minimal: its parts belong to the
        // finer leaves. The face belongs to the first leaf of its own level.
        bool minimal = true, owner = true;
        for (int q = 0; q < quadrants && minimal; ++q) {
          const int bits = k_ == 1 ? q : (q == 0 ? 0 : q == 1 ? 1 : q == 2 ? 3 : 2);
          std::copy(corner.begin(), corner.end(), position.begin());
          for (int t = 0; t < k_; ++t) position[axes[t]] += ((bits >> t) & 1) - 1;
          around[q] = tree_.find(level, position);
          minimal = around[q].kind != Occ::kFiner;
          if (around[q].kind == Occ::kLeaf && tree_.level(around[q].leaf) == level &&
              around[q].leaf < c)
            owner = false;
        }
        if (!minimal || !owner) continue;
        const std::uint64_t key =
            static_cast<std::uint64_t>(c) * faceTypes + (a << k_) + std::uint64_t(side);
        auto it = faces_.find(key);
        if (it == faces_.end()) {
          if (!restricted) {
            restrictTo(c);
            restricted = true;
          }
          it = faces_.emplace(key, solveFace(c, axes, side)).first;
        }
        degenerate += addFace(it->second, around, FaceRef{level, corner, axes});
      }
    }
  }
  return degenerate;
}

template <class S>
std::int64_t AdaptiveCrossing<S>::addFace(const FaceResult<S>& r, std::array<Occupant, 4>& around,
                                          const FaceRef& face) {
  const int quadrants = 1 << k_;
  std::vector<S> centre(n_);
  const Grid& g = tree_.grid(face.level);
  for (int j = 0; j < n_; ++j) {
    const bool fixed = j == face.axes[0] || (k_ == 2 && j == face.axes[1]);
    centre[j] = domain_.lo[j] + S((face.corner[j] + (fixed ? 0.0 : 0.5)) * g.cellWidth(j));
  }
  const bool unproven = !r.proven || r.roots > 1 || std::abs(r.degree) > 1 || r.degenerate;
  const bool singular = !r.certain || std::abs(r.degree) > 1;
  // Roots the face solver could not isolate at its finest face level, or within rounding
  // of the face's boundary: a finer cell has the same trouble (a tangency, or a feature at
  // the scale of the level offset c), so such leaves are not refined.
  const bool stuck = !r.certain || r.withinRounding || r.degenerate;
  for (int q = 0; q < quadrants; ++q) {
    if (around[q].kind != Occ::kLeaf) continue;
    if (stuck) stuck_[around[q].leaf] = 1;
    if (unproven) unproven_[around[q].leaf] = 1;
    if (singular) singular_[around[q].leaf] = 1;
    if (unproven)
      setTrouble(around[q].leaf,
                 r.roots > 0 ? std::span<const S>(r.root) : std::span<const S>(centre));
  }
  if (r.degree == 0) {
    if (unproven) recordUnproven(around, face);
    return r.degenerate;
  }
  Polygon p;
  for (int q = 0; q < quadrants; ++q) {
    std::int64_t node = 0;
    if (around[q].kind == Occ::kEmpty) {
      // A cell the level set F = c enters where M only touches it: a touch leaf.
      std::vector<std::int32_t> index(n_);
      grid_.unpack(around[q].key, index);
      around[q].kind = Occ::kLeaf;
      around[q].leaf = tree_.addLeaf(grid_.depth, index, false);
      grow();
      if (unproven) unproven_[around[q].leaf] = 1;
      if (singular) singular_[around[q].leaf] = 1;
    }
    if (around[q].kind == Occ::kLeaf) {
      node = around[q].leaf;
    } else {
      node = -1 - static_cast<std::int64_t>(around[q].key);
      p.outside = true;
    }
    if (p.size > 0 && p.node[p.size - 1] == node) continue;
    p.node[p.size++] = node;
  }
  if (p.size > 1 && p.node[p.size - 1] == p.node[0]) --p.size;
  if (unproven) recordUnproven(around, face);
  p.root = static_cast<std::int32_t>(rootPoints_.size() / n_);
  rootPoints_.insert(rootPoints_.end(), r.root.begin(), r.root.end());
  for (int copy = 0; copy < std::abs(r.degree); ++copy) polygons_.push_back(p);
  return r.degenerate;
}

template <class S>
void AdaptiveCrossing<S>::recordUnproven(const std::array<Occupant, 4>& around,
                                         const FaceRef& face) {
  const auto f = static_cast<std::int32_t>(unprovenFaces_.size());
  for (int q = 0; q < (1 << k_); ++q) {
    if (around[q].kind == Occ::kLeaf) {
      unprovenOf_.resize(tree_.size());
      unprovenOf_[around[q].leaf].push_back(f);
    } else if (around[q].kind == Occ::kEmpty) {
      unprovenOfEmpty_[around[q].key].push_back(f);
    }
  }
  unprovenFaces_.push_back(face);
}

template Vector<double> singularValuesAt(const System<double>&, std::span<const double>);
template Vector<Mpfr> singularValuesAt(const System<Mpfr>&, std::span<const Mpfr>);
template struct GeneralPosition<double>;
template struct GeneralPosition<Mpfr>;
// The members of AdaptiveCrossing defined in this file, for double and ndc::Mpfr.
#define NDC_CROSSING_INSTANTIATE(S)                                                                \
  template const typename AdaptiveCrossing<S>::RootForms& AdaptiveCrossing<S>::rootForms(          \
      std::span<const std::int32_t> index, int level);                                             \
  template Box<S> AdaptiveCrossing<S>::leafBox(std::int32_t leaf) const;                           \
  template bool AdaptiveCrossing<S>::restrictTo(std::int32_t leaf);                                \
  template FaceResult<S> AdaptiveCrossing<S>::solveFace(std::int32_t leaf,                         \
                                                        const std::array<int, 2>& axes, int side); \
  template std::int64_t AdaptiveCrossing<S>::crossFaces();                                         \
  template std::int64_t AdaptiveCrossing<S>::addFace(                                              \
      const FaceResult<S>& r, std::array<Occupant, 4>& around, const FaceRef& face);               \
  template void AdaptiveCrossing<S>::recordUnproven(const std::array<Occupant, 4>& around,         \
                                                    const FaceRef& face);
NDC_CROSSING_INSTANTIATE(double)
NDC_CROSSING_INSTANTIATE(Mpfr)
#undef NDC_CROSSING_INSTANTIATE

}  // namespace ndc::crossing_detail
