/// \file singular.hpp
/// Singular points of M: where the m x n Jacobian J of the constraints loses rank on the zero
/// set (docs/contracts.md 4.5 `diagnostics.singular_points` and section 6; see docs/singular.md).
///
/// Notation: F = (F_1..F_m) the constraints, J = DF (m x n), M = {F = 0} in the domain D,
/// sigma_min(J) and sigma_max(J) its extreme singular values. A point x of M is *singular*
/// when rank J(x) < m (a cone apex, a self-intersection, a pinch point, a tangency of two
/// sheets). s_i is the gradient scale of F_i (the largest |grad F_i| at the centres of the
/// solution cells) and `^J = diag(1/s) J` the Jacobian in those units.
#pragma once

#include <cstdint>
#include <vector>

#include "framework/mesh/complex.hpp"
#include "framework/numeric/box.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/summary.hpp"
#include "framework/problem/system.hpp"
#include "strategies/projection/projection.hpp"

namespace ndc {

/// Bounds on the work of findSingularPoints (the defaults are what the pipeline uses).
struct SingularOptions {
  /// At most this many points are reported (the most singular clusters first).
  int maxPoints = 64;
  /// Gauss-Newton starts tried per cluster of candidate cells before it is given up.
  int seedsPerCluster = 3;
  /// Gauss-Newton starts in all.
  int maxAttempts = 256;
  /// Clusters never extend over a block of the grid at this level (2^blockLevel blocks per
  /// axis, or the B-spline patches when they are smaller); the Lipschitz bounds of the first
  /// test are per block too.
  int blockLevel = 3;
  /// Gauss-Newton steps per start; 0: 40 + the working precision in bits.
  int maxIterations = 0;
};

/// What findSingularPoints found, and how much work each step did.
struct SingularSearch {
  std::vector<SingularPoint> points;     ///< located singular points, sorted by coordinates
  std::int64_t cells = 0;                ///< solution cells tested
  std::int64_t excludedByLipschitz = 0;  ///< full rank proven by the block Lipschitz bound
  std::int64_t excludedByEnclosure = 0;  ///< full rank proven by the cell's Bernstein enclosure
  std::int64_t candidates = 0;           ///< cells where rank deficiency could not be excluded
  std::int64_t clusters = 0;             ///< connected groups of candidate cells (within one block)
  std::int64_t attempts = 0;             ///< Gauss-Newton starts
  std::int64_t accepted = 0;             ///< starts that ended at a singular point (before merging)
};

/// Finds and locates the singular points of M from the solution cells of a run.
///
/// **1. Candidate cells** (every solution cell, two exclusion tests, cheapest first). Both use
/// Weyl's inequality: singular values move by at most the spectral norm of a perturbation, so
/// if `||DJ(x) - A||_2 <= r` for every x of the cell and `sigma_min(DA) > r`, then J has full
/// rank on the whole cell (D = diag(1/|grad F_i(c)|) is a row scaling at the cell centre c;
/// it does not change the rank and balances equations of different magnitudes).
///  - *Lipschitz test*: A = J(c). On the block holding the cell, the Bernstein coefficients of
///    the second derivatives bound the Hessian of each F_i entrywise; their Frobenius norm L_i
///    is a Lipschitz constant of grad F_i there, so `||D(J(x) - J(c))||_2 <= |x - c| ||D L||`.
///    One evaluation of J per cell: on a smooth manifold at a useful depth this excludes
///    almost every cell.
///  - *Enclosure test* (the cells left): the Bernstein form of each F_i on the cell (restricted
///    from the block) is differentiated along each axis; the coefficient ranges enclose every
///    entry of J on the cell (convex hull property, and tighter than interval arithmetic:
///    their excess over the true range is O(h^2)). With A the midpoint matrix and R the
///    radii, the test is `sigma_min(DA) > ||DR||_F`; for m = 1 a partial derivative whose
///    coefficients all have one strict sign also proves `grad F != 0` on the cell.
///  Both comparisons keep a relative margin of 1e-8 and an absolute one of 1e3 eps times the
///  magnitudes involved, so rounding can only make a cell a candidate, never exclude one. The
///  cells are closed boxes: a singular point on a face or a vertex of the grid (the apex of
///  x^2 + y^2 - z^2 at the origin of [-1, 1]^3) lies in every cell around it, and the strict
///  sign test keeps all of them.
///
/// **2. Clusters.** Candidate cells are grouped by face adjacency, never across a block (so a
/// curve of singular points, e.g. the double line of the Whitney umbrella, gives at most one
/// cluster per block it crosses, not one huge cluster). Each cell is scored by
/// `sigma_min(^J(p))` at its projected point p (the cell centre if Newton failed); clusters
/// are tried in the order of their best score.
///
/// **3. Location: Gauss-Newton on the augmented system** in the unknowns (x, v), v in R^m:
///
///     F(x)/s = 0,   ^J(x)^T v = 0,   (|v|^2 - 1)/2 = 0      (m + n + 1 equations, n + m unknowns)
///
/// started at the cell's p with v the left singular vector of sigma_min(^J(p)). Its solutions
/// are exactly the points of M where J^T has a unit null vector, i.e. rank J < m. It was chosen
/// over minimising `|F|^2 + sigma_min(J)^2` because that objective is not smooth where singular
/// values cross (and its minimum is flat in the degenerate cases below), while the augmented
/// system is polynomial and, at a nondegenerate singular point (cone apex, a transversal
/// self-intersection such as Viviani's double point), has a Jacobian of full column rank, so
/// Gauss-Newton converges quadratically. At degenerate points (two spheres touching: the
/// Hessian of F is rank 1 there) it converges linearly, which the iteration budget allows for.
/// The step is the minimum-norm least-squares step (complete orthogonal decomposition), with
/// backtracking on |G|; the Hessian of `v^T F(x)/s` in the Jacobian is formed by central
/// differences of J (step eps^(1/3) times the domain width): exact for quadratics, and for
/// any F its error only slows the convergence, it does not move the solution, which is decided
/// by the residual alone.
///
/// **Acceptance** of the final iterate x (all must hold):
///  - every `|F_i(x)| <= 64 tol_i(x) + d |grad F_i(x)| + d^2 s_i / w`, where tol_i is
///    the chosen projection's backward-error tolerance (`residualTolerance`; NewtonProjection's at
///    the working precision), w the largest
///    domain width and d = 64 eps w: x is within rounding of the domain size of a zero of F
///    (the extra terms matter only near x = 0, where tol_i vanishes with |F_i|(|x|));
///  - `sigma_min(^J(x)) <= tau`, tau = 1e-6 sqrt(eps / 2^-52): 1e-6 in double, about 5e-18 in
///    MPFR at 128 bits;
///  - x lies in the domain (closed, both the problem's and the grid's) and within one cell
///    of the cluster's cells (so each point is the one its candidate cells stand for).
///
/// **Merging and caps.** An accepted point closer than a cell width (on every axis) to one
/// already found is the same point: the one with the smaller `sigma_min(^J)` is kept. At most
/// one point per cluster, `seedsPerCluster` starts per cluster, `maxAttempts` starts and
/// `maxPoints` points in all. A singular curve is therefore reported as a bounded sample of
/// points on it (about one per block it crosses), not as the whole curve.
///
/// `projection` is the run's projection model (its residual tolerance decides acceptance);
/// `domain` is the grid's domain in S (`cells.grid.domain`, jitter applied). B-spline input
/// (`problem.roots`) is handled per patch, like the subdivision.
template <class S>
SingularSearch findSingularPoints(const Problem& problem, const System<S>& system,
                                  const Projection<S>& projection, const SolutionCells& cells,
                                  const Projections<S>& projections, const Box<S>& domain,
                                  const SingularOptions& options = {});

extern template SingularSearch findSingularPoints(const Problem&, const System<double>&,
                                                  const Projection<double>&, const SolutionCells&,
                                                  const Projections<double>&, const Box<double>&,
                                                  const SingularOptions&);
extern template SingularSearch findSingularPoints(const Problem&, const System<Mpfr>&,
                                                  const Projection<Mpfr>&, const SolutionCells&,
                                                  const Projections<Mpfr>&, const Box<Mpfr>&,
                                                  const SingularOptions&);

/// Joins the mesh at located singular points: the dual vertices within one cell width (on every
/// axis) of a point are given the coordinates of the one nearest to it, so that welding makes
/// them one vertex. The crossing connection builds the mesh of a perturbed level set F = c
/// (docs/crossing.md), which separates the branches of M at a singular point (Viviani's double
/// point into two arcs, a double cone into two sheets); joined there, the mesh meets itself at
/// the point as M does. The vertices keep their places on M (the nearest is one of them), so
/// `max_residual` stays at working precision. Returns the number of vertices moved.
template <class S>
std::int64_t joinAtSingularPoints(Complex<S>& complex, const std::vector<SingularPoint>& points,
                                  const Grid& grid);

extern template std::int64_t joinAtSingularPoints(Complex<double>&,
                                                  const std::vector<SingularPoint>&, const Grid&);
extern template std::int64_t joinAtSingularPoints(Complex<Mpfr>&, const std::vector<SingularPoint>&,
                                                  const Grid&);

}  // namespace ndc
