#include "pipeline/rank.hpp"

#include <boost/multiprecision/eigen.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <sstream>
#include <vector>

#include "framework/util/errors.hpp"

namespace ndc {

namespace {

template <class S>
using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;

/// sigma_min / sigma_max of the Jacobian at `x` with its rows scaled to unit length: 0 when a
/// row vanishes (that equation's gradient is 0 there).
template <class S>
double relativeSigma(const System<S>& system, std::span<const S> x, std::vector<S>& f,
                     std::vector<S>& jacobian) {
  const int m = system.m(), n = system.n();
  system.evaluate(x, f, jacobian);
  Matrix<S> a(m, n);
  for (int i = 0; i < m; ++i) {
    S norm = 0;
    for (int j = 0; j < n; ++j) norm += jacobian[i * n + j] * jacobian[i * n + j];
    if (!(norm > 0)) return 0;
    norm = sqrt(norm);
    for (int j = 0; j < n; ++j) a(i, j) = jacobian[i * n + j] / norm;
  }
  const auto sigma = Eigen::JacobiSVD<Matrix<S>>(a).singularValues();
  return static_cast<double>(sigma(sigma.size() - 1) / sigma(0));
}

}  // namespace

template <class S>
void checkRankOnM(const Problem& problem, const System<S>& system,
                  const Projections<S>& projections) {
  if (system.m() < 2) return;  // one equation cannot depend on others
  // The converged projections, and an even spread of at most kRankSamples of them. Newton
  // may converge nowhere when the equations are dependent (its steps solve with a singular
  // Jacobian): then the points it reached, each within its cell of M.
  std::vector<std::size_t> on;
  for (std::size_t c = 0; c < projections.converged.size(); ++c)
    if (projections.converged[c]) on.push_back(c);
  if (on.empty())
    for (std::size_t c = 0; c < projections.converged.size(); ++c) on.push_back(c);
  if (on.empty()) return;
  const std::size_t samples = std::min(on.size(), kRankSamples);
  std::vector<S> f(system.m()), jacobian(std::size_t(system.m()) * system.n());
  double largest = 0;
  for (std::size_t s = 0; s < samples; ++s) {
    const std::size_t c = on[s * on.size() / samples];
    largest = std::max(largest, relativeSigma(system, projections.at(c), f, jacobian));
    if (largest > kDependentSigma) return;  // one regular point: M is a k-manifold there
  }
  std::ostringstream line;
  line << problem.path << ": the equations are dependent on M: their Jacobian has rank below "
       << system.m() << " at every one of the " << samples << " points found near M (sigma_min / "
       << "sigma_max at most " << largest << "), so the zero set is not a " << problem.k()
       << "-manifold; remove the equations that follow from the others";
  throw InputError(line.str());
}

template void checkRankOnM(const Problem&, const System<double>&, const Projections<double>&);
template void checkRankOnM(const Problem&, const System<Mpfr>&, const Projections<Mpfr>&);

}  // namespace ndc
