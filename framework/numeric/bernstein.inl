// Template bodies of Bernstein<S>. Included only by bernstein.cpp, which instantiates them for
// double and Mpfr; users of bernstein.hpp never compile this file.
#pragma once

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "framework/numeric/bernstein.hpp"

namespace ndc {
namespace bernstein_detail {

// Scalars are passed by value for double (keeps them in registers, no aliasing with the
// coefficient arrays) and by reference for Mpfr.
template <class S>
using In = std::conditional_t<std::is_same_v<S, double>, double, const S&>;

// Per-thread temporaries for the allocation-free paths (evaluate, split, halve): Mpfr objects
// are reused by assignment, which copies the precision of the source.
template <class S>
struct Scratch {
  S t, omt, w, tmp;
  std::vector<S> buffer;
};

template <class S>
Scratch<S>& scratch() {
  thread_local Scratch<S> s;
  return s;
}

// dst = src, rounded to the working precision (a plain Mpfr assignment would copy the
// precision of src, which may be lower, e.g. for a domain bound read from a file).
template <class S>
void setWorking(S& dst, const S& src) {
  if constexpr (std::is_same_v<S, double>) {
    dst = src;
  } else {
    const auto bits = static_cast<mpfr_prec_t>(mpfrPrecision());
    if (mpfr_get_prec(dst.backend().data()) != bits) mpfr_set_prec(dst.backend().data(), bits);
    mpfr_set(dst.backend().data(), src.backend().data(), MPFR_RNDN);
  }
}

// out = 1 - t at the working precision, in place.
template <class S>
void oneMinus(const S& t, S& out) {
  setWorking(out, t);
  out -= 1;
  if constexpr (std::is_same_v<S, double>)
    out = -out;
  else
    out.backend().negate();
}

// target = wt * target + wo * other, without temporaries for Mpfr.
template <class S>
inline void combine(S& target, In<S> wt, const S& other, In<S> wo, S& tmp) {
  if constexpr (std::is_same_v<S, double>) {
    target = wt * target + wo * other;
  } else {
    target *= wt;
    tmp = other;
    tmp *= wo;
    target += tmp;
  }
}

// target = (target + other) / 2.
template <class S>
inline void average(S& target, const S& other) {
  if constexpr (std::is_same_v<S, double>) {
    target = (target + other) * 0.5;
  } else {
    target += other;
    target /= 2;
  }
}

// The coefficient array seen along one axis: `outer` blocks, each of d + 1 contiguous slabs of
// `st` coefficients (st = stride of the axis). Slab i of a block holds the coefficients with
// index i along the axis.
struct Slabs {
  std::size_t outer;
  int d;
  std::size_t st;
  std::size_t block() const { return st * static_cast<std::size_t>(d + 1); }
};

inline Slabs slabsOf(const std::vector<int>& degrees, std::size_t size, int axis) {
  std::size_t st = 1;
  for (int j = 0; j < axis; ++j) st *= static_cast<std::size_t>(degrees[j] + 1);
  const int d = degrees[axis];
  return {size / (st * static_cast<std::size_t>(d + 1)), d, st};
}

// de Casteljau along the slab axis, in place: `c` becomes the right part (on [t, 1]); if `left`
// is not null it receives the left part (on [0, t]). kHalf specialises to t = 1/2.
// Level k updates positions 0..d-k in ascending order, so position j ends with b_j^{(d-j)}
// (the right edge of the triangle) and position 0 after level k is b_0^{(k)} (the left edge).
template <bool kHalf, class S>
void deCasteljauRight(S* c, S* left, const Slabs& sl, In<S> t, In<S> omt, S& tmp) {
  const std::size_t block = sl.block();
  for (std::size_t o = 0; o < sl.outer; ++o) {
    S* b = c + o * block;
    S* l = left ? left + o * block : nullptr;
    if (l) std::copy(b, b + sl.st, l);
    for (int k = 1; k <= sl.d; ++k) {
      for (int i = 0; i <= sl.d - k; ++i) {
        S* bi = b + static_cast<std::size_t>(i) * sl.st;
        const S* bn = bi + sl.st;
        for (std::size_t s = 0; s < sl.st; ++s) {
          if constexpr (kHalf)
            average(bi[s], bn[s]);
          else
            combine<S>(bi[s], omt, bn[s], t, tmp);
        }
      }
      if (l) std::copy(b, b + sl.st, l + static_cast<std::size_t>(k) * sl.st);
    }
  }
}

// de Casteljau along the slab axis, in place, keeping the left part (on [0, t]): level k
// updates positions d..k in descending order, so position k ends with b_0^{(k)}.
template <class S>
void deCasteljauLeft(S* c, const Slabs& sl, In<S> t, In<S> omt, S& tmp) {
  const std::size_t block = sl.block();
  for (std::size_t o = 0; o < sl.outer; ++o) {
    S* b = c + o * block;
    for (int k = 1; k <= sl.d; ++k) {
      for (int i = sl.d; i >= k; --i) {
        S* bi = b + static_cast<std::size_t>(i) * sl.st;
        const S* bp = bi - sl.st;
        for (std::size_t s = 0; s < sl.st; ++s) combine<S>(bi[s], t, bp[s], omt, tmp);
      }
    }
  }
}

// Applies the (m x (d+1)) row-major matrix M to every fiber along the slab axis.
template <class S>
std::vector<S> transformAxis(const std::vector<S>& c, const Slabs& sl, int m,
                             const std::vector<S>& M) {
  const std::size_t block = sl.block();
  const std::size_t outBlock = sl.st * static_cast<std::size_t>(m);
  std::vector<S> out(sl.outer * outBlock, S(0));
  for (std::size_t o = 0; o < sl.outer; ++o) {
    for (int r = 0; r < m; ++r) {
      S* dst = out.data() + o * outBlock + static_cast<std::size_t>(r) * sl.st;
      for (int i = 0; i <= sl.d; ++i) {
        const S& w = M[static_cast<std::size_t>(r) * (sl.d + 1) + i];
        if (w == 0) continue;
        const S* src = c.data() + o * block + static_cast<std::size_t>(i) * sl.st;
        for (std::size_t s = 0; s < sl.st; ++s) dst[s] += w * src[s];
      }
    }
  }
  return out;
}

// Row n of Pascal's triangle (exact in S for the degrees used here).
template <class S>
std::vector<S> binomialRow(int n) {
  std::vector<S> row(static_cast<std::size_t>(n) + 1, S(1));
  for (int i = 1; i < n; ++i)
    for (int k = i; k >= 1; --k) row[k] += row[k - 1];
  return row;
}

// Visits every multi-index of a tensor with the given degrees in linear order (variable 0
// fastest), calling f(linearIndex, multiIndex).
template <class F>
void forEachIndex(const std::vector<int>& degrees, std::size_t size, F&& f) {
  std::vector<int> idx(degrees.size(), 0);
  for (std::size_t lin = 0; lin < size; ++lin) {
    f(lin, idx);
    for (std::size_t j = 0; j < idx.size(); ++j) {
      if (++idx[j] <= degrees[j]) break;
      idx[j] = 0;
    }
  }
}

template <class S>
bool sameBox(const Box<S>& a, const Box<S>& b) {
  return a.lo == b.lo && a.hi == b.hi;
}

}  // namespace bernstein_detail

template <class S>
Bernstein<S>::Bernstein(Box<S> domain, std::vector<int> degrees)
    : domain_(std::move(domain)), degrees_(std::move(degrees)) {
  if (domain_.lo.size() != degrees_.size() || domain_.hi.size() != degrees_.size())
    throw std::invalid_argument("Bernstein: domain and degrees differ in dimension");
  std::size_t n = 1;
  for (std::size_t j = 0; j < degrees_.size(); ++j) {
    if (degrees_[j] < 0) throw std::invalid_argument("Bernstein: negative degree");
    if (!(domain_.lo[j] < domain_.hi[j]))
      throw std::invalid_argument("Bernstein: empty domain along axis " + std::to_string(j));
    n *= static_cast<std::size_t>(degrees_[j] + 1);
  }
  coefficients_.assign(n, S(0));
}

template <class S>
Bernstein<S> Bernstein<S>::constant(const Box<S>& domain, const S& value) {
  Bernstein p(domain, std::vector<int>(domain.lo.size(), 0));
  p.coefficients_[0] = value;
  return p;
}

template <class S>
Bernstein<S> Bernstein<S>::variable(const Box<S>& domain, int axis) {
  if (axis < 0 || axis >= domain.dim())
    throw std::invalid_argument("Bernstein::variable: bad axis " + std::to_string(axis));
  std::vector<int> degrees(domain.lo.size(), 0);
  degrees[axis] = 1;
  Bernstein p(domain, std::move(degrees));
  // x = lo (1 - t) + hi t
  p.coefficients_[0] = domain.lo[axis];
  p.coefficients_[1] = domain.hi[axis];
  return p;
}

template <class S>
std::size_t Bernstein<S>::stride(int j) const {
  if (j < 0 || j >= dim())
    throw std::invalid_argument("Bernstein::stride: bad axis " + std::to_string(j));
  std::size_t st = 1;
  for (int i = 0; i < j; ++i) st *= static_cast<std::size_t>(degrees_[i] + 1);
  return st;
}

template <class S>
const S& Bernstein<S>::coefficient(std::span<const int> index) const {
  if (static_cast<int>(index.size()) != dim())
    throw std::invalid_argument("Bernstein::coefficient: index has the wrong size");
  std::size_t lin = 0, st = 1;
  for (int j = 0; j < dim(); ++j) {
    if (index[j] < 0 || index[j] > degrees_[j])
      throw std::invalid_argument("Bernstein::coefficient: index out of range");
    lin += static_cast<std::size_t>(index[j]) * st;
    st *= static_cast<std::size_t>(degrees_[j] + 1);
  }
  return coefficients_[lin];
}

template <class S>
S& Bernstein<S>::coefficient(std::span<const int> index) {
  return const_cast<S&>(std::as_const(*this).coefficient(index));
}

template <class S>
S Bernstein<S>::evaluate(std::span<const S> x) const {
  using namespace bernstein_detail;
  if (static_cast<int>(x.size()) != dim())
    throw std::invalid_argument("Bernstein::evaluate: point has the wrong dimension");
  if (dim() == 0) return coefficients_[0];
  auto& sc = scratch<S>();
  std::vector<S>& buf = sc.buffer;
  if (buf.size() < size()) buf.resize(size());
  std::copy(coefficients_.begin(), coefficients_.end(), buf.begin());
  // Reduce the slowest axis first: each reduction leaves a contiguous tensor of the lower axes.
  std::size_t len = size();
  for (int a = dim() - 1; a >= 0; --a) {
    const int d = degrees_[a];
    const std::size_t st = len / static_cast<std::size_t>(d + 1);
    if (d > 0) {
      // t = (x - lo) / w and 1 - t = (hi - x) / w, at the working precision.
      setWorking(sc.w, domain_.hi[a]);
      sc.w -= domain_.lo[a];
      setWorking(sc.t, x[a]);
      sc.t -= domain_.lo[a];
      sc.t /= sc.w;
      setWorking(sc.omt, domain_.hi[a]);
      sc.omt -= x[a];
      sc.omt /= sc.w;
      deCasteljauRight<false, S>(buf.data(), nullptr, Slabs{1, d, st}, sc.t, sc.omt, sc.tmp);
    }
    len = st;
  }
  return buf[0];
}

template <class S>
Bernstein<S> Bernstein<S>::derivative(int axis) const {
  using namespace bernstein_detail;
  if (axis < 0 || axis >= dim())
    throw std::invalid_argument("Bernstein::derivative: bad axis " + std::to_string(axis));
  const int d = degrees_[axis];
  Bernstein r;
  r.domain_ = domain_;
  r.degrees_ = degrees_;
  if (d == 0) {
    r.coefficients_.assign(size(), S(0));
    return r;
  }
  r.degrees_[axis] = d - 1;
  // d (b_{i+1} - b_i) / (hi - lo): differences first, then one scaling.
  std::vector<S> M(static_cast<std::size_t>(d) * (d + 1), S(0));
  for (int i = 0; i < d; ++i) {
    M[static_cast<std::size_t>(i) * (d + 1) + i] = -1;
    M[static_cast<std::size_t>(i) * (d + 1) + i + 1] = 1;
  }
  r.coefficients_ = transformAxis(coefficients_, slabsOf(degrees_, size(), axis), d, M);
  const S scale = S(d) / domain_.width(axis);
  for (S& c : r.coefficients_) c *= scale;
  return r;
}

template <class S>
void Bernstein<S>::split(int axis, const S& t, Bernstein& left, Bernstein& right) const {
  using namespace bernstein_detail;
  if (axis < 0 || axis >= dim())
    throw std::invalid_argument("Bernstein::split: bad axis " + std::to_string(axis));
  if (!(t > 0 && t < 1)) throw std::invalid_argument("Bernstein::split: t must be in (0, 1)");
  if (&left == &right) throw std::invalid_argument("Bernstein::split: left and right alias");
  if (&left == this || &right == this) {
    const Bernstein copy(*this);
    copy.split(axis, t, left, right);
    return;
  }
  // Outputs take this shape by element-wise assignment (no allocation when sizes match).
  for (Bernstein* out : {&left, &right}) {
    out->degrees_ = degrees_;
    out->domain_.lo = domain_.lo;
    out->domain_.hi = domain_.hi;
    if (out->coefficients_.size() != size()) out->coefficients_.resize(size());
  }
  std::copy(coefficients_.begin(), coefficients_.end(), right.coefficients_.begin());
  auto& sc = scratch<S>();
  oneMinus(t, sc.omt);
  deCasteljauRight<false, S>(right.coefficients_.data(), left.coefficients_.data(),
                             slabsOf(degrees_, size(), axis), t, sc.omt, sc.tmp);
  // Split point lo + t (hi - lo), in place, at the working precision.
  S& m = left.domain_.hi[axis];
  setWorking(m, domain_.hi[axis]);
  m -= domain_.lo[axis];
  m *= t;
  m += domain_.lo[axis];
  right.domain_.lo[axis] = m;
}

template <class S>
void Bernstein<S>::halve(int axis, Bernstein& left, Bernstein& right) const {
  using namespace bernstein_detail;
  if (axis < 0 || axis >= dim())
    throw std::invalid_argument("Bernstein::halve: bad axis " + std::to_string(axis));
  if (&left == &right) throw std::invalid_argument("Bernstein::halve: left and right alias");
  if (&left == this || &right == this) {
    const Bernstein copy(*this);
    copy.halve(axis, left, right);
    return;
  }
  for (Bernstein* out : {&left, &right}) {
    out->degrees_ = degrees_;
    out->domain_.lo = domain_.lo;
    out->domain_.hi = domain_.hi;
    if (out->coefficients_.size() != size()) out->coefficients_.resize(size());
  }
  std::copy(coefficients_.begin(), coefficients_.end(), right.coefficients_.begin());
  auto& sc = scratch<S>();
  // t is unused by the averaging kernel.
  deCasteljauRight<true, S>(right.coefficients_.data(), left.coefficients_.data(),
                            slabsOf(degrees_, size(), axis), domain_.lo[axis], domain_.lo[axis],
                            sc.tmp);
  S& m = left.domain_.hi[axis];
  setWorking(m, domain_.lo[axis]);
  m += domain_.hi[axis];
  m /= 2;
  right.domain_.lo[axis] = m;
}

template <class S>
Bernstein<S> Bernstein<S>::restrict(const Box<S>& sub) const {
  Bernstein r;
  restrictInto(sub, r);
  return r;
}

template <class S>
void Bernstein<S>::restrictInto(const Box<S>& sub, Bernstein& r) const {
  using namespace bernstein_detail;
  using std::abs;
  if (sub.lo.size() != static_cast<std::size_t>(dim()) ||
      sub.hi.size() != static_cast<std::size_t>(dim()))
    throw std::invalid_argument("Bernstein::restrict: sub-box has the wrong dimension");
  for (int a = 0; a < dim(); ++a)
    if (!(sub.lo[a] < sub.hi[a]))
      throw std::invalid_argument("Bernstein::restrict: empty sub-box along axis " +
                                  std::to_string(a));
  r = *this;  // vectors assigned in place: no allocation when r has the size already
  S tmp;
  for (int a = 0; a < dim(); ++a) {
    const S &lo = domain_.lo[a], &hi = domain_.hi[a], &sa = sub.lo[a], &sb = sub.hi[a];
    if (degrees_[a] == 0 || (sa == lo && sb == hi)) continue;
    const Slabs sl = slabsOf(degrees_, size(), a);
    const S w = hi - lo;
    // Two splits; the second divides by the length of the kept piece, so keep the longer one
    // first (both orders are exact in exact arithmetic, also outside the domain).
    if (abs(hi - sa) >= abs(sb - lo)) {
      // Keep [sa, hi], then its part [sa, sb].
      deCasteljauRight<false, S>(r.coefficients_.data(), nullptr, sl, S((sa - lo) / w),
                                 S((hi - sa) / w), tmp);
      const S w2 = hi - sa;
      deCasteljauLeft<S>(r.coefficients_.data(), sl, S((sb - sa) / w2), S((hi - sb) / w2), tmp);
    } else {
      // Keep [lo, sb], then its part [sa, sb].
      deCasteljauLeft<S>(r.coefficients_.data(), sl, S((sb - lo) / w), S((hi - sb) / w), tmp);
      const S w2 = sb - lo;
      deCasteljauRight<false, S>(r.coefficients_.data(), nullptr, sl, S((sa - lo) / w2),
                                 S((sb - sa) / w2), tmp);
    }
  }
  r.domain_ = sub;
}

template <class S>
Bernstein<S> Bernstein<S>::faceSlice(int axis, bool upper) const {
  Bernstein r;
  faceSliceInto(axis, upper, r);
  return r;
}

template <class S>
void Bernstein<S>::faceSliceInto(int axis, bool upper, Bernstein& r) const {
  using namespace bernstein_detail;
  if (axis < 0 || axis >= dim())
    throw std::invalid_argument("Bernstein::faceSlice: bad axis " + std::to_string(axis));
  if (&r == this) throw std::invalid_argument("Bernstein::faceSliceInto: output is the input");
  // Every vector assigned in place: no allocation when r has the slice's sizes already.
  const auto dropAxis = [axis](const auto& from, auto& to) {
    to.assign(from.begin(), from.begin() + axis);
    to.insert(to.end(), from.begin() + axis + 1, from.end());
  };
  dropAxis(domain_.lo, r.domain_.lo);
  dropAxis(domain_.hi, r.domain_.hi);
  dropAxis(degrees_, r.degrees_);
  // The boundary slab i_axis = 0 or d is the coefficient tensor of the face.
  const Slabs sl = slabsOf(degrees_, size(), axis);
  const std::size_t k = upper ? static_cast<std::size_t>(sl.d) : 0;
  r.coefficients_.resize(sl.outer * sl.st);
  for (std::size_t o = 0; o < sl.outer; ++o) {
    const auto first =
        coefficients_.begin() + static_cast<std::ptrdiff_t>(o * sl.block() + k * sl.st);
    std::copy(first, first + static_cast<std::ptrdiff_t>(sl.st),
              r.coefficients_.begin() + static_cast<std::ptrdiff_t>(o * sl.st));
  }
}

template <class S>
Bernstein<S> Bernstein<S>::elevate(std::span<const int> degrees) const {
  using namespace bernstein_detail;
  if (static_cast<int>(degrees.size()) != dim())
    throw std::invalid_argument("Bernstein::elevate: degrees have the wrong size");
  for (int a = 0; a < dim(); ++a)
    if (degrees[a] < degrees_[a])
      throw std::invalid_argument("Bernstein::elevate: cannot lower the degree");
  Bernstein r(*this);
  for (int a = 0; a < dim(); ++a) {
    const int d = degrees_[a], e = degrees[a];
    if (e == d) continue;
    // c_k = sum_i C(d,i) C(e-d,k-i) / C(e,k) b_i
    const std::vector<S> cd = binomialRow<S>(d), ced = binomialRow<S>(e - d),
                         ce = binomialRow<S>(e);
    std::vector<S> M(static_cast<std::size_t>(e + 1) * (d + 1), S(0));
    for (int k = 0; k <= e; ++k)
      for (int i = std::max(0, k - (e - d)); i <= std::min(d, k); ++i)
        M[static_cast<std::size_t>(k) * (d + 1) + i] = cd[i] * ced[k - i] / ce[k];
    r.coefficients_ = transformAxis(r.coefficients_, slabsOf(r.degrees_, r.size(), a), e + 1, M);
    r.degrees_[a] = e;
  }
  return r;
}

template <class S>
Bernstein<S> Bernstein<S>::embed(const Box<S>& domain, std::span<const int> positions) const {
  using namespace bernstein_detail;
  const int n = domain.dim();
  if (domain.hi.size() != domain.lo.size())
    throw std::invalid_argument("Bernstein::embed: malformed domain");
  if (static_cast<int>(positions.size()) != dim())
    throw std::invalid_argument("Bernstein::embed: positions have the wrong size");
  std::vector<int> degrees(static_cast<std::size_t>(n), 0);
  std::vector<bool> used(static_cast<std::size_t>(n), false);
  for (int j = 0; j < dim(); ++j) {
    const int p = positions[j];
    if (p < 0 || p >= n || used[p])
      throw std::invalid_argument("Bernstein::embed: bad or repeated position");
    used[p] = true;
    if (!(domain.lo[p] == domain_.lo[j] && domain.hi[p] == domain_.hi[j]))
      throw std::invalid_argument("Bernstein::embed: domains disagree on axis " +
                                  std::to_string(p));
    degrees[p] = degrees_[j];
  }
  Bernstein r(domain, degrees);
  std::vector<std::size_t> st(static_cast<std::size_t>(n), 1);
  for (int p = 1; p < n; ++p) st[p] = st[p - 1] * static_cast<std::size_t>(degrees[p - 1] + 1);
  // New variables have degree 0, so only the mapped axes contribute to the linear index.
  forEachIndex(degrees_, size(), [&](std::size_t lin, const std::vector<int>& idx) {
    std::size_t target = 0;
    for (int j = 0; j < dim(); ++j) target += static_cast<std::size_t>(idx[j]) * st[positions[j]];
    r.coefficients_[target] = coefficients_[lin];
  });
  return r;
}

namespace bernstein_detail {

// Shared checks of the binary operations, then both operands at their common degrees.
template <class S>
std::vector<int> commonDegrees(const Bernstein<S>& a, const Bernstein<S>& b, const char* op) {
  if (a.dim() != b.dim())
    throw std::invalid_argument(std::string("Bernstein ") + op + ": dimensions differ");
  if (!sameBox(a.domain(), b.domain()))
    throw std::invalid_argument(std::string("Bernstein ") + op + ": domains differ");
  std::vector<int> d(a.degrees());
  for (int j = 0; j < a.dim(); ++j) d[j] = std::max(d[j], b.degree(j));
  return d;
}

}  // namespace bernstein_detail

template <class S>
Bernstein<S>& Bernstein<S>::operator+=(const Bernstein& other) {
  const std::vector<int> d = bernstein_detail::commonDegrees(*this, other, "+=");
  if (d != degrees_) *this = elevate(d);
  if (d != other.degrees_) {
    const Bernstein o = other.elevate(d);
    for (std::size_t i = 0; i < size(); ++i) coefficients_[i] += o.coefficients_[i];
  } else {
    for (std::size_t i = 0; i < size(); ++i) coefficients_[i] += other.coefficients_[i];
  }
  return *this;
}

template <class S>
Bernstein<S>& Bernstein<S>::operator-=(const Bernstein& other) {
  const std::vector<int> d = bernstein_detail::commonDegrees(*this, other, "-=");
  if (d != degrees_) *this = elevate(d);
  if (d != other.degrees_) {
    const Bernstein o = other.elevate(d);
    for (std::size_t i = 0; i < size(); ++i) coefficients_[i] -= o.coefficients_[i];
  } else {
    for (std::size_t i = 0; i < size(); ++i) coefficients_[i] -= other.coefficients_[i];
  }
  return *this;
}

template <class S>
Bernstein<S>& Bernstein<S>::operator*=(const S& scale) {
  for (S& c : coefficients_) c *= scale;
  return *this;
}

template <class S>
Bernstein<S> Bernstein<S>::operator-() const {
  Bernstein r(*this);
  for (S& c : r.coefficients_) c = -c;
  return r;
}

template <class S>
std::pair<S, S> Bernstein<S>::coefficientRange() const {
  const auto [lo, hi] = std::minmax_element(coefficients_.begin(), coefficients_.end());
  return {*lo, *hi};
}

template <class S>
bool Bernstein<S>::excludesZero() const {
  const auto [lo, hi] = coefficientRange();
  return lo > 0 || hi < 0;
}

template <class S>
Bernstein<S> operator*(const Bernstein<S>& a, const Bernstein<S>& b) {
  using namespace bernstein_detail;
  const int n = a.dim();
  if (n != b.dim()) throw std::invalid_argument("Bernstein *: dimensions differ");
  if (!sameBox(a.domain(), b.domain())) throw std::invalid_argument("Bernstein *: domains differ");
  std::vector<int> f(static_cast<std::size_t>(n));
  std::vector<std::vector<S>> ca(n), cb(n), cf(n);
  std::vector<std::size_t> st(static_cast<std::size_t>(n), 1);
  for (int j = 0; j < n; ++j) {
    f[j] = a.degree(j) + b.degree(j);
    ca[j] = binomialRow<S>(a.degree(j));
    cb[j] = binomialRow<S>(b.degree(j));
    cf[j] = binomialRow<S>(f[j]);
    if (j > 0) st[j] = st[j - 1] * static_cast<std::size_t>(f[j - 1] + 1);
  }
  // Scaled (power-like) coefficients C(d,i) b_i and their offsets in the product tensor.
  auto scaled = [&](const Bernstein<S>& p, const std::vector<std::vector<S>>& binom,
                    std::vector<S>& values, std::vector<std::size_t>& offsets) {
    values.resize(p.size());
    offsets.resize(p.size());
    forEachIndex(p.degrees(), p.size(), [&](std::size_t lin, const std::vector<int>& idx) {
      S v = p.coefficients()[lin];
      std::size_t off = 0;
      for (int j = 0; j < n; ++j) {
        // A factor of 1 (the ends of every row) leaves v as it is: skipped (it is most of
        // them at degree 1 and 2, and an MPFR product costs as much as any other).
        const S& factor = binom[j][idx[j]];
        if (factor != 1) v *= factor;
        off += static_cast<std::size_t>(idx[j]) * st[j];
      }
      values[lin] = v;
      offsets[lin] = off;
    });
  };
  std::vector<S> va, vb;
  std::vector<std::size_t> oa, ob;
  scaled(a, ca, va, oa);
  scaled(b, cb, vb, ob);
  Bernstein<S> r(a.domain(), f);
  std::span<S> c = r.coefficients();
  S tmp;
  for (std::size_t i = 0; i < va.size(); ++i)
    for (std::size_t k = 0; k < vb.size(); ++k) {
      tmp = va[i];
      tmp *= vb[k];
      c[oa[i] + ob[k]] += tmp;
    }
  // Divide by C(d+e, k) per axis (a divisor of 1 changes nothing and is skipped).
  forEachIndex(f, r.size(), [&](std::size_t lin, const std::vector<int>& idx) {
    for (int j = 0; j < n; ++j)
      if (cf[j][idx[j]] != 1) c[lin] /= cf[j][idx[j]];
  });
  return r;
}

template <class S>
Bernstein<S> pow(const Bernstein<S>& a, int exponent) {
  if (exponent < 0) throw std::invalid_argument("Bernstein pow: negative exponent");
  Bernstein<S> result = Bernstein<S>::constant(a.domain(), S(1));
  if (exponent == 0) return result;
  // Repeated squaring; the first factor is taken as is to avoid a product with 1.
  Bernstein<S> base = a;
  bool first = true;
  while (true) {
    if (exponent & 1) {
      result = first ? base : result * base;
      first = false;
    }
    exponent >>= 1;
    if (exponent == 0) break;
    base = base * base;
  }
  return result;
}

}  // namespace ndc
