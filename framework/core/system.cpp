#include "framework/core/system.hpp"

#include <algorithm>
#include <cmath>

namespace ndc {

template <class S>
System<S>::System(const Problem& problem) : n_(problem.n()), equations_(problem.equations) {
  const Box<S> domain = problem.domainAs<S>();
  for (int j = 0; j < n_; ++j) origin_.push_back((domain.lo[j] + domain.hi[j]) / 2);
}

template <class S>
void System<S>::evaluate(std::span<const S> x, std::span<S> f) const {
  for (int i = 0; i < m(); ++i) f[i] = equations_[i].template evaluate<S>(x);
}

template <class S>
void System<S>::evaluate(std::span<const S> x, std::span<S> f, std::span<S> jacobian) const {
  for (int i = 0; i < m(); ++i) {
    f[i] = equations_[i].template evaluate<S>(x, jacobian.subspan(std::size_t(i) * n_, n_));
  }
}

template <class S>
S System<S>::maxResidual(std::span<const S> x) const {
  using std::abs;
  S worst = 0;
  for (const auto& e : equations_) worst = std::max<S>(worst, abs(e.template evaluate<S>(x)));
  return worst;
}

template class System<double>;
template class System<Mpfr>;

}  // namespace ndc
