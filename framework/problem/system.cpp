#include "framework/problem/system.hpp"

#include <algorithm>
#include <cmath>

#include "framework/numeric/iteration.hpp"
#include "framework/numeric/tape.hpp"

namespace ndc {

template <class S>
System<S>::System(const Problem& problem) : n_(problem.n()), equations_(problem.equations) {
  const Box<S> domain = problem.domainAs<S>();
  for (int j = 0; j < n_; ++j) origin_.push_back((domain.lo[j] + domain.hi[j]) / 2);
  // The quadratic forms: f and g at o, column l of H from the gradient at o + delta e_l.
  const auto n = static_cast<std::size_t>(n_);
  forms_.resize(equations_.size());
  for (std::size_t i = 0; i < equations_.size(); ++i) {
    const Tape& tape = equations_[i].tape();
    if (!tape.leaves().empty() || tape.totalDegree(3) > 2) continue;
    Form form;
    form.g.resize(n);
    form.f = evaluateTape<S>(tape, std::span<const S>(origin_), std::span<S>(form.g));
    std::vector<S> x = origin_, g(n);
    std::vector<S> h(n * n);
    for (std::size_t l = 0; l < n; ++l) {
      x[l] = origin_[l] + 1;
      const S delta = x[l] - origin_[l];
      evaluateTape<S>(tape, std::span<const S>(x), std::span<S>(g));
      x[l] = origin_[l];
      for (std::size_t j = 0; j < n; ++j) h[j * n + l] = (g[j] - form.g[j]) / delta;
    }
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t l = 0; l < n; ++l) {
        const S mid = (h[j * n + l] + h[l * n + j]) / 2;  // H is symmetric
        if (mid == 0) continue;
        form.row.push_back(static_cast<std::uint32_t>(j));
        form.column.push_back(static_cast<std::uint32_t>(l));
        form.h.push_back(mid);
      }
    bool finite = isFinite(form.f);
    for (const S& v : form.g) finite = finite && isFinite(v);
    for (const S& v : form.h) finite = finite && isFinite(v);
    if (finite) forms_[i] = std::move(form);
  }
}

template <class S>
S System<S>::evaluateForm(const Form& form, std::span<const S> x, std::span<S> gradient) const {
  // G = g + H d row by row, and F = f + sum_j d_j (g_j + G_j) / 2 (exact for a quadratic).
  S value = form.f;
  std::size_t t = 0;
  const std::size_t nonzeros = form.h.size();
  for (std::size_t j = 0; j < std::size_t(n_); ++j) {
    S g = form.g[j];
    for (; t < nonzeros && form.row[t] == j; ++t)
      g += form.h[t] * (x[form.column[t]] - origin_[form.column[t]]);
    value += (x[j] - origin_[j]) * (form.g[j] + g) / 2;
    if (!gradient.empty()) gradient[j] = g;
  }
  return value;
}

template <class S>
void System<S>::evaluate(std::span<const S> x, std::span<S> f) const {
  for (int i = 0; i < m(); ++i) {
    const Form& form = forms_[std::size_t(i)];
    f[i] = form.g.empty() ? equations_[i].template evaluate<S>(x) : evaluateForm(form, x, {});
  }
}

template <class S>
void System<S>::evaluate(std::span<const S> x, std::span<S> f, std::span<S> jacobian) const {
  for (int i = 0; i < m(); ++i) {
    const std::span<S> row = jacobian.subspan(std::size_t(i) * n_, n_);
    const Form& form = forms_[std::size_t(i)];
    f[i] = form.g.empty() ? equations_[i].template evaluate<S>(x, row) : evaluateForm(form, x, row);
  }
}

template <class S>
bool System<S>::hessianSpread(int i, std::span<const S> h, std::span<S> spread) const {
  using std::abs;
  const Form& form = forms_[std::size_t(i)];
  if (form.g.empty()) return false;
  std::fill(spread.begin(), spread.end(), S(0));
  for (std::size_t t = 0; t < form.h.size(); ++t)
    spread[form.row[t]] += abs(form.h[t]) * h[form.column[t]];
  return true;
}

template <class S>
S System<S>::hessianNorm(int i) const {
  using std::sqrt;
  const Form& form = forms_[std::size_t(i)];
  if (form.g.empty()) return S(-1);
  S sum = 0;
  for (const S& v : form.h) sum += v * v;
  return sqrt(sum);
}

template <class S>
S System<S>::maxResidual(std::span<const S> x) const {
  using std::abs;
  S worst = 0;
  // The programs themselves (not the quadratic forms): the reported residual is the one of the
  // equations as written.
  for (const auto& e : equations_) worst = std::max<S>(worst, abs(e.template evaluate<S>(x)));
  return worst;
}

template class System<double>;
template class System<Mpfr>;

}  // namespace ndc
