#include "strategies/connection/crossing/leaf_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "framework/numeric/inverse.hpp"
#include "framework/numeric/iteration.hpp"
#include "framework/numeric/multipliers.hpp"
#include "framework/numeric/parallel.hpp"

namespace ndc {

/// buildFacePreconditioner's working storage (threadScratch).
template <class S>
struct PreconditionerWork {
  std::vector<S> mid, inverse;  ///< m x m, column-major
};

/// faceMultipliersExclude's working storage (threadScratch).
template <class S>
struct FaceMultiplierWork {
  std::vector<S> jac, mu, rho, h;  ///< the face's linearisation: m x free, m, m, free
  MultiplierTest<S> test;
};

template <class S>
void centreAndRadius(const Box<S>& box, std::vector<S>& centre, std::vector<S>& radius) {
  const int n = box.dim();
  const S up = S(1) + S(8) * ScalarTraits<S>::epsilon();
  centre.resize(n);
  radius.resize(n);
  for (int j = 0; j < n; ++j) {
    centre[j] = (box.lo[j] + box.hi[j]) / 2;
    radius[j] = std::max<S>(box.hi[j] - centre[j], centre[j] - box.lo[j]) * up;
  }
}

template <class S>
void buildLeafModel(std::vector<MidRadEvaluator<S>>& evaluators, const Box<S>& box,
                    std::span<const S> level, LeafModel<S>& model) {
  using std::abs;
  const std::size_t m = evaluators.size(), n = static_cast<std::size_t>(box.dim());
  const S eps = 2 * ScalarTraits<S>::epsilon();
  centreAndRadius(box, model.centre, model.radius);
  thread_local std::vector<S> zero;
  zero.assign(n, S(0));
  model.valueMid.resize(m);
  model.valueRad.resize(m);
  model.gradMid.resize(m * n);
  model.gradRad.resize(m * n);
  model.valid = false;
  const S up = S(1) + S(8) * ScalarTraits<S>::epsilon();
  thread_local std::vector<S> spread;
  spread.resize(n);
  for (std::size_t i = 0; i < m; ++i) {
    MidRadEvaluator<S>& e = evaluators[i];
    const bool taylor = e.gradientAffine();
    // J(X): for a quadratic its radius from |H| (gradientSpread; the centres come from the run
    // at c below), otherwise a run over the leaf.
    if (taylor && e.gradientSpread(std::span<const S>(model.radius), std::span<S>(spread))) {
      for (std::size_t j = 0; j < n; ++j) model.gradRad[i * n + j] = spread[j];
    } else {
      if (!e.run(std::span<const S>(model.centre), std::span<const S>(model.radius), true)) return;
      for (std::size_t j = 0; j < n; ++j) {
        model.gradMid[i * n + j] = e.mid(static_cast<int>(j) + 1);
        model.gradRad[i * n + j] = e.rad(static_cast<int>(j) + 1);
      }
    }
    if (!e.run(std::span<const S>(model.centre), std::span<const S>(zero), taylor)) return;
    const int sign = taylor ? e.curvature().sign : 0;
    S remainder = 0;  // sum_j rad J_ij(X) radius_j / 2 >= |d^T H d| / 2 (semidefinite H)
    for (std::size_t j = 0; taylor && j < n; ++j) {
      // The Taylor slope: grad F(c) +- (its rounding + rad J(X) / 2), the sum rounded up; for
      // a semidefinite H the gradient at c alone, the remainder moved into the value below.
      S& rad = model.gradRad[i * n + j];
      if (sign != 0) {
        remainder += rad * model.radius[j];
        rad = e.rad(static_cast<int>(j) + 1);
      } else {
        rad = (e.rad(static_cast<int>(j) + 1) + rad / 2) * up;
      }
      model.gradMid[i * n + j] = e.mid(static_cast<int>(j) + 1);
    }
    // The subtraction of the level rounds once: its error joins the radius.
    model.valueMid[i] = e.mid(0) - level[i];
    model.valueRad[i] = e.rad(0) + eps * abs(model.valueMid[i]);
    if (sign != 0) {
      // d^T H d / 2 in [-slack, remainder] (sign +1; mirrored for -1), slack = the proof's
      // slack times the largest squared radius: its centre joins the value, its radius the
      // value's radius.
      S radiusMax = 0;
      for (std::size_t j = 0; j < n; ++j) radiusMax = std::max(radiusMax, model.radius[j]);
      // The sum of n terms above rounds by at most (n - 1) units: gamma_n covers it.
      remainder = remainder / 2 * (S(1) + S(4 * (n + 4)) * ScalarTraits<S>::epsilon());
      S centre, radius;
      taylorRemainder(e.curvature(), remainder, radiusMax, up, centre, radius);
      model.valueMid[i] += centre;
      model.valueRad[i] = (model.valueRad[i] + radius + eps * abs(model.valueMid[i])) * up;
    }
  }
  model.valid = true;
}

template <class S>
void addFixedTerms(const LeafModel<S>& model, std::size_t i, const Box<S>& box,
                   std::span<const int> axes, int side, S& centre, S& magnitude, S& radius) {
  using std::abs;
  const std::size_t n = model.centre.size();
  const S eps = 2 * ScalarTraits<S>::epsilon();
  for (std::size_t t = 0; t < axes.size(); ++t) {
    const auto j = static_cast<std::size_t>(axes[t]);
    const S x = (side >> t) & 1 ? box.hi[j] : box.lo[j];
    const S d = x - model.centre[j];  // rounded: off by at most eps |d|
    const S g = model.gradMid[i * n + j], r = model.gradRad[i * n + j];
    centre += g * d;
    magnitude += abs(g * d);
    radius += r * abs(d) + (abs(g) + r) * eps * abs(d);
  }
}

template <class S>
bool faceExcluded(const LeafModel<S>& model, const Box<S>& box, std::span<const int> axes,
                  int side) {
  using std::abs;
  if (!model.valid) return false;
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  const S gamma = S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  for (std::size_t i = 0; i < m; ++i) {
    const S* gm = &model.gradMid[i * n];
    const S* gr = &model.gradRad[i * n];
    S centre = model.valueMid[i], magnitude = abs(centre), radius = model.valueRad[i];
    for (std::size_t j = 0; j < n; ++j) {
      if (std::find(axes.begin(), axes.end(), static_cast<int>(j)) != axes.end()) continue;
      radius += (abs(gm[j]) + gr[j]) * model.radius[j];
    }
    addFixedTerms(model, i, box, axes, side, centre, magnitude, radius);
    magnitude += radius;
    if (abs(centre) > radius + gamma * magnitude + tiny) return true;
  }
  return false;
}

template <class S>
void buildFacePreconditioner(const LeafModel<S>& model, std::span<const int> axes,
                             FacePreconditioner<S>& out) {
  using std::abs;
  out.valid = false;
  if (!model.valid) return;
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  out.free.clear();
  for (std::size_t j = 0; j < n; ++j) {
    if (std::find(axes.begin(), axes.end(), static_cast<int>(j)) == axes.end())
      out.free.push_back(static_cast<int>(j));
  }
  if (out.free.size() != m) return;
  std::optional<PreconditionerWork<S>> fresh;
  PreconditionerWork<S>& w = threadScratch<S, PreconditionerWork<S>>(fresh);
  std::vector<S>& mid = w.mid;
  mid.resize(m * m);
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t t = 0; t < m; ++t) mid[t * m + i] = model.gradMid[i * n + out.free[t]];
  }
  std::vector<S>& inverse = w.inverse;
  if (!invertGaussJordan(static_cast<int>(m), mid, inverse)) return;
  out.y.resize(m * m);
  for (std::size_t l = 0; l < m; ++l) {
    for (std::size_t i = 0; i < m; ++i) out.y[l * m + i] = inverse[i * m + l];
  }
  // |I - Y J_free(X)|_lj <= |delta_lj - sum_i Y_li mid_ij| + sum_i |Y_li| rad_ij, plus the
  // gamma_p bound of the sums' rounding; then the spread, rounded up the same way.
  const S gamma = S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  out.spread.assign(m, S(0));
  for (std::size_t l = 0; l < m; ++l) {
    S spread = 0, spreadMagnitude = 0;
    for (std::size_t t = 0; t < m; ++t) {
      const std::size_t j = static_cast<std::size_t>(out.free[t]);
      S centre = S(l == t ? 1 : 0), magnitude = abs(centre), radius = 0;
      for (std::size_t i = 0; i < m; ++i) {
        const S yli = out.y[l * m + i];
        centre -= yli * model.gradMid[i * n + j];
        magnitude += abs(yli * model.gradMid[i * n + j]);
        radius += abs(yli) * model.gradRad[i * n + j];
      }
      magnitude += radius;
      const S entry = abs(centre) + radius + gamma * magnitude + tiny;
      spread += entry * model.radius[j];
      spreadMagnitude += entry * model.radius[j];
    }
    out.spread[l] = spread + gamma * spreadMagnitude + tiny;
    if (!isFinite(out.spread[l])) return;
  }
  out.valid = true;
}

