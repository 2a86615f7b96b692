/// \file crossing.hpp
/// `crossing`: watertight dual contouring in any dimension (docs/crossing.md; beyond the paper).
#pragma once

#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"

namespace ndc {

/// Dual contouring generalised to k-manifolds in R^n (k = 1, 2). A generic k-manifold meets a
/// grid face of dimension m = n - k in isolated points: the roots of the square system of the
/// constraints restricted to the face. Each crossed m-face is shared by 2^k solution cells and
/// gives one dual k-cube on their vertices: an edge (k = 1) or a quad split into two triangles
/// along its shorter diagonal (k = 2). The crossings on the boundary of an (m+1)-face come in
/// pairs (the ends of the curve M ∩ face), so the result is closed mod 2, and a closed
/// manifold wherever every cell holds one simple piece of M. See \ref crossing.
class CrossingConnection final {
 public:
  /// Faces are halved at most this many times per free axis when a root is not proven unique.
  /// The level perturbation (docs/crossing.md) splits a fold or a double point of M into two
  /// crossings about sqrt(2^-26 h / h) = 2^-13 face widths apart: 16 halvings separate them.
  /// Where M is tangent to a face plane to higher order (the Krawczyk test then needs a box
  /// smaller than the face determinant, about c^(3/4) for a quartic contact) 20 halvings prove
  /// the root unique; the extra levels cost only on such faces.
  int maxFaceDepth = 20;

  /// The model's name, what it does, its parameters with their defaults and its capabilities
  /// (defined in crossing/spec.cpp, next to the model; the family's registry lists it in one line).
  static ModelSpec spec();
  /// The model with a spec's parameter values.
  static CrossingConnection create(const Parameters& parameters);

  template <class S>
  ConnectionOutput<S> connect(const ConnectionInput<S>& in) const;
};

}  // namespace ndc
