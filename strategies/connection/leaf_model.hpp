/// \file leaf_model.hpp
/// An affine model of a system over a leaf of the crossing connection, from which the
/// enclosure of the system on each of the leaf's faces follows without an evaluation on the face
/// (docs/crossing.md, "Faces by evaluation").
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "framework/core/box.hpp"
#include "framework/core/midrad.hpp"
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

/// An affine model of the system F - level over a leaf X with centre c: by the mean value
/// theorem, F_i(c + d) - level_i lies in value_i + sum_j J_ij(X) d_j for every c + d in X. It
/// is built with one evaluation per equation, and then encloses F on each of the leaf's faces
/// in O(n) operations per equation (faceExcluded), where an evaluation on the face costs a
/// program run with its gradient: a leaf in R^n has 2 n (n - 1) faces of dimension n - 2 (for a
/// surface), and most of them do not meet M.
template <class S>
struct LeafModel {
  std::vector<S> centre, radius;      ///< of the leaf; radius rounded up
  std::vector<S> valueMid, valueRad;  ///< F(c) - level (m)
  std::vector<S> gradMid, gradRad;    ///< J(X), m x n, row-major
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
  for (std::size_t i = 0; i < m; ++i) {
    MidRadEvaluator<S>& e = evaluators[i];
    if (!e.run(std::span<const S>(model.centre), std::span<const S>(model.radius), true)) return;
    for (std::size_t j = 0; j < n; ++j) {
      model.gradMid[i * n + j] = e.mid(static_cast<int>(j) + 1);
      model.gradRad[i * n + j] = e.rad(static_cast<int>(j) + 1);
    }
    if (!e.run(std::span<const S>(model.centre), std::span<const S>(zero), false)) return;
    // The subtraction of the level rounds once: its error joins the radius.
    model.valueMid[i] = e.mid(0) - level[i];
    model.valueRad[i] = e.rad(0) + eps * abs(model.valueMid[i]);
  }
  model.valid = true;
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
  const S eps = 2 * ScalarTraits<S>::epsilon();
  const S gamma = S(8 * (n + m + 8)) * ScalarTraits<S>::epsilon();
  const S tiny = S(std::numeric_limits<double>::min());
  for (std::size_t i = 0; i < m; ++i) {
    const S* gm = &model.gradMid[i * n];
    const S* gr = &model.gradRad[i * n];
    S centre = model.valueMid[i], magnitude = abs(centre), radius = model.valueRad[i];
    for (std::size_t j = 0; j < n; ++j) {
      int t = 0;
      while (t < static_cast<int>(axes.size()) && axes[t] != static_cast<int>(j)) ++t;
      if (t == static_cast<int>(axes.size())) {
        radius += (abs(gm[j]) + gr[j]) * model.radius[j];
        continue;
      }
      const S x = (side >> t) & 1 ? box.hi[j] : box.lo[j];
      const S d = x - model.centre[j];  // rounded: off by at most eps |d|
      centre += gm[j] * d;
      magnitude += abs(gm[j] * d);
      radius += gr[j] * abs(d) + (abs(gm[j]) + gr[j]) * eps * abs(d);
    }
    magnitude += radius;
    if (abs(centre) > radius + gamma * magnitude + tiny) return true;
  }
  return false;
}

}  // namespace ndc
