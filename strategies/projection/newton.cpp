#include "strategies/projection/newton.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "framework/numeric/iteration.hpp"
#include "framework/numeric/minimum_norm.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/util/errors.hpp"

namespace ndc {

template <class S>
NewtonProjection<S>::NewtonProjection(const System<S>& system, int maxIterations)
    : system_(&system), maxIterations_(maxIterations) {
  for (const Expression& e : system.equations()) magnitudes_.emplace_back(e.sharedTape());
}

namespace {

/// residualTolerance's working storage (threadScratch).
template <class S>
struct ToleranceWork {
  std::vector<S> absX, stack;
};

/// project's working storage (threadScratch): one projection allocates nothing once warm.
template <class S>
struct ProjectWork {
  std::vector<S> f, jacobian, tol, step;
  MinimumNormSolver<S> solver;
};

}  // namespace

template <class S>
void NewtonProjection<S>::residualTolerance(std::span<const S> x, std::span<S> tol) const {
  for (std::size_t i = 0; i < magnitudes_.size(); ++i) tol[i] = toleranceOf(int(i), x, i == 0);
}

template <class S>
S NewtonProjection<S>::toleranceOf(int i, std::span<const S> x, bool fresh) const {
  using std::abs;
  std::optional<ToleranceWork<S>> own;
  ToleranceWork<S>& w = threadScratch<S, ToleranceWork<S>>(own);
  std::vector<S>&absX = w.absX, &stack = w.stack;
  if (fresh || own) {
    absX.resize(x.size());
    for (std::size_t j = 0; j < x.size(); ++j) absX[j] = abs(x[j]);
  }
  // tol_i = 2 (ops_i + deg_i) eps |F_i|(|x|): see the header.
  const auto& magnitude = magnitudes_[std::size_t(i)];
  return S(2 * magnitude.count()) * ScalarTraits<S>::epsilon() * magnitude(absX, stack);
}

template <class S>
ProjectedPoint<S> NewtonProjection<S>::project(std::span<S> x) const {
  using std::abs;
  const int n = system_->n(), m = system_->m();
  const S eps = ScalarTraits<S>::epsilon();
  const IterationGuard<S> guard{std::span<const S>(x)};
  std::optional<ProjectWork<S>> fresh;
  ProjectWork<S>& w = threadScratch<S, ProjectWork<S>>(fresh);
  std::vector<S>&f = w.f, &jacobian = w.jacobian, &tol = w.tol, &step = w.step;
  f.resize(m), jacobian.resize(std::size_t(m) * n), tol.resize(m), step.resize(n);
  // Relative rank threshold: pivots at most 8 n eps of the first count as zero.
  const S threshold = S(8 * n) * eps;

  // The componentwise tolerance plus the normwise one, 2 eps |x|_inf |grad F_i|_1: a
  // coordinate whose value at the root is 0 (M in a coordinate plane) otherwise never
  // converges, its componentwise rounding being 0. Needs `jacobian` at x.
  // Equation by equation, each tol_i only where the normwise part alone does not pass F_i and
  // only up to the first F_i that fails (the magnitudes are most of a step's cost far from M).
  const auto residualConverged = [&](const S& slack) {
    const S normwise = 2 * eps * normInf<S>(x);
    bool fresh = true;  // |x| not yet taken for this x
    for (int i = 0; i < m; ++i) {
      S gradient = 0;
      for (int j = 0; j < n; ++j) gradient += abs(jacobian[std::size_t(i) * n + j]);
      if (abs(f[i]) <= slack * (normwise * gradient)) continue;
      tol[i] = toleranceOf(i, std::span<const S>(x.data(), x.size()), fresh);
      fresh = false;
      if (!(abs(f[i]) <= slack * (tol[i] + normwise * gradient))) return false;
    }
    return true;
  };

  ProjectedPoint<S> result;
  for (int it = 0;; ++it) {
    result.iterations = it;
    system_->evaluate(x, f, jacobian);
    // Divergence: overflow or NaN ends the iteration.
    if (!std::all_of(f.begin(), f.end(), isFinite<S>)) return result;
    // Converged when no equation can be told from zero at the working precision.
    if (residualConverged(S(1))) {
      result.converged = true;
      return result;
    }
    if (it == maxIterations_) return result;

    //! [newton-step]
    // Minimum-norm step s = J^+ F(x) from a pivoted QR of J^T. A rank-deficient J has no
    // minimum-norm Newton step that zeroes F.
    if (!w.solver.factor(jacobian.data(), m, n, threshold)) return result;
    w.solver.solve(f.data(), step.data());
    S stepNorm = 0;
    for (int j = 0; j < n; ++j) {
      x[j] -= step[j];
      stepNorm = std::max<S>(stepNorm, abs(step[j]));
    }
    result.iterations = it + 1;
    //! [newton-step]

    // Divergence: the iterate ran away from where it started.
    const S size = normInf<S>(x);
    if (guard.diverged(size)) return result;
    // Stagnation at the rounding floor: accept within a slack of the residual tolerance.
    if (IterationGuard<S>::stagnated(stepNorm, size)) {
      system_->evaluate(x, f, jacobian);
      result.converged = std::all_of(f.begin(), f.end(), isFinite<S>) && residualConverged(S(64));
      return result;
    }
  }
}

template <class S>
ModelSpec NewtonProjection<S>::spec() {
  return {"newton",
          "Minimum-norm Newton-Raphson from the cell's centre (Sec. 4, Alg. 1), stopping at the "
          "backward error of the run's scalar.",
          {}};
}

template class NewtonProjection<double>;
template class NewtonProjection<Mpfr>;

}  // namespace ndc
