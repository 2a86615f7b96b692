#include "pipeline/singular.hpp"

#include <boost/multiprecision/eigen.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <span>
#include <unordered_map>
#include <utility>
#include <variant>

#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/iteration.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/problem/cell_forms.hpp"

namespace ndc {
namespace {

template <class S>
using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// Smallest and largest singular value of an m x n matrix, m <= n.
template <class S>
std::pair<S, S> sigmaRange(const Matrix<S>& a) {
  if (a.rows() == 1) {
    const S s = a.norm();
    return {s, s};
  }
  const Vector<S> v = Eigen::JacobiSVD<Matrix<S>>(a).singularValues();
  return {v(v.size() - 1), v(0)};
}

/// Whether sigma_min(a) > threshold(sigma_max(a)), where two Cholesky factorizations (a few
/// times cheaper than the singular values) decide it clearly; `threshold` nondecreasing. With
/// G = a a^T and T = trace G, sigma_max^2 lies in [T / m, T], and G and a factorization round
/// by under 1e-13 T for these sizes. A factorization of G - t I with
/// t = 2 max(threshold(sqrt T)^2, 1e-8 T) shows lambda_min(G) > t - rounding, so
/// sigma_min > threshold(sigma_max): true. A failed factorization of G - t I with
/// t = threshold(sqrt(T / m))^2 / 2 >= 1e-8 T shows lambda_min(G) < t + rounding < 2 t, so
/// sigma_min < threshold(sigma_max): false. Otherwise (close to the threshold, or not finite)
/// nullopt: the singular values decide.
template <class S, class Threshold>
std::optional<bool> clearlyBeyond(const Matrix<S>& a, const Threshold& threshold) {
  using std::sqrt;
  if (a.rows() < 2) return std::nullopt;  // sigmaRange is a norm there
  for (Eigen::Index i = 0; i < a.size(); ++i)
    if (!isFinite<S>(a.data()[i])) return std::nullopt;
  const Matrix<S> gram = a * a.transpose();
  const S trace = gram.trace();
  const S high = threshold(S(sqrt(trace)));
  const S low = threshold(S(sqrt(trace / S(a.rows()))));
  if (!isFinite(trace) || !isFinite(high) || !(trace > 0)) return std::nullopt;
  const auto factors = [&](const S& t) {
    Matrix<S> shifted = gram;
    shifted.diagonal().array() -= t;
    return Eigen::LLT<Matrix<S>>(shifted).info() == Eigen::Success;
  };
  if (factors(2 * std::max<S>(high * high, S(1e-8) * trace))) return true;
  const S t = low * low / 2;
  if (t >= S(1e-8) * trace && !factors(t)) return false;
  return std::nullopt;
}

/// The data of one block of the grid at the block level (step 1). An equation in its quadratic
/// form (System::quadraticForm) has no Bernstein form here: its Hessian is constant and its
/// gradient affine, so both bounds come from the form itself.
template <class S>
struct Block {
  std::vector<Bernstein<S>> forms;  ///< F_i on the block (a placeholder for a quadratic)
  std::vector<S> lipschitz;         ///< m: Frobenius bound of the Hessian of F_i on the block
  std::vector<S> slope;             ///< m x n: largest |dF_i/dx_j| on the block (bounded)
};

/// A start that Gauss-Newton brought to a singular point.
template <class S>
struct Located {
  std::vector<S> x;
  S sigma = 0;        ///< sigma_min(J(x))
  S scaledSigma = 0;  ///< sigma_min(^J(x))
};

template <class S>
class Search {
 public:
  Search(const Problem& problem, const System<S>& system, const Projection<S>& projection,
         const SolutionCells& cells, const Projections<S>& projections, const Box<S>& domain,
         const SingularOptions& options)
      : problem_(problem),
        system_(system),
        projection_(projection),
        cells_(cells),
        projections_(projections),
        domain_(domain),
        options_(options),
        grid_(cells.grid),
        forms_(system.equations(), cells.grid, domain,
               problem.roots.empty() ? 0 : problem.rootLevel),
        n_(system.n()),
        m_(system.m()),
        eps_(ScalarTraits<S>::epsilon()) {
    blockLevel_ = std::min(grid_.depth, std::max(options.blockLevel, problem.rootLevel));
    maxIterations_ = options.maxIterations > 0
                         ? options.maxIterations
                         : 40 + static_cast<int>(ScalarTraits<S>::precisionBits());
    f_.resize(m_);
    jac_.resize(std::size_t(m_) * n_);
    tol_.resize(m_);
    scale_.assign(m_, S(0));
    // Acceptance region: the closed domain of the grid and of the problem, with a slack of
    // rounding.
    for (int j = 0; j < n_; ++j) {
      using std::max;
      using std::min;
      const S slack = S(64) * eps_ * (domain.hi[j] - domain.lo[j]);
      inLo_.push_back(max(domain.lo[j], S(problem.domain.lo[j])) - slack);
      inHi_.push_back(min(domain.hi[j], S(problem.domain.hi[j])) + slack);
      width_ = max(width_, S(domain.hi[j] - domain.lo[j]));
      cellWidth_.push_back((domain.hi[j] - domain.lo[j]) / S(double(grid_.cellsPerAxis())));
    }
  }

