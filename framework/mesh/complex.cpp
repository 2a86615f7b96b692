#include "framework/mesh/complex.hpp"

#include "framework/numeric/scalar.hpp"

namespace ndc {

const char* className(CellClass c) {
  switch (c) {
    case CellClass::kNormal:
      return "normal";
    case CellClass::kAbnormal:
      return "abnormal";
    case CellClass::kFailed:
      return "failed";
  }
  return "?";
}

template <class S>
std::int32_t Complex<S>::addVertex(std::span<const S> x, std::int32_t cell) {
  const auto number = static_cast<std::int32_t>(vertexCount());
  vertices.insert(vertices.end(), x.begin(), x.end());
  vertexCell.push_back(cell);
  return number;
}

template <class S>
void Complex<S>::addSimplex(std::span<const std::int32_t> v) {
  simplices.insert(simplices.end(), v.begin(), v.end());
}

template struct Complex<double>;
template struct Complex<Mpfr>;

}  // namespace ndc
