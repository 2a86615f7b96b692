/// \file leaf_model.hpp
/// An affine model of a system over a leaf of the crossing connection, from which the
/// enclosure of the system on each of the leaf's faces follows without an evaluation on the face
/// (docs/crossing.md, "Faces by evaluation").
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "framework/numeric/box.hpp"
#include "framework/numeric/linearized_system.hpp"
#include "framework/numeric/midrad.hpp"
#include "framework/numeric/scalar.hpp"

namespace ndc {

/// Centre and radii (rounded up, so that centre +- radius holds the box) of `box`.
template <class S>
void centreAndRadius(const Box<S>& box, std::vector<S>& centre, std::vector<S>& radius);

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
                    std::span<const S> level, LeafModel<S>& model);

/// Adds the fixed axes' terms J_ij(X) d_j of equation i on the face of `box` (the model's
/// leaf) that fixes `axes` at the ends `side` (bit t: upper end of axes[t]) to an enclosure
/// kept as centre, magnitude (sum of the absolute terms, for the rounding bound) and radius.
template <class S>
void addFixedTerms(const LeafModel<S>& model, std::size_t i, const Box<S>& box,
                   std::span<const int> axes, int side, S& centre, S& magnitude, S& radius);

/// True when the model proves that some F_i - level_i has no zero on the face of `box` (the model's
/// leaf) that fixes `axes` (its first k entries) at the ends `side` (bit t: upper end of axes[t]).
/// The fixed axes contribute J_ij(X) d_j with d_j the face's offset from the centre, the free ones
/// J_ij(X) [-radius_j, radius_j]; every floating-point sum is bounded by the standard gamma_p
/// margin.
template <class S>
bool faceExcluded(const LeafModel<S>& model, const Box<S>& box, std::span<const int> axes,
                  int side);

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

/// Builds `out` for the faces of the model's leaf that fix `axes` (k of them).
template <class S>
void buildFacePreconditioner(const LeafModel<S>& model, std::span<const int> axes,
                             FacePreconditioner<S>& out);

/// True when the Krawczyk test of `pre` proves that F - level has no zero on the face of
/// `box` (the model's leaf) that fixes `axes` (its first k entries) at the ends `side` (bit t:
/// upper end of axes[t]).
template <class S>
bool faceKrawczykExcludes(const LeafModel<S>& model, const FacePreconditioner<S>& pre,
                          const Box<S>& box, std::span<const int> axes, int side);

/// True when the multiplier test (framework/numeric/multipliers.hpp) proves that F - level has no
/// zero on the face of `box` (the model's leaf) that fixes `axes` (its first k entries) at the
/// ends `side`. On the face the model gives g(d) in mu + J_free d_free +- rho, with mu and the
/// fixed axes' part of rho as in faceKrawczykExcludes, J_free the slopes' midpoints on the free
/// axes and their radii times the free half-widths added to rho; the test decides this
/// linearisation exactly (up to its least-squares steps), where Krawczyk's preconditioned rows
/// are only some of its multipliers. `iterations` caps the least-squares steps.
template <class S>
bool faceMultipliersExclude(const LeafModel<S>& model, const Box<S>& box, std::span<const int> axes,
                            int side, int iterations);

/// Fills `system` (resized if needed) with the model's linearisation over its whole leaf:
/// J_c the slopes' midpoints, G the value widened by the slopes' radii times the half-widths,
/// the value's centre moved by `shift` and its radius widened by `widen` (per equation; empty:
/// none). Returns false when an entry is not finite.
template <class S>
bool fillModelSystem(const LeafModel<S>& model, LinearizedSystem<S>& system,
                     std::span<const S> shift, std::span<const S> widen);

/// For a surface (k = 2): which facets of the model's leaf (fixed axis j at its lower end,
/// entry 2 j, or upper end, 2 j + 1) may hold a zero of F - level, into `met` (2 n entries, 1:
/// may), by the planar test of the model's linearisation over the whole leaf
/// (LinearizedSystem::facetsMet, fillModelSystem). A face of dimension n - 2 lies in two
/// facets, so one facet ruled out rules out its 2 (n - 1) faces, and a leaf M_c crosses near its
/// middle meets few facets: one O(n^2 m) test per leaf instead of a test per face
/// (docs/crossing.md, "Facets first"). Returns true when no point of the leaf is a zero; every
/// entry is 1 where nothing is proven.
template <class S>
bool facetsOfModel(const LeafModel<S>& model, LinearizedSystem<S>& system, std::vector<char>& met);

