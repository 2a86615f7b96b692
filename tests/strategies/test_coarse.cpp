// Coarse depths in the crossing connection: a coarser base grid never costs more work than a
// finer one, and certifies the same topology.
//
// The family is the scale benchmark's (bench/scale.py): the unit sphere of R^n cut by n - 1 - k
// hyperplanes with seeded random orthonormal normals and offsets in [-0.1, 0.1], a k-sphere, on
// [-1.2, 1.2]^n. Each is solved at depths 3 and 4 with the default refinement; both runs must be
// certified with the k-sphere's topology (1 component, chi 0 or 2, no defect), and the minimal
// faces solved (`topology.faces_solved`, the connection's work independent of the machine) at
// depth 3 at most those at depth 4. Before refineGraphFailures a coarse leaf solved every face
// before its graph test sent it to refinement: both seeds of the circle in R^13 and of the
// 2-sphere in R^8 below solved more faces at depth 3 than at depth 4 (4372 against 3101, 9372
// against 9001 for seed 1).
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "framework/problem/problem.hpp"
#include "pipeline/pipeline.hpp"
#include "tests/solve_support.hpp"
#include "tests/test_support.hpp"

namespace {

/// The k-sphere in R^n of `seed`: x.x = 1 and n - 1 - k hyperplanes a_i.x = b_i with orthonormal
/// a_i (the first columns of a random orthogonal matrix, std::mt19937).
ndc::Problem kSphere(int n, int k, std::uint32_t seed) {
  std::mt19937 rng(seed * 100 + n * 10 + k);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> offset(-0.1, 0.1);
  Eigen::MatrixXd g(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) g(i, j) = normal(rng);
  }
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(g).householderQ();
  std::vector<std::string> equations;
  std::ostringstream sphere;
  for (int j = 0; j < n; ++j) sphere << (j ? " + " : "") << "x" << j << "^2";
  equations.push_back(sphere.str() + " - 1");
  for (int i = 0; i < n - 1 - k; ++i) {
    std::ostringstream plane;
    plane.precision(17);
    for (int j = 0; j < n; ++j) plane << (j ? " + " : "") << "(" << q(j, i) << ")*x" << j;
    plane << " - (" << offset(rng) << ")";
    equations.push_back(plane.str());
  }
  return ndc::test::makeProblem(n, equations, 1.2);
}

using ndc::test::solveAt;

/// Certified with the k-sphere's topology.
void checkSphere(const ndc::RunResult& r, int k) {
  const auto& m = r.summary.mesh;
  CHECK(r.summary.topology.certified);
  CHECK(m.components == 1);
  CHECK(m.eulerCharacteristic == (k == 1 ? 0 : 2));
  CHECK(m.nonmanifoldEdges == 0);
  CHECK(m.boundaryEdges == 0);
  CHECK(m.openEnds == 0);
  CHECK(m.branchVertices == 0);
}

}  // namespace

TEMPLATE_TEST_CASE("coarse: a coarser grid solves no more faces and certifies the same sphere",
                   "[coarse]", NDC_SCALARS) {
  using S = TestType;
  constexpr bool kDouble = std::is_same_v<S, double>;
  struct Case {
    int n, k;
  };
  // MPFR costs about 30 times double: the small dimensions there.
  const std::vector<Case> cases = kDouble ? std::vector<Case>{{6, 1}, {13, 1}, {5, 2}, {8, 2}}
                                          : std::vector<Case>{{4, 1}, {4, 2}};
  for (const Case& c : cases) {
    for (std::uint32_t seed = 1; seed <= 2; ++seed) {
      const ndc::Problem problem = kSphere(c.n, c.k, seed);
      INFO("the " << c.k << "-sphere in R^" << c.n << ", seed " << seed);
      const ndc::RunResult coarse = solveAt<S>(problem, 3);
      const ndc::RunResult fine = solveAt<S>(problem, 4);
      checkSphere(coarse, c.k);
      checkSphere(fine, c.k);
      INFO("faces solved at depth 3: " << coarse.summary.topology.facesSolved
                                       << ", at depth 4: " << fine.summary.topology.facesSolved);
      CHECK(coarse.summary.topology.facesSolved > 0);
      CHECK(coarse.summary.topology.facesSolved <= fine.summary.topology.facesSolved);
    }
  }
}