  SingularSearch run();

 private:
  /// The data of the block of `cell`, whose root forms are `root` (null when every equation is
  /// in its quadratic form); pure: blocks are made in parallel.
  Block<S> makeBlock(std::span<const std::int32_t> cell,
                     const std::vector<Bernstein<S>>* root) const;
  /// Whether the system needs Bernstein forms here (some equation is not in its quadratic
  /// form).
  bool needsBernstein() const;
  const std::vector<Bernstein<S>>& rootFor(std::span<const std::int32_t> cell);
  CellKey blockKey(std::span<const std::int32_t> cell) const;
  /// Which test of step 1 excludes rank deficiency on `cell` (in `block`); the row norms of
  /// J at its centre into `norms` (for the gradient scales). Reads only, so the cells are
  /// tested in parallel.
  enum class Exclusion : std::uint8_t { kNone, kLipschitz, kEnclosure };
  Exclusion excluded(std::span<const std::int32_t> cell, const Block<S>& block,
                     std::span<S> norms) const;
  /// Step 1: the cells where rank deficiency cannot be excluded, in cell order.
  std::vector<std::int32_t> findCandidates(SingularSearch& out);
  /// Step 2: clusters of face-adjacent candidates within one block, as positions in
  /// `candidates`, best score first.
  std::vector<std::vector<std::int32_t>> clusterCandidates(
      const std::vector<std::int32_t>& candidates);
  /// Step 3 for one cluster: Gauss-Newton from its best cells until one point near the cluster
  /// is found; merged into `found` (the better of two points one cell apart stays).
  void searchCluster(const std::vector<std::int32_t>& cluster,
                     const std::vector<std::int32_t>& candidates, std::vector<Located<S>>& found,
                     SingularSearch& out);
  /// The start of Gauss-Newton for cell c.
  std::vector<S> seedOf(std::size_t c) const;
  S score(std::size_t c);
  bool locate(std::span<const S> start, Located<S>& result);
  bool accept(const std::vector<S>& x, Located<S>& result);
  /// F(x)/s, ^J(x)^T v and (|v|^2 - 1)/2 into g, ^J(x) into jhat; false if not finite.
  bool residual(const std::vector<S>& x, const Vector<S>& v, Vector<S>& g, Matrix<S>& jhat);