template <class S>
bool faceKrawczykExcludes(const LeafModel<S>& model, const FacePreconditioner<S>& pre,
                          const Box<S>& box, std::span<const int> axes, int side) {
  using std::abs;
  if (!model.valid || !pre.valid) return false;
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  const S gamma = S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  // g(0) = F(c) - level + J_fixed(X) d_fixed: centre, radius and magnitude per equation.
  thread_local std::vector<S> gc, gr, gm;
  gc.resize(m), gr.resize(m), gm.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    S centre = model.valueMid[i], magnitude = abs(centre), radius = model.valueRad[i];
    addFixedTerms(model, i, box, axes, side, centre, magnitude, radius);
    gc[i] = centre;
    gr[i] = radius + gamma * (magnitude + radius);
    gm[i] = magnitude + gr[i];
  }
  // K_l = -(Y g(0))_l + [-s_l, s_l] against [-radius_l, radius_l] of free axis l.
  for (std::size_t l = 0; l < m; ++l) {
    S centre = 0, radius = 0, magnitude = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const S yli = pre.y[l * m + i];
      centre += yli * gc[i];
      radius += abs(yli) * gr[i];
      magnitude += abs(yli) * gm[i];
    }
    const S reach = radius + gamma * magnitude + tiny + pre.spread[l] +
                    model.radius[static_cast<std::size_t>(pre.free[l])];
    if (abs(centre) > reach * (1 + gamma)) return true;
  }
  return false;
}

