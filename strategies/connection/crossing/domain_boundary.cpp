#include "strategies/connection/crossing/domain_boundary.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "framework/numeric/interval.hpp"
#include "framework/numeric/iteration.hpp"
#include "framework/numeric/minimum_norm.hpp"
#include "framework/numeric/parallel.hpp"
#include "strategies/connection/crossing/certificate.hpp"
#include "strategies/connection/crossing/enclosure.hpp"
#include "strategies/connection/crossing/jacobian_work.hpp"
#include "strategies/connection/crossing/leaf_model.hpp"

namespace ndc::crossing_detail {

template <class S>
bool levelsMiss(const System<S>& system, const Box<S>& box, std::span<const S> level,
                bool byEvaluation) {
  using I = Interval<S>;
  using std::abs;
  const int n = box.dim(), m = system.m();
  // The band of levels between 0 and c_i.
  const auto misses = [&](const I& f, int i) {
    return f.lower() > std::max<S>(S(0), level[i]) || f.upper() < std::min<S>(S(0), level[i]);
  };
  std::vector<I> x;
  for (int j = 0; j < n; ++j) x.emplace_back(box.lo[j], box.hi[j]);
  for (int i = 0; i < m; ++i) {
    if (misses(system.equations()[i].template evaluate<S>(std::span<const I>(x)), i)) return true;
  }
  if (!byEvaluation) return false;
  // The mean-value form around the centre y, for the middle level c / 2, widened by |c| / 2.
  std::vector<S> centre, radius, middle(level.begin(), level.end());
  for (S& c : middle) c /= 2;
  centreAndRadius(box, centre, radius);
  std::vector<int> all(n);
  for (int j = 0; j < n; ++j) all[j] = j;
  std::vector<I> jacobian, fy;
  bool excluded = false;
  if (!encloseSystem(threadEvaluators(system), std::span<const S>(centre),
                     std::span<const S>(radius), std::span<const S>(middle),
                     std::span<const int>(all), jacobian, fy, excluded, false))
    return false;
  const S up = S(1) + S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  for (int i = 0; i < m; ++i) {
    S spread = abs(middle[i]);
    for (int j = 0; j < n; ++j) {
      const I& d = jacobian[std::size_t(i) * n + j];
      spread += std::max<S>(abs(d.lower()), abs(d.upper())) * radius[j];
    }
    if (!(fy[i] + I(-spread * up, spread * up)).containsZero()) return true;
  }
  return false;
}

template <class S>
bool slicesMiss(const std::vector<Bernstein<S>>& patches, std::span<const S> margins,
                const Box<S>& leaf, const DomainStratum<S>& face, std::span<const S> level) {
  // Slice the largest fixed axis first, so that the smaller ones keep their index.
  std::vector<int> fixed = face.fixed;
  std::sort(fixed.rbegin(), fixed.rend());
  for (std::size_t i = 0; i < patches.size(); ++i) {
    Bernstein<S> slice = patches[i];
    for (int a : fixed) slice = slice.faceSlice(a, face.box.lo[a] == leaf.hi[a]);
    const S lo = std::min<S>(S(0), level[i]), hi = std::max<S>(S(0), level[i]);
    if (clearsRange(slice, lo, hi, margins[i])) return true;
  }
  return false;
}

/// faceNewton's working storage, per thread (threadScratch).
template <class S>
struct FaceNewtonWork {
  std::vector<S> f, jacobian, free, step;
  MinimumNormSolver<S> solver;
};

/// Gauss-Newton on the free coordinates of x towards M: each step the minimum-norm step of a
/// pivoted QR of J's free columns or, with `leastSquares`, least squares by the singular values
/// where the QR declines (their rank below m, or fewer than m of them). False when F is not
/// finite, the QR declines without `leastSquares`, or x leaves `near` (when given) by four of
/// its widths.
template <class S>
bool freeNewton(const System<S>& system, std::span<S> x, const std::vector<int>& freeAxes,
                bool leastSquares, const Box<S>* near) {
  using std::abs;
  using Matrix = typename JacobianWork<S>::Matrix;
  using Vector = typename JacobianWork<S>::Vector;
  constexpr int kIterations = 40;  // as the run's projection
  std::optional<FaceNewtonWork<S>> fresh;
  FaceNewtonWork<S>& w = threadScratch<S, FaceNewtonWork<S>>(fresh);
  const int n = system.n(), m = system.m(), free = static_cast<int>(freeAxes.size());
  w.f.resize(m), w.jacobian.resize(std::size_t(m) * n);
  w.free.resize(std::size_t(m) * free), w.step.resize(free);
  const S threshold = S(8 * free) * ScalarTraits<S>::epsilon();
  Matrix a;
  Vector r;
  for (int it = 0; it < kIterations; ++it) {
    system.evaluate(std::span<const S>(x.data(), x.size()), w.f, w.jacobian);
    if (!std::all_of(w.f.begin(), w.f.end(), isFinite<S>)) return false;
    // The step moves the free coordinates only: J's columns of the free axes.
    for (int i = 0; i < m; ++i) {
      for (int t = 0; t < free; ++t)
        w.free[std::size_t(i) * free + t] = w.jacobian[std::size_t(i) * n + freeAxes[t]];
    }
    if (free >= m && w.solver.factor(w.free.data(), m, free, threshold)) {
      w.solver.solve(w.f.data(), w.step.data());
    } else if (leastSquares) {
      a.resize(m, free), r.resize(m);
      for (int i = 0; i < m; ++i) {
        r(i) = w.f[i];
        for (int t = 0; t < free; ++t) a(i, t) = w.free[std::size_t(i) * free + t];
      }
      const Vector step = a.jacobiSvd(Eigen::ComputeThinU | Eigen::ComputeThinV).solve(r);
      for (int t = 0; t < free; ++t) w.step[t] = step(t);
    } else {
      return false;
    }
    S size = 0;
    bool away = false;
    for (int t = 0; t < free; ++t) {
      const int j = freeAxes[t];
      x[j] -= w.step[t];
      size = std::max<S>(size, abs(w.step[t]));
      if (near) {
        const S width = near->hi[j] - near->lo[j];
        away = away || !(x[j] >= near->lo[j] - 4 * width && x[j] <= near->hi[j] + 4 * width);
      }
    }
    if (away) return false;
    if (IterationGuard<S>::stagnated(size, normInf<S>(std::span<const S>(x.data(), x.size()))))
      return true;
  }
  return true;
}

template <class S>
bool faceNewton(const System<S>& system, std::span<S> x, const std::vector<int>& freeAxes) {
  if (static_cast<int>(freeAxes.size()) < system.m()) return false;
  return freeNewton(system, x, freeAxes, false, static_cast<const Box<S>*>(nullptr));
}

template <class S>
bool tangentToFace(const System<S>& system, const DomainStratum<S>& face) {
  using std::abs;
  using Matrix = typename JacobianWork<S>::Matrix;
  const int n = system.n(), m = system.m(), free = static_cast<int>(face.free.size());
  std::vector<S> x(n);
  for (int j = 0; j < n; ++j) x[j] = (face.box.lo[j] + face.box.hi[j]) / 2;
  // Gauss-Newton towards a point of M on the face's plane, going on where the free columns
  // lose rank (on a face of dimension below m too), and given up once x is four face widths
  // away: the test below wants it within one (a probe for cost, not a proof; docs/
  // certificate.md, "Blocks"). A corner of D has nothing to move.
  if (!face.free.empty() && !freeNewton(system, std::span<S>(x), face.free, true, &face.box))
    return false;
  // Within the face widened by its width, and on M.
  for (int j : face.free) {
    const S width = face.box.hi[j] - face.box.lo[j];
    if (!(x[j] >= face.box.lo[j] - width && x[j] <= face.box.hi[j] + width)) return false;
  }
  std::optional<JacobianWork<S>> fresh;
  JacobianWork<S>& work = threadScratch<S, JacobianWork<S>>(fresh);
  const auto& full = work.jacobianAt(system, std::span<const S>(x));
  // On M: every residual small against the gradient times the face's size.
  for (int i = 0; i < m; ++i) {
    S scale = 0;
    for (int j = 0; j < n; ++j) scale += abs(full(i, j)) * (face.box.hi[j] - face.box.lo[j]);
    if (!(abs(work.f[i]) <= S(1e-6) * scale)) return false;
  }
  if (free < m) return true;  // M passes through a face of D of dimension below m
  Matrix columns(m, free);
  for (std::size_t t = 0; t < face.free.size(); ++t) columns.col(int(t)) = full.col(face.free[t]);
  Eigen::JacobiSVD<Matrix> svd(columns);
  const S largest = work.singularValues()(0);
  const auto& sigma = svd.singularValues();
  return !(sigma(m - 1) > S(1e-6) * largest);
}

template bool faceNewton(const System<double>&, std::span<double>, const std::vector<int>&);
template bool faceNewton(const System<Mpfr>&, std::span<Mpfr>, const std::vector<int>&);
template bool tangentToFace(const System<double>&, const DomainStratum<double>&);
template bool tangentToFace(const System<Mpfr>&, const DomainStratum<Mpfr>&);
template bool levelsMiss(const System<double>&, const Box<double>&, std::span<const double>, bool);
template bool levelsMiss(const System<Mpfr>&, const Box<Mpfr>&, std::span<const Mpfr>, bool);
template bool slicesMiss(const std::vector<Bernstein<double>>&, std::span<const double>,
                         const Box<double>&, const DomainStratum<double>&, std::span<const double>);
template bool slicesMiss(const std::vector<Bernstein<Mpfr>>&, std::span<const Mpfr>,
                         const Box<Mpfr>&, const DomainStratum<Mpfr>&, std::span<const Mpfr>);

}  // namespace ndc::crossing_detail