/// True when the model proves that no level set F = t level, t in [0, 1], meets its leaf (the
/// band from M to M_c, the model being of F - level): the value's centre moved by level / 2
/// and its radius widened by |level| / 2, then the linearized system's tests
/// (LinearizedSystem::excludes, `multiplierSteps` least-squares steps). Where it holds, the
/// leaf is empty in the sense of the Bernstein coefficients' test (docs/crossing.md, "Empty
/// leaves by the model"), which then need not be restricted to the leaf.
template <class S>
bool bandExcluded(const LeafModel<S>& model, std::span<const S> level, LinearizedSystem<S>& system,
                  int multiplierSteps);

extern template void centreAndRadius(const Box<double>& box, std::vector<double>& centre,
                                     std::vector<double>& radius);
extern template void buildLeafModel(std::vector<MidRadEvaluator<double>>& evaluators,
                                    const Box<double>& box, std::span<const double> level,
                                    LeafModel<double>& model);
extern template void addFixedTerms(const LeafModel<double>& model, std::size_t i,
                                   const Box<double>& box, std::span<const int> axes, int side,
                                   double& centre, double& magnitude, double& radius);
extern template bool faceExcluded(const LeafModel<double>& model, const Box<double>& box,
                                  std::span<const int> axes, int side);
extern template void buildFacePreconditioner(const LeafModel<double>& model,
                                             std::span<const int> axes,
                                             FacePreconditioner<double>& out);
extern template bool faceKrawczykExcludes(const LeafModel<double>& model,
                                          const FacePreconditioner<double>& pre,
                                          const Box<double>& box, std::span<const int> axes,
                                          int side);
extern template bool faceMultipliersExclude(const LeafModel<double>& model, const Box<double>& box,
                                            std::span<const int> axes, int side, int iterations);
extern template bool fillModelSystem(const LeafModel<double>& model,
                                     LinearizedSystem<double>& system,
                                     std::span<const double> shift, std::span<const double> widen);
extern template bool facetsOfModel(const LeafModel<double>& model, LinearizedSystem<double>& system,
                                   std::vector<char>& met);
extern template bool bandExcluded(const LeafModel<double>& model, std::span<const double> level,
                                  LinearizedSystem<double>& system, int multiplierSteps);
extern template void centreAndRadius(const Box<Mpfr>& box, std::vector<Mpfr>& centre,
                                     std::vector<Mpfr>& radius);
extern template void buildLeafModel(std::vector<MidRadEvaluator<Mpfr>>& evaluators,
                                    const Box<Mpfr>& box, std::span<const Mpfr> level,
                                    LeafModel<Mpfr>& model);
extern template void addFixedTerms(const LeafModel<Mpfr>& model, std::size_t i,
                                   const Box<Mpfr>& box, std::span<const int> axes, int side,
                                   Mpfr& centre, Mpfr& magnitude, Mpfr& radius);
extern template bool faceExcluded(const LeafModel<Mpfr>& model, const Box<Mpfr>& box,
                                  std::span<const int> axes, int side);
extern template void buildFacePreconditioner(const LeafModel<Mpfr>& model,
                                             std::span<const int> axes,
                                             FacePreconditioner<Mpfr>& out);
extern template bool faceKrawczykExcludes(const LeafModel<Mpfr>& model,
                                          const FacePreconditioner<Mpfr>& pre, const Box<Mpfr>& box,
                                          std::span<const int> axes, int side);
extern template bool faceMultipliersExclude(const LeafModel<Mpfr>& model, const Box<Mpfr>& box,
                                            std::span<const int> axes, int side, int iterations);
extern template bool fillModelSystem(const LeafModel<Mpfr>& model, LinearizedSystem<Mpfr>& system,
                                     std::span<const Mpfr> shift, std::span<const Mpfr> widen);
extern template bool facetsOfModel(const LeafModel<Mpfr>& model, LinearizedSystem<Mpfr>& system,
                                   std::vector<char>& met);
extern template bool bandExcluded(const LeafModel<Mpfr>& model, std::span<const Mpfr> level,
                                  LinearizedSystem<Mpfr>& system, int multiplierSteps);

}  // namespace ndc