template <class S>
bool faceMultipliersExclude(const LeafModel<S>& model, const Box<S>& box, std::span<const int> axes,
                            int side, int iterations) {
  using std::abs;
  if (!model.valid) return false;
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  const std::size_t free = n - axes.size();
  const S gamma = S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  std::optional<FaceMultiplierWork<S>> fresh;
  FaceMultiplierWork<S>& w = threadScratch<S, FaceMultiplierWork<S>>(fresh);
  w.jac.resize(m * free), w.mu.resize(m), w.rho.resize(m), w.h.resize(free);
  const auto isFixed = [&](std::size_t j) {
    return std::find(axes.begin(), axes.end(), static_cast<int>(j)) != axes.end();
  };
  for (std::size_t j = 0, t = 0; j < n; ++j)
    if (!isFixed(j)) w.h[t++] = model.radius[j];
  for (std::size_t i = 0; i < m; ++i) {
    S centre = model.valueMid[i], magnitude = abs(centre), radius = model.valueRad[i];
    addFixedTerms(model, i, box, axes, side, centre, magnitude, radius);
    S spread = 0;  // sum over the free axes of rad S_ij h_j
    for (std::size_t j = 0, t = 0; j < n; ++j) {
      if (isFixed(j)) continue;
      w.jac[i * free + t] = model.gradMid[i * n + j];
      spread += model.gradRad[i * n + j] * w.h[t];
      ++t;
    }
    w.mu[i] = centre;
    w.rho[i] = (radius + spread) * (1 + gamma) + gamma * magnitude + tiny;
    if (!isFinite(w.rho[i])) return false;
  }
  return w.test.excludes(static_cast<int>(m), static_cast<int>(free), w.jac.data(), w.mu.data(),
                         w.rho.data(), w.h.data(), gamma, iterations);
}

template <class S>
bool fillModelSystem(const LeafModel<S>& model, LinearizedSystem<S>& system,
                     std::span<const S> shift, std::span<const S> widen) {
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  if (system.n() != static_cast<int>(n) || system.m() != static_cast<int>(m))
    system.resize(static_cast<int>(n), static_cast<int>(m));
  const S up = S(1) + system.tolerance();
  std::copy(model.radius.begin(), model.radius.end(), system.h.begin());
  for (std::size_t i = 0; i < m; ++i) {
    // F_i - level_i in valueMid +- valueRad + sum_j (gradMid_ij +- gradRad_ij) d_j, |d_j| <= h_j.
    S spread = model.valueRad[i];
    for (std::size_t j = 0; j < n; ++j) {
      system.jac[i * n + j] = model.gradMid[i * n + j];
      spread += model.gradRad[i * n + j] * model.radius[j];
    }
    system.mu[i] = model.valueMid[i];
    if (!shift.empty()) {
      // The shifted centre rounds once: its error joins the radius.
      system.mu[i] += shift[i];
      using std::abs;
      spread = (spread + widen[i] + 2 * ScalarTraits<S>::epsilon() * abs(system.mu[i])) * up;
    }
    system.rho[i] = spread * up + S(std::numeric_limits<double>::min());
    if (!isFinite(system.rho[i])) return false;
  }
  return true;
}

