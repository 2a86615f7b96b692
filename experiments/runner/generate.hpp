/// \file generate.hpp
/// Generated test problems for experiments (docs/experiments.md): manifolds of known topology
/// embedded in R^n by a random rotation, so that a sweep over n measures how the method
/// behaves with the ambient dimension alone (`fig-degeneracy-vs-n`).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ndc {

/// Names of the problem generators, as written in experiment configs (`generator = ...`).
///  - `rotated-circle`: the circle y0^2 + y1^2 = r^2, y2 = ... = y_{n-1} = 0 (k = 1, n >= 2);
///  - `rotated-sphere`: the 2-sphere y0^2 + y1^2 + y2^2 = r^2, y3 = ... = 0 (k = 2, n >= 3);
/// with y = Q (x - c), Q a random orthogonal matrix and c a small random offset.
inline constexpr std::array<std::string_view, 2> kGeneratorNames = {"rotated-circle",
                                                                    "rotated-sphere"};
/// Largest ambient dimension a generator accepts (the quadric has 3^n Bernstein coefficients,
/// past R^12 over the reader's cap; it needs no dense form, ndc::densityFree).
inline constexpr int kMaxGeneratedDimension = 16;

/// A generated problem: its problem file text (docs/contracts.md 4.1) and the embedding it encodes.
struct GeneratedProblem {
  std::string name;  ///< `<generator>-n<n>-s<seed>`, e.g. `rotated-circle-n5-s3`
  std::string text;  ///< the TOML problem file
  int n = 0;         ///< ambient dimension
  int k = 0;         ///< manifold dimension: 1 (circle) or 2 (sphere)
  double radius = 1;
  std::vector<double> rotation;  ///< Q, n x n, row-major
  std::vector<double> offset;    ///< c, n entries
  /// Expected topology: one component, Euler characteristic 0 (circle) or 2 (sphere).
  long components = 1, eulerCharacteristic = 0;
};

/// Smallest ambient dimension of a generator (2 for rotated-circle, 3 for rotated-sphere);
/// 0 for an unknown name.
int generatorMinDimension(std::string_view generator);

/// Generates the problem of `generator` in dimension n from `seed`. Deterministic on every
/// platform: the random numbers come from std::mt19937_64 (whose output the standard fixes)
/// through our own transforms, not the implementation-defined standard distributions.
/// Throws std::invalid_argument for an unknown generator or n outside
/// [generatorMinDimension, kMaxGeneratedDimension].
GeneratedProblem generateProblem(std::string_view generator, int n, std::uint64_t seed);

/// The point x = c + Q^T y of the manifold with y = r (u, 0, ..., 0), for a unit vector u of
/// k + 1 entries (u = (cos t, sin t) on the circle).
std::vector<double> generatedPoint(const GeneratedProblem& problem, std::span<const double> u);

}  // namespace ndc
