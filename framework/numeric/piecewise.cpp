// Piecewise tensor-product Bernstein polynomials: evaluation by de Casteljau per axis (plain and
// interval), exact Bernstein forms on sub-boxes, derivatives.
#include "framework/numeric/piecewise.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>

namespace ndc {

namespace {

/// Largest number of local axes a leaf may have (surfaces have 2, motions 1).
constexpr int kMaxLeafAxes = 8;

/// Index of the piece along one axis that holds `x` (clamped: extrapolation outside).
template <class S>
int pieceOf(const std::vector<double>& breaks, const S& x) {
  const int last = static_cast<int>(breaks.size()) - 2;
  int i = 0;
  while (i < last && !(x < S(breaks[i + 1]))) ++i;
  return i;
}

/// A double coefficient in T (exact: every scalar holds a double).
template <class T>
struct Lift {
  static T of(double c) { return T(c); }
};
template <class S>
struct Lift<Interval<S>> {
  static Interval<S> of(double c) { return Interval<S>(S(c)); }
};

/// de Casteljau along every axis of a tensor-product piece at local parameters t (t[a] = 0 at
/// the piece's lower break, 1 at the upper one), in T = S or Interval<S>, on `work`, which
/// holds the piece's coefficients on entry (axis 0 fastest) and is overwritten.
template <class T>
T tensorDeCasteljau(const Bernstein<double>& piece, const T* t, T* work) {
  std::size_t count = piece.coefficients().size();
  for (int a = 0; a < piece.dim(); ++a) {
    // Axis a is the fastest axis of what is left: blocks of d + 1 values, each reduced to one.
    const int d = piece.degree(a);
    const std::size_t block = static_cast<std::size_t>(d) + 1, blocks = count / block;
    for (std::size_t b = 0; b < blocks; ++b) {
      T* w = &work[b * block];
      for (int r = 1; r <= d; ++r)
        for (int i = 0; i + r <= d; ++i) w[i] += t[a] * (w[i + 1] - w[i]);
      if (b) work[b] = w[0];
    }
    count = blocks;
  }
  return work[0];
}

/// The same with the coefficients lifted to T into the vector `work` (any size).
template <class T>
T tensorDeCasteljau(const Bernstein<double>& piece, const T* t, std::vector<T>& work) {
  work.clear();
  for (double c : piece.coefficients()) work.push_back(Lift<T>::of(c));
  return tensorDeCasteljau<T>(piece, t, work.data());
}

/// An enclosure of (x - lo) / (hi - lo) for an interval x and doubles lo < hi.
template <class S>
Interval<S> localParameter(const Interval<S>& x, double lo, double hi) {
  const Interval<S> width = Interval<S>(S(hi)) - Interval<S>(S(lo));
  const Interval<S> shifted = x - Interval<S>(S(lo));
  if (width.lower() == width.upper()) return shifted.dividedBy(width.lower());
  return shifted.dividedBy(width.lower()).hull(shifted.dividedBy(width.upper()));
}

}  // namespace

int PiecewiseBernstein::degree(int a) const {
  int d = 0;
  for (const auto& piece : pieces) d = std::max(d, piece.degree(a));
  return d;
}

double PiecewiseBernstein::maxAbsCoefficient() const {
  double m = 0;
  for (const auto& piece : pieces)
    for (double c : piece.coefficients()) m = std::max(m, std::abs(c));
  return m;
}

void PiecewiseBernstein::validate() const {
  const int p = dim();
  if (p < 1 || p > kMaxLeafAxes)
    throw std::invalid_argument(name + ": a piecewise polynomial needs 1 to 8 axes");
  if (static_cast<int>(breaks.size()) != p)
    throw std::invalid_argument(name + ": one list of breaks per axis is required");
  std::size_t expected = 1;
  for (int a = 0; a < p; ++a) {
    if (breaks[a].size() < 2) throw std::invalid_argument(name + ": an axis needs two breaks");
    for (std::size_t i = 0; i + 1 < breaks[a].size(); ++i)
      if (!(breaks[a][i] < breaks[a][i + 1]))
        throw std::invalid_argument(name + ": breaks must increase");
    expected *= breaks[a].size() - 1;
  }
  if (pieces.size() != expected) throw std::invalid_argument(name + ": wrong number of pieces");
  for (const auto& piece : pieces)
    if (piece.dim() != p) throw std::invalid_argument(name + ": a piece has the wrong dimension");
}

template <class S>
S PiecewiseBernstein::evaluate(std::span<const S> local) const {
  // Locate the piece, then evaluate it at the local parameters.
  std::size_t index = 0, stride = 1;
  S t[kMaxLeafAxes];
  for (int a = 0; a < dim(); ++a) {
    const int i = pieceOf(breaks[a], local[a]);
    index += stride * static_cast<std::size_t>(i);
    stride *= static_cast<std::size_t>(pieceCount(a));
    t[a] = (local[a] - S(breaks[a][i])) / (S(breaks[a][i + 1]) - S(breaks[a][i]));
  }
  if constexpr (std::is_same_v<S, double>) {
    // Small pieces (a bicubic patch has 16 coefficients) on the stack: this is the innermost
    // call of every Newton step on an application's expression.
    constexpr std::size_t kStack = 64;
    const auto coefficients = pieces[index].coefficients();
    if (coefficients.size() <= kStack) {
      double work[kStack];
      std::copy(coefficients.begin(), coefficients.end(), work);
      return tensorDeCasteljau<double>(pieces[index], t, work);
    }
    thread_local std::vector<double> work;
    return tensorDeCasteljau<double>(pieces[index], t, work);
  } else {
    std::vector<S> work;
    return tensorDeCasteljau<S>(pieces[index], t, work);
  }
}

template <class S>
Interval<S> PiecewiseBernstein::enclose(std::span<const Interval<S>> local) const {
  const int p = dim();
  // The range of pieces each axis meets.
  int first[kMaxLeafAxes], last[kMaxLeafAxes], current[kMaxLeafAxes];
  for (int a = 0; a < p; ++a) {
    first[a] = pieceOf(breaks[a], local[a].lower());
    last[a] = pieceOf(breaks[a], local[a].upper());
    current[a] = first[a];
  }
  // Scratch for de Casteljau in Mpfr (double has a kernel of its own, in interval.cpp).
  std::vector<Interval<S>> work;
  Interval<S> t[kMaxLeafAxes];
  bool any = false;
  Interval<S> result;
  for (;;) {
    std::size_t index = 0, stride = 1;
    for (int a = 0; a < p; ++a) {
      const int i = current[a];
      index += stride * static_cast<std::size_t>(i);
      stride *= static_cast<std::size_t>(pieceCount(a));
      // The part of the box in this piece (the whole box for an extrapolated end piece).
      S lo = local[a].lower(), hi = local[a].upper();
      if (i > first[a]) lo = S(breaks[a][i]);
      if (i < last[a]) hi = S(breaks[a][i + 1]);
      t[a] = localParameter(Interval<S>(lo, hi), breaks[a][i], breaks[a][i + 1]);
    }
    Interval<S> value;
    if constexpr (std::is_same_v<S, double>)
      value = tensorDeCasteljauEnclosure(pieces[index].coefficients(), pieces[index].degrees(), t);
    else
      value = tensorDeCasteljau<Interval<S>>(pieces[index], t, work);
    result = any ? result.hull(value) : value;
    any = true;
    int a = 0;
    while (a < p && current[a] == last[a]) current[a] = first[a], ++a;
    if (a == p) break;
    ++current[a];
  }
  return result;
}

template <class S>
Bernstein<S> PiecewiseBernstein::onBox(const Box<S>& local) const {
  const int p = dim();
  std::size_t index = 0, stride = 1;
  Box<S> pieceBox{std::vector<S>(p), std::vector<S>(p)};
  for (int a = 0; a < p; ++a) {
    const double lo = toDouble(local.lo[a]), hi = toDouble(local.hi[a]);
    const int i = pieceOf(breaks[a], (lo + hi) / 2);
    const double b0 = breaks[a][i], b1 = breaks[a][i + 1], slack = 1e-9 * (b1 - b0);
    const bool inside =
        (i == 0 || lo >= b0 - slack) && (i == pieceCount(a) - 1 || hi <= b1 + slack);
    if (!inside)
      throw std::domain_error(name + ": the box [" + std::to_string(lo) + ", " +
                              std::to_string(hi) +
                              "] straddles a break of the piecewise polynomial");
    index += stride * static_cast<std::size_t>(i);
    stride *= static_cast<std::size_t>(pieceCount(a));
    pieceBox.lo[a] = S(b0);
    pieceBox.hi[a] = S(b1);
  }
  const Bernstein<double>& piece = pieces[index];
  Bernstein<S> converted(pieceBox, piece.degrees());
  const auto from = piece.coefficients();
  auto to = converted.coefficients();
  for (std::size_t i = 0; i < from.size(); ++i) to[i] = S(from[i]);
  return converted.restrict(local);
}

PiecewiseBernstein PiecewiseBernstein::derivative(int a) const {
  PiecewiseBernstein d{name + "_" + std::to_string(a), axes, breaks, {}};
  d.pieces.reserve(pieces.size());
  for (const auto& piece : pieces) d.pieces.push_back(piece.derivative(a));
  return d;
}

template double PiecewiseBernstein::evaluate<double>(std::span<const double>) const;
template Mpfr PiecewiseBernstein::evaluate<Mpfr>(std::span<const Mpfr>) const;
template Interval<double> PiecewiseBernstein::enclose<double>(
    std::span<const Interval<double>>) const;
template Interval<Mpfr> PiecewiseBernstein::enclose<Mpfr>(std::span<const Interval<Mpfr>>) const;
template Bernstein<double> PiecewiseBernstein::onBox<double>(const Box<double>&) const;
template Bernstein<Mpfr> PiecewiseBernstein::onBox<Mpfr>(const Box<Mpfr>&) const;

}  // namespace ndc