template <class S>
bool facetsOfModel(const LeafModel<S>& model, LinearizedSystem<S>& system, std::vector<char>& met) {
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  met.assign(2 * n, 1);
  if (!model.valid || n != m + 2) return false;
  if (!fillModelSystem(model, system, std::span<const S>(), std::span<const S>())) return false;
  return system.facetsMet(met);
}

template <class S>
bool bandExcluded(const LeafModel<S>& model, std::span<const S> level, LinearizedSystem<S>& system,
                  int multiplierSteps) {
  using std::abs;
  if (!model.valid) return false;
  const std::size_t m = model.valueMid.size();
  thread_local std::vector<S> shift, widen;
  shift.resize(m), widen.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    shift[i] = level[i] / 2;  // exact: a halving
    widen[i] = abs(shift[i]);
  }
  if (!fillModelSystem(model, system, std::span<const S>(shift), std::span<const S>(widen)))
    return false;
  const S up = S(1) + system.tolerance();
  S hh = 0;
  for (const S& h : system.h) hh += h * h;
  return system.excludes(hh * up, multiplierSteps);
}

template void centreAndRadius(const Box<double>& box, std::vector<double>& centre,
                              std::vector<double>& radius);
template void buildLeafModel(std::vector<MidRadEvaluator<double>>& evaluators,
                             const Box<double>& box, std::span<const double> level,
                             LeafModel<double>& model);
template void addFixedTerms(const LeafModel<double>& model, std::size_t i, const Box<double>& box,
                            std::span<const int> axes, int side, double& centre, double& magnitude,
                            double& radius);
template bool faceExcluded(const LeafModel<double>& model, const Box<double>& box,
                           std::span<const int> axes, int side);
template void buildFacePreconditioner(const LeafModel<double>& model, std::span<const int> axes,
                                      FacePreconditioner<double>& out);
template bool faceKrawczykExcludes(const LeafModel<double>& model,
                                   const FacePreconditioner<double>& pre, const Box<double>& box,
                                   std::span<const int> axes, int side);
template bool faceMultipliersExclude(const LeafModel<double>& model, const Box<double>& box,
                                     std::span<const int> axes, int side, int iterations);
template bool fillModelSystem(const LeafModel<double>& model, LinearizedSystem<double>& system,
                              std::span<const double> shift, std::span<const double> widen);
template bool facetsOfModel(const LeafModel<double>& model, LinearizedSystem<double>& system,
                            std::vector<char>& met);
template bool bandExcluded(const LeafModel<double>& model, std::span<const double> level,
                           LinearizedSystem<double>& system, int multiplierSteps);
template void centreAndRadius(const Box<Mpfr>& box, std::vector<Mpfr>& centre,
                              std::vector<Mpfr>& radius);
template void buildLeafModel(std::vector<MidRadEvaluator<Mpfr>>& evaluators, const Box<Mpfr>& box,
                             std::span<const Mpfr> level, LeafModel<Mpfr>& model);
template void addFixedTerms(const LeafModel<Mpfr>& model, std::size_t i, const Box<Mpfr>& box,
                            std::span<const int> axes, int side, Mpfr& centre, Mpfr& magnitude,
                            Mpfr& radius);
template bool faceExcluded(const LeafModel<Mpfr>& model, const Box<Mpfr>& box,
                           std::span<const int> axes, int side);
template void buildFacePreconditioner(const LeafModel<Mpfr>& model, std::span<const int> axes,
                                      FacePreconditioner<Mpfr>& out);
template bool faceKrawczykExcludes(const LeafModel<Mpfr>& model,
                                   const FacePreconditioner<Mpfr>& pre, const Box<Mpfr>& box,
                                   std::span<const int> axes, int side);
template bool faceMultipliersExclude(const LeafModel<Mpfr>& model, const Box<Mpfr>& box,
                                     std::span<const int> axes, int side, int iterations);
template bool fillModelSystem(const LeafModel<Mpfr>& model, LinearizedSystem<Mpfr>& system,
                              std::span<const Mpfr> shift, std::span<const Mpfr> widen);
template bool facetsOfModel(const LeafModel<Mpfr>& model, LinearizedSystem<Mpfr>& system,
                            std::vector<char>& met);
template bool bandExcluded(const LeafModel<Mpfr>& model, std::span<const Mpfr> level,
                           LinearizedSystem<Mpfr>& system, int multiplierSteps);

}  // namespace ndc
