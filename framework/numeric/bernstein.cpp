// Explicit instantiations of Bernstein<S> for the two scalar types.
#include "framework/numeric/bernstein.inl"

namespace ndc {

template class Bernstein<double>;
template class Bernstein<Mpfr>;
template Bernstein<double> operator*(const Bernstein<double>&, const Bernstein<double>&);
template Bernstein<Mpfr> operator*(const Bernstein<Mpfr>&, const Bernstein<Mpfr>&);
template Bernstein<double> pow(const Bernstein<double>&, int);
template Bernstein<Mpfr> pow(const Bernstein<Mpfr>&, int);

}  // namespace ndc