  const Problem& problem_;
  const System<S>& system_;
  const Projection<S>& projection_;  // its backward-error tolerance decides acceptance
  const SolutionCells& cells_;
  const Projections<S>& projections_;
  const Box<S>& domain_;
  const SingularOptions& options_;
  const Grid& grid_;
  CellForms<S> forms_;  // the root forms of the blocks
  const int n_, m_;
  const S eps_;
  int blockLevel_ = 0, maxIterations_ = 0;
  S width_ = 0;
  std::vector<S> inLo_, inHi_, cellWidth_;
  std::vector<S> scale_;  // s_i
  CellMap<Block<S>> blocks_;
  // Scratch.
  std::vector<S> f_, jac_, tol_;
};

template <class S>
CellKey Search<S>::blockKey(std::span<const std::int32_t> cell) const {
  const int shift = grid_.depth - blockLevel_;
  CellKey key = 0;
  for (int j = 0; j < n_; ++j) key |= static_cast<CellKey>(cell[j] >> shift) << (blockLevel_ * j);
  return key;
}

template <class S>
const std::vector<Bernstein<S>>& Search<S>::rootFor(std::span<const std::int32_t> cell) {
  // One polynomial per equation on the grid's domain, or per B-spline patch.
  return forms_.root(cell, grid_.depth);
}

template <class S>
bool Search<S>::needsBernstein() const {
  for (int i = 0; i < m_; ++i)
    if (!system_.quadraticForm(i)) return true;
  return false;
}

template <class S>
Block<S> Search<S>::makeBlock(std::span<const std::int32_t> cell,
                              const std::vector<Bernstein<S>>* root) const {
  using std::abs;
  using std::max;
  using std::sqrt;
  const int shift = grid_.depth - blockLevel_;
  std::vector<std::int32_t> index(n_);
  for (int j = 0; j < n_; ++j) index[j] = cell[j] >> shift;
  const Box<S> box = cellBox<S>(Grid{n_, blockLevel_, grid_.domain}, domain_, index);
  const auto largest = [](const Bernstein<S>& p) {
    S worst = 0;
    for (const S& c : p.coefficients()) worst = max<S>(worst, abs(c));
    return worst;
  };
  // The quadratics' gradients at the block's centre, and its half-widths.
  std::vector<S> centre(n_), half(n_), f(m_), jac(std::size_t(m_) * n_), spread(n_);
  for (int j = 0; j < n_; ++j) {
    centre[j] = (box.lo[j] + box.hi[j]) / 2;
    half[j] = max<S>(box.hi[j] - centre[j], centre[j] - box.lo[j]);
  }
  system_.evaluate(centre, f, jac);
  Block<S> block;
  block.lipschitz.assign(m_, S(0));
  block.slope.assign(std::size_t(m_) * n_, S(0));
  for (int i = 0; i < m_; ++i) {
    if (system_.hessianSpread(i, half, spread)) {
      // |dF_i/dx_j| <= |G_j(c)| + (|H| h)_j on the block; |H|_F everywhere.
      block.forms.emplace_back();
      for (int j = 0; j < n_; ++j)
        block.slope[std::size_t(i) * n_ + j] = abs(jac[std::size_t(i) * n_ + j]) + spread[j];
      block.lipschitz[i] = system_.hessianNorm(i);
      continue;
    }
    block.forms.push_back((*root)[i].restrict(box));
    S frobenius = 0;
    for (int j = 0; j < n_; ++j) {
      const Bernstein<S> dj = block.forms[i].derivative(j);
      block.slope[std::size_t(i) * n_ + j] = largest(dj);
      // The Hessian entries bounded by their Bernstein coefficients (off-diagonal ones twice).
      for (int k = j; k < n_; ++k) {
        const S h = largest(dj.derivative(k));
        frobenius += (k == j ? S(1) : S(2)) * h * h;
      }
    }
    block.lipschitz[i] = sqrt(frobenius);
  }
  return block;
}

template <class S>
typename Search<S>::Exclusion Search<S>::excluded(std::span<const std::int32_t> cell,
                                                  const Block<S>& block, std::span<S> norms) const {
  using std::abs;
  using std::sqrt;
  const Box<S> box = cellBox<S>(grid_, domain_, cell);
  std::vector<S> centre(n_);
  S radius2 = 0;
  for (int j = 0; j < n_; ++j) {
    centre[j] = (box.lo[j] + box.hi[j]) / 2;
    const S half = (box.hi[j] - box.lo[j]) / 2;
    radius2 += half * half;
  }
  const S radius = sqrt(radius2);
  std::vector<S> f(m_), jac(std::size_t(m_) * n_);
  system_.evaluate(centre, f, jac);
  // The row scaling D at the centre; the gradient scales s_i.
  std::vector<S> d(m_);
  Matrix<S> a(m_, n_);
  for (int i = 0; i < m_; ++i) {
    S norm2 = 0;
    for (int j = 0; j < n_; ++j)
      norm2 += jac[std::size_t(i) * n_ + j] * jac[std::size_t(i) * n_ + j];
    const S norm = sqrt(norm2);
    norms[i] = norm;
    d[i] = norm > 0 && isFinite(norm) ? S(1 / norm) : S(1);
    for (int j = 0; j < n_; ++j) a(i, j) = d[i] * jac[std::size_t(i) * n_ + j];
  }
  const S relative = S(1e-8), absolute = S(1e3) * eps_;

  // Test 1 (Weyl): ||D (J(x) - J(c))||_2 <= |x - c| ||D L|| on the cell.
  S lip2 = 0;
  for (int i = 0; i < m_; ++i) lip2 += d[i] * d[i] * block.lipschitz[i] * block.lipschitz[i];
  const auto lipschitzBound = [&](const S& sigmaMax) {
    return S(sqrt(lip2) * radius * (1 + relative) + absolute * sigmaMax);
  };
  const std::optional<bool> lipschitz = clearlyBeyond<S>(a, lipschitzBound);
  if (lipschitz.value_or(false)) return Exclusion::kLipschitz;
  if (!lipschitz) {
    const auto [sigmaMin, sigmaMax] = sigmaRange<S>(a);
    if (isFinite(sigmaMin) && sigmaMin > lipschitzBound(sigmaMax)) return Exclusion::kLipschitz;
  }

  // Test 2 (Weyl): J(x) in [A - R, A + R] entrywise, from the Bernstein form on the cell, or
  // for a quadratic from its affine gradient: G_j(c) +- (|H| h)_j.
  Matrix<S> mid(m_, n_), rad(m_, n_);
  std::vector<S> half(n_), spread(n_);
  for (int j = 0; j < n_; ++j) half[j] = std::max<S>(box.hi[j] - centre[j], centre[j] - box.lo[j]);
  S slope2 = 0;
  for (int i = 0; i < m_; ++i) {
    const bool quadratic = system_.hessianSpread(i, half, spread);
    const Bernstein<S> form = quadratic ? Bernstein<S>() : block.forms[i].restrict(box);
    for (int j = 0; j < n_; ++j) {
      const S& g = jac[std::size_t(i) * n_ + j];
      const auto [lo, hi] = quadratic ? std::pair<S, S>(g - spread[j], g + spread[j])
                                      : form.derivative(j).coefficientRange();
      const S slope = block.slope[std::size_t(i) * n_ + j];
      // m = 1: a partial derivative of one strict sign on the cell proves grad F != 0.
      if (m_ == 1 && (lo > absolute * slope || hi < -absolute * slope))
        return Exclusion::kEnclosure;
      mid(i, j) = d[i] * (lo + hi) / 2;
      rad(i, j) = d[i] * (hi - lo) / 2;
      slope2 += d[i] * d[i] * slope * slope;
    }
  }
  const S enclosureBound = rad.norm() * (1 + relative) + absolute * sqrt(slope2);
  const std::optional<bool> enclosure =
      clearlyBeyond<S>(mid, [&](const S&) { return enclosureBound; });
  if (enclosure) return *enclosure ? Exclusion::kEnclosure : Exclusion::kNone;
  const S midMin = sigmaRange<S>(mid).first;
  if (isFinite(midMin) && midMin > enclosureBound) return Exclusion::kEnclosure;
  return Exclusion::kNone;
}

template <class S>
S Search<S>::score(std::size_t c) {
  // sigma_min(^J) at the projected point, or at the centre when Newton failed.
  std::vector<S> x(n_);
  if (projections_.converged[c]) {
    const auto p = projections_.at(c);
    std::copy(p.begin(), p.end(), x.begin());
  } else {
    const Box<S> box = cellBox<S>(grid_, domain_, cells_.cell(c));
    for (int j = 0; j < n_; ++j) x[j] = (box.lo[j] + box.hi[j]) / 2;
  }
  system_.evaluate(x, f_, jac_);
  Matrix<S> a(m_, n_);
  for (int i = 0; i < m_; ++i)
    for (int j = 0; j < n_; ++j) a(i, j) = jac_[std::size_t(i) * n_ + j] / scale_[i];
  const S s = sigmaRange<S>(a).first;
  return isFinite(s) ? s : S(1e300);
}

template <class S>
bool Search<S>::residual(const std::vector<S>& x, const Vector<S>& v, Vector<S>& g,
                         Matrix<S>& jhat) {
  system_.evaluate(x, f_, jac_);
  for (int i = 0; i < m_; ++i) {
    g(i) = f_[i] / scale_[i];
    for (int j = 0; j < n_; ++j) jhat(i, j) = jac_[std::size_t(i) * n_ + j] / scale_[i];
  }
  g.segment(m_, n_) = jhat.transpose() * v;
  g(m_ + n_) = (v.squaredNorm() - 1) / 2;
  for (int r = 0; r < g.size(); ++r)
    if (!isFinite(g(r))) return false;
  return true;
}

template <class S>
bool Search<S>::locate(std::span<const S> start, Located<S>& result) {
  using std::abs;
  using std::cbrt;
  using std::max;
  const int unknowns = n_ + m_, rows = m_ + n_ + 1;
  std::vector<S> x(start.begin(), start.end()), trial(n_), shifted(n_);
  Vector<S> v(m_), g(rows), gTrial(rows), step(unknowns), vTrial(m_);
  Matrix<S> jhat(m_, n_), jhatTrial(m_, n_), jg(rows, unknowns), hessian(n_, n_);

  // v: the left singular vector of the smallest singular value of ^J at the start.
  system_.evaluate(x, f_, jac_);
  for (int i = 0; i < m_; ++i)
    for (int j = 0; j < n_; ++j) jhat(i, j) = jac_[std::size_t(i) * n_ + j] / scale_[i];
  if (m_ == 1) {
    v(0) = 1;
  } else {
    Eigen::JacobiSVD<Matrix<S>> svd(jhat, Eigen::ComputeFullU);
    v = svd.matrixU().col(m_ - 1);
  }
  if (!residual(x, v, g, jhat)) return false;
  S norm = g.norm();
  const IterationGuard<S> guard{std::span<const S>(x)};
  std::vector<S> delta(n_);
  for (int j = 0; j < n_; ++j) delta[j] = cbrt(eps_) * (domain_.hi[j] - domain_.lo[j]);
  Eigen::CompleteOrthogonalDecomposition<Matrix<S>> cod(rows, unknowns);
  cod.setThreshold(S(8 * rows) * eps_);

  int slow = 0;
  for (int it = 0; it < maxIterations_ && norm > 0; ++it) {
    // The Jacobian of the augmented system; the Hessian of v^T F(x)/s by central differences.
    for (int a = 0; a < n_; ++a) {
      shifted = x;
      shifted[a] = x[a] + delta[a];
      if (!residual(shifted, v, gTrial, jhatTrial)) return false;
      const Vector<S> up = gTrial.segment(m_, n_);
      shifted[a] = x[a] - delta[a];
      if (!residual(shifted, v, gTrial, jhatTrial)) return false;
      const S h = (x[a] + delta[a]) - (x[a] - delta[a]);
      hessian.col(a) = (up - gTrial.segment(m_, n_)) / h;
    }
    jg.setZero();
    jg.topLeftCorner(m_, n_) = jhat;
    jg.block(m_, 0, n_, n_) = (hessian + hessian.transpose()) / 2;
    jg.block(m_, n_, n_, m_) = jhat.transpose();
    jg.block(m_ + n_, n_, 1, m_) = v.transpose();
    cod.compute(jg);
    step = -cod.solve(g);

    // Backtracking on |G|: the full Gauss-Newton step, else halves of it.
    S trialNorm = 0;
    const S t = halveStep<S>(12, [&](const S& lambda, int) {
      for (int j = 0; j < n_; ++j) trial[j] = x[j] + lambda * step(j);
      vTrial = v + lambda * step.tail(m_);
      if (!residual(trial, vTrial, gTrial, jhatTrial)) return false;
      trialNorm = gTrial.norm();
      return trialNorm < norm;
    });
    if (t == 0) break;  // at the rounding floor (or a local minimum of |G|)
    S moved = 0, size = 0;
    for (int j = 0; j < n_; ++j) {
      moved = max<S>(moved, abs(trial[j] - x[j]));
      size = max<S>(size, abs(trial[j]));
    }
    slow = trialNorm > S(0.99) * norm ? slow + 1 : 0;
    std::swap(x, trial);
    v = vTrial;
    std::swap(g, gTrial);
    std::swap(jhat, jhatTrial);
    norm = trialNorm;
    if (guard.diverged(size)) return false;
    if (IterationGuard<S>::stagnated(moved, size) || slow >= 3) break;
  }
  return accept(x, result);
}

template <class S>
bool Search<S>::accept(const std::vector<S>& x, Located<S>& result) {
  using std::abs;
  using std::sqrt;
  for (int j = 0; j < n_; ++j)
    if (!(x[j] >= inLo_[j] && x[j] <= inHi_[j])) return false;
  system_.evaluate(x, f_, jac_);
  std::visit([&](const auto& model) { model.residualTolerance(x, tol_); }, projection_);
  const S d = S(64) * eps_ * width_;
  Matrix<S> j(m_, n_), jhat(m_, n_);
  for (int i = 0; i < m_; ++i) {
    S norm2 = 0;
    for (int k = 0; k < n_; ++k) {
      j(i, k) = jac_[std::size_t(i) * n_ + k];
      jhat(i, k) = j(i, k) / scale_[i];
      norm2 += j(i, k) * j(i, k);
    }
    // Within rounding of the domain size of a zero of F_i.
    const S allowed = S(64) * tol_[i] + d * sqrt(norm2) + d * d * scale_[i] / width_;
    if (!(abs(f_[i]) <= allowed)) return false;
  }
  const S tau = S(1e-6) * sqrt(eps_ / S(0x1p-52));
  result.scaledSigma = sigmaRange<S>(jhat).first;
  if (!(result.scaledSigma <= tau)) return false;
  result.sigma = sigmaRange<S>(j).first;
  result.x = x;
  return true;
}

template <class S>
SingularSearch Search<S>::run() {
  SingularSearch out;
  out.cells = static_cast<std::int64_t>(cells_.size());
  if (cells_.size() == 0 || m_ == 0) return out;
  const std::vector<std::int32_t> candidates = findCandidates(out);  // step 1
  if (candidates.empty()) return out;
  for (S& s : scale_)
    if (!(s > 0)) s = 1;
  const std::vector<std::vector<std::int32_t>> clusters = clusterCandidates(candidates);  // 2
  out.clusters = static_cast<std::int64_t>(clusters.size());
  // Step 3: Gauss-Newton from the best cells of each cluster; merge duplicates.
  std::vector<Located<S>> found;
  for (const auto& cluster : clusters) {
    if (out.attempts >= options_.maxAttempts) break;
    if (static_cast<int>(found.size()) >= options_.maxPoints) break;
    searchCluster(cluster, candidates, found, out);
  }
  for (const Located<S>& p : found) {
    SingularPoint sp;
    for (const S& v : p.x) sp.point.push_back(toDouble(v));
    sp.sigmaMin = toDouble(p.sigma);
    out.points.push_back(std::move(sp));
  }
  std::sort(out.points.begin(), out.points.end(),
            [](const SingularPoint& p, const SingularPoint& q) { return p.point < q.point; });
  return out;
}

template <class S>
std::vector<std::int32_t> Search<S>::findCandidates(SingularSearch& out) {
  // Step 1: candidate cells, where rank deficiency cannot be excluded. The blocks first, in
  // cell order (the root forms are made on first use), each block's data in parallel.
  const std::size_t count = cells_.size();
  const bool bernstein = needsBernstein();
  std::vector<std::size_t> firsts;  // the first cell of each new block
  std::vector<const std::vector<Bernstein<S>>*> roots;
  CellSet pending;
  for (std::size_t c = 0; c < count; ++c) {
    const CellKey key = blockKey(cells_.cell(c));
    if (blocks_.count(key) || !pending.insert(key).second) continue;
    firsts.push_back(c);
    roots.push_back(bernstein ? &rootFor(cells_.cell(c)) : nullptr);
  }
  std::vector<Block<S>> made(firsts.size());
  parallelFor(firsts.size(),
              [&](std::size_t b) { made[b] = makeBlock(cells_.cell(firsts[b]), roots[b]); });
  for (std::size_t b = 0; b < firsts.size(); ++b)
    blocks_.emplace(blockKey(cells_.cell(firsts[b])), std::move(made[b]));
  // Then the cells' tests in parallel, each into its slots, merged in cell order.
  std::vector<Exclusion> result(count);
  std::vector<S> norms(count * std::size_t(m_));
  parallelFor(count, [&](std::size_t c) {
    const auto cell = cells_.cell(c);
    result[c] = excluded(cell, blocks_.at(blockKey(cell)),
                         std::span<S>(norms).subspan(c * std::size_t(m_), std::size_t(m_)));
  });
  std::vector<std::int32_t> candidates;
  for (std::size_t c = 0; c < count; ++c) {
    for (int i = 0; i < m_; ++i) {
      const S& norm = norms[c * std::size_t(m_) + std::size_t(i)];
      if (isFinite(norm) && norm > scale_[i]) scale_[i] = norm;
    }
    if (result[c] == Exclusion::kLipschitz) ++out.excludedByLipschitz;
    if (result[c] == Exclusion::kEnclosure) ++out.excludedByEnclosure;
    if (result[c] == Exclusion::kNone) candidates.push_back(static_cast<std::int32_t>(c));
  }
  out.candidates = static_cast<std::int64_t>(candidates.size());
  return candidates;
}

template <class S>
std::vector<std::vector<std::int32_t>> Search<S>::clusterCandidates(
    const std::vector<std::int32_t>& candidates) {
  // Step 2: clusters of face-adjacent candidates within one block (union-find), each sorted by
  // score (best first), the clusters by their best score.
  std::vector<std::int32_t> position(cells_.size(), -1);
  for (std::size_t a = 0; a < candidates.size(); ++a)
    position[static_cast<std::size_t>(candidates[a])] = static_cast<std::int32_t>(a);
  std::vector<std::int32_t> parent(candidates.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](std::int32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (std::size_t a = 0; a < candidates.size(); ++a) {
    const std::size_t c = static_cast<std::size_t>(candidates[a]);
    const CellKey key = blockKey(cells_.cell(c));
    for (int axis = 0; axis < n_; ++axis) {
      const std::int32_t nb = cells_.neighbour(c, axis, +1);
      if (nb < 0 || position[nb] < 0 || blockKey(cells_.cell(nb)) != key) continue;
      parent[find(static_cast<std::int32_t>(a))] = find(position[nb]);
    }
  }
  std::vector<S> scores(candidates.size());
  for (std::size_t a = 0; a < candidates.size(); ++a) scores[a] = score(candidates[a]);
  std::unordered_map<std::int32_t, std::vector<std::int32_t>> members;
  for (std::size_t a = 0; a < candidates.size(); ++a)
    members[find(static_cast<std::int32_t>(a))].push_back(static_cast<std::int32_t>(a));
  std::vector<std::vector<std::int32_t>> clusters;
  for (auto& [root, list] : members) {
    std::sort(list.begin(), list.end(), [&](std::int32_t p, std::int32_t q) {
      return scores[p] < scores[q] || (!(scores[q] < scores[p]) && p < q);
    });
    clusters.push_back(std::move(list));
  }
  std::sort(clusters.begin(), clusters.end(), [&](const auto& p, const auto& q) {
    return scores[p[0]] < scores[q[0]] || (!(scores[q[0]] < scores[p[0]]) && p[0] < q[0]);
  });
  return clusters;
}

template <class S>
void Search<S>::searchCluster(const std::vector<std::int32_t>& cluster,
                              const std::vector<std::int32_t>& candidates,
                              std::vector<Located<S>>& found, SingularSearch& out) {
  // The cluster's cells grown by one cell: where its point must lie.
  std::vector<std::int32_t> lo(n_, grid_.cellsPerAxis()), hi(n_, -1);
  for (std::int32_t a : cluster) {
    const auto cell = cells_.cell(candidates[a]);
    for (int j = 0; j < n_; ++j) {
      lo[j] = std::min(lo[j], cell[j] - 1);
      hi[j] = std::max(hi[j], cell[j] + 2);
    }
  }
  const auto sameAs = [&](const Located<S>& p, const Located<S>& q) {
    using std::abs;
    for (int j = 0; j < n_; ++j)
      if (!(abs(p.x[j] - q.x[j]) < cellWidth_[j])) return false;
    return true;
  };
  const int tries = std::min<int>(options_.seedsPerCluster, static_cast<int>(cluster.size()));
  for (int s = 0; s < tries && out.attempts < options_.maxAttempts; ++s) {
    ++out.attempts;
    Located<S> point;
    if (!locate(seedOf(static_cast<std::size_t>(candidates[cluster[s]])), point)) continue;
    bool near = true;
    for (int j = 0; j < n_ && near; ++j) {
      near = point.x[j] >= domain_.lo[j] + cellWidth_[j] * S(double(lo[j])) &&
             point.x[j] <= domain_.lo[j] + cellWidth_[j] * S(double(hi[j]));
    }
    if (!near) continue;
    ++out.accepted;
    auto same = std::find_if(found.begin(), found.end(),
                             [&](const Located<S>& q) { return sameAs(point, q); });
    if (same == found.end()) {
      found.push_back(std::move(point));
    } else if (point.scaledSigma < same->scaledSigma) {
      *same = std::move(point);
    }
    return;  // one point per cluster
  }
}

template <class S>
std::vector<S> Search<S>::seedOf(std::size_t c) const {
  // The cell's projected point, or its centre where Newton did not converge.
  std::vector<S> seed(n_);
  if (projections_.converged[c]) {
    const auto p = projections_.at(c);
    std::copy(p.begin(), p.end(), seed.begin());
  } else {
    const Box<S> box = cellBox<S>(grid_, domain_, cells_.cell(c));
    for (int j = 0; j < n_; ++j) seed[j] = (box.lo[j] + box.hi[j]) / 2;
  }
  return seed;
}

}  // namespace

template <class S>
SingularSearch findSingularPoints(const Problem& problem, const System<S>& system,
                                  const Projection<S>& projection, const SolutionCells& cells,
                                  const Projections<S>& projections, const Box<S>& domain,
                                  const SingularOptions& options) {
  return Search<S>(problem, system, projection, cells, projections, domain, options).run();
}

template SingularSearch findSingularPoints(const Problem&, const System<double>&,
                                           const Projection<double>&, const SolutionCells&,
                                           const Projections<double>&, const Box<double>&,
                                           const SingularOptions&);
template SingularSearch findSingularPoints(const Problem&, const System<Mpfr>&,
                                           const Projection<Mpfr>&, const SolutionCells&,
                                           const Projections<Mpfr>&, const Box<Mpfr>&,
                                           const SingularOptions&);

template <class S>
std::int64_t joinAtSingularPoints(Complex<S>& complex, const std::vector<SingularPoint>& points,
                                  const Grid& grid) {
  const int n = complex.n;
  std::int64_t moved = 0;
  std::vector<std::size_t> near;
  for (const SingularPoint& p : points) {
    // The vertices within one cell of the point, and the nearest of them.
    near.clear();
    std::size_t nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < complex.vertexCount(); ++v) {
      const auto x = complex.vertex(v);
      bool inside = true;
      double d2 = 0;
      for (int j = 0; j < n && inside; ++j) {
        const double d = toDouble(x[j]) - p.point[j];
        inside = std::abs(d) <= grid.cellWidth(j) * (1 + 1e-9);
        d2 += d * d;
      }
      if (!inside) continue;
      near.push_back(v);
      if (d2 < best) best = d2, nearest = v;
    }
    if (near.size() < 2) continue;
    const std::vector<S> target(complex.vertex(nearest).begin(), complex.vertex(nearest).end());
    for (std::size_t v : near) {
      if (v == nearest) continue;
      std::copy(target.begin(), target.end(), complex.vertices.begin() + v * n);
      ++moved;
    }
  }
  return moved;
}

template std::int64_t joinAtSingularPoints(Complex<double>&, const std::vector<SingularPoint>&,
                                           const Grid&);
template std::int64_t joinAtSingularPoints(Complex<Mpfr>&, const std::vector<SingularPoint>&,
                                           const Grid&);

}  // namespace ndc
