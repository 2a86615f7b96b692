/// \file leaf_model.hpp
/// An affine model of a system over a leaf of the crossing connection, from which the
/// enclosure of the system on each of the leaf's faces follows without an evaluation on the face
/// (docs/crossing.md, "Faces by evaluation").
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "framework/core/box.hpp"
#include "framework/core/inverse.hpp"
#include "framework/core/iteration.hpp"
#include "framework/core/linearised_system.hpp"
#include "framework/core/midrad.hpp"
#include "framework/core/multipliers.hpp"
#include "framework/core/parallel.hpp"
#include "framework/core/scalar.hpp"

namespace ndc {

/// Centre and radii (rounded up, so that centre +- radius holds the box) of `box`.
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

/// An affine model of the system F - level over a leaf X with centre c: F_i(c + d) - level_i
/// lies in value_i + sum_j S_ij d_j for every c + d in X, with slopes S_ij in gradMid +- gradRad:
/// J(X) by the mean value theorem, or, for an equation whose gradient is affine (total degree
/// 2, MidRadEvaluator::gradientAffine), its Taylor form grad F_i(c) + H_i d / 2, enclosed by the
/// gradient at c plus half of sum_l |H_jl| radius_l (MidRadEvaluator::gradientSpread, the radius
/// of J(X)): half the mean-value form's spread. Where H_i is proven semidefinite
/// (MidRadEvaluator::curvature) the slopes are the gradient at c alone and the one-sided remainder
/// d^T H_i d / 2 joins the value instead, half as wide again. Slopes, not derivatives, so the model
/// proves only that a face holds no zero (faceExcluded, faceKrawczykExcludes), never that a zero is
/// unique. It is built with one evaluation per equation, and then encloses F on each of the leaf's
/// faces in O(n) operations per equation (faceExcluded), where an evaluation on the face costs a
/// program run with its gradient: a leaf in R^n has 2 n (n - 1) faces of dimension n - 2 (for a
/// surface), and most of them do not meet M.
template <class S>
struct LeafModel {
  std::vector<S> centre, radius;      ///< of the leaf; radius rounded up
  std::vector<S> valueMid, valueRad;  ///< F(c) - level (m)
  std::vector<S> gradMid, gradRad;    ///< the slopes S, m x n, row-major
  bool valid = false;                 ///< every evaluation finite
};

/// Builds `model` of the system over `box` with `evaluators` (one per equation, scratch).
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

/// Adds the fixed axes' terms J_ij(X) d_j of equation i on the face of `box` (the model's
/// leaf) that fixes `axes` at the ends `side` (bit t: upper end of axes[t]) to an enclosure
/// kept as centre, magnitude (sum of the absolute terms, for the rounding bound) and radius.
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

/// True when the model proves that some F_i - level_i has no zero on the face of `box` (the model's
/// leaf) that fixes `axes` (its first k entries) at the ends `side` (bit t: upper end of axes[t]).
/// The fixed axes contribute J_ij(X) d_j with d_j the face's offset from the centre, the free ones
/// J_ij(X) [-radius_j, radius_j]; every floating-point sum is bounded by the standard gamma_p
/// margin.
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

/// The Krawczyk test of the faces of a leaf that fix one choice of k axes, from the leaf's
/// affine model: such a face has m free axes, as many as equations, and on it F - level is
/// g(d) = F(c) - level + J_fixed d_fixed + J_free d_free, d the offset from the leaf's centre
/// c (its free part ranging over D = [-radius, radius]). With Y an approximate inverse of the
/// midpoint of J_free, every zero of g in D lies in K = -Y g(0) + (I - Y J_free(X)) D, so a
/// face where K misses D holds none. Y and the spread (I - Y J_free(X)) D are shared by the 2^k
/// faces of the choice; each face costs O(m^2). Where single equations cannot exclude a face
/// (each F_i vanishes somewhere on it, near M but not on it), this decides with all of them
/// together, as solving the face would.
template <class S>
struct FacePreconditioner {
  std::vector<int> free;  ///< the free axes (m)
  std::vector<S> y;       ///< Y, m x m, row-major
  std::vector<S> spread;  ///< s_l >= sum_j |I - Y J_free(X)|_lj radius_j (rounded up)
  bool valid = false;
};

/// buildFacePreconditioner's working storage (threadScratch).
template <class S>
struct PreconditionerWork {
  std::vector<S> mid, inverse;  ///< m x m, column-major
};

/// Builds `out` for the faces of the model's leaf that fix `axes` (k of them).
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

/// True when the Krawczyk test of `pre` proves that F - level has no zero on the face of
/// `box` (the model's leaf) that fixes `axes` (its first k entries) at the ends `side` (bit t:
/// upper end of axes[t]).
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

/// faceMultipliersExclude's working storage (threadScratch).
template <class S>
struct FaceMultiplierWork {
  std::vector<S> jac, mu, rho, h;  ///< the face's linearisation: m x free, m, m, free
  MultiplierTest<S> test;
};

/// True when the multiplier test (framework/core/multipliers.hpp) proves that F - level has no
/// zero on the face of `box` (the model's leaf) that fixes `axes` (its first k entries) at the
/// ends `side`. On the face the model gives g(d) in mu + J_free d_free +- rho, with mu and the
/// fixed axes' part of rho as in faceKrawczykExcludes, J_free the slopes' midpoints on the free
/// axes and their radii times the free half-widths added to rho; the test decides this
/// linearisation exactly (up to its least-squares steps), where Krawczyk's preconditioned rows
/// are only some of its multipliers. `iterations` caps the least-squares steps.
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

/// Fills `system` (resized if needed) with the model's linearisation over its whole leaf:
/// J_c the slopes' midpoints, G the value widened by the slopes' radii times the half-widths,
/// the value's centre moved by `shift` and its radius widened by `widen` (per equation; empty:
/// none). Returns false when an entry is not finite.
template <class S>
bool fillModelSystem(const LeafModel<S>& model, LinearisedSystem<S>& system,
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

/// For a surface (k = 2): which facets of the model's leaf (fixed axis j at its lower end,
/// entry 2 j, or upper end, 2 j + 1) may hold a zero of F - level, into `met` (2 n entries, 1:
/// may), by the planar test of the model's linearisation over the whole leaf
/// (LinearisedSystem::facetsMet, fillModelSystem). A face of dimension n - 2 lies in two
/// facets, so one facet ruled out rules out its 2 (n - 1) faces, and a leaf M_c crosses near its
/// middle meets few facets: one O(n^2 m) test per leaf instead of a test per face
/// (docs/crossing.md, "Facets first"). Returns true when no point of the leaf is a zero; every
/// entry is 1 where nothing is proven.
template <class S>
bool facetsOfModel(const LeafModel<S>& model, LinearisedSystem<S>& system, std::vector<char>& met) {
  const std::size_t m = model.valueMid.size(), n = model.centre.size();
  met.assign(2 * n, 1);
  if (!model.valid || n != m + 2) return false;
  if (!fillModelSystem(model, system, std::span<const S>(), std::span<const S>())) return false;
  return system.facetsMet(met);
}

/// True when the model proves that no level set F = t level, t in [0, 1], meets its leaf (the
/// band from M to M_c, the model being of F - level): the value's centre moved by level / 2
/// and its radius widened by |level| / 2, then the linearised system's tests
/// (LinearisedSystem::excludes, `multiplierSteps` least-squares steps). Where it holds, the
/// leaf is empty in the sense of the Bernstein coefficients' test (docs/crossing.md, "Empty
/// leaves by the model"), which then need not be restricted to the leaf.
template <class S>
bool bandExcluded(const LeafModel<S>& model, std::span<const S> level, LinearisedSystem<S>& system,
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

}  // namespace ndc
