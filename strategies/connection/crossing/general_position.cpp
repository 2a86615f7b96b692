#include "strategies/connection/crossing/general_position.hpp"

#include <algorithm>
#include <cmath>

namespace ndc::crossing_detail {

template <class S>
GeneralPosition<S>::GeneralPosition(const ConnectionInput<S>& in, const Grid& grid) {
  using std::abs;
  using std::sqrt;
  const int n = grid.n, m = in.system.m();
  S width = S(grid.cellWidth(0));
  for (int j = 1; j < n; ++j) width = std::min<S>(width, S(grid.cellWidth(j)));
  // Gradient scale of each F_i: the median gradient norm at (a sample of) the projected cell
  // points that Newton brought onto M. Points where it failed can lie far off M, with
  // gradients orders of magnitude larger (interval bounding keeps many such cells).
  const std::size_t count = in.cells.size();
  std::vector<std::size_t> onM;
  for (std::size_t c = 0; c < count; ++c) {
    if (in.projections.converged[c]) onM.push_back(c);
  }
  if (onM.empty()) {
    for (std::size_t c = 0; c < count; ++c) onM.push_back(c);
  }
  const std::size_t stride = std::max<std::size_t>(1, onM.size() / 256);
  std::vector<std::vector<S>> norms(m);
  std::vector<S> f(m), jacobian(std::size_t(m) * n);
  for (std::size_t t = 0; t < onM.size(); t += stride) {
    in.system.evaluate(in.projections.at(onM[t]), f, jacobian);
    for (int i = 0; i < m; ++i) {
      S norm = 0;
      for (int j = 0; j < n; ++j)
        norm += jacobian[std::size_t(i) * n + j] * jacobian[std::size_t(i) * n + j];
      norms[i].push_back(sqrt(norm));
    }
  }
  scale.assign(m, S(0));
  for (int i = 0; i < m; ++i) {
    auto middle = norms[i].begin() + norms[i].size() / 2;
    std::nth_element(norms[i].begin(), middle, norms[i].end());
    if (middle != norms[i].end()) scale[i] = *middle;
  }
  for (S& g : scale) {
    if (!(g > 0)) g = 1;
    g *= width * S(kRelative);
  }
  slack = 64 * width * S(kRelative);
  tolerance = width * S(kRelative) / 64;
}

template <class S>
std::vector<S> GeneralPosition<S>::level(int attempt) const {
  std::vector<S> c(scale.size());
  for (std::size_t i = 0; i < scale.size(); ++i) {
    const double t = std::fmod(0.6180339887498949 * double(attempt * 7 + i + 1), 1.0);
    c[i] = S(0.5 + 0.5 * t) * scale[i];
  }
  return c;
}

template <class S>
std::int64_t GeneralPosition<S>::nearBoundary(const std::vector<std::vector<S>>& roots,
                                              const Box<S>& box, const std::vector<int>& freeAxes,
                                              const FaceEnds& ends) const {
  using std::abs;
  std::int64_t near = 0;
  for (const auto& r : roots) {
    for (std::size_t t = 0; t < freeAxes.size(); ++t) {
      const int j = freeAxes[t];
      if ((!ends.lower[t] && abs(r[j] - box.lo[j]) < tolerance) ||
          (!ends.upper[t] && abs(box.hi[j] - r[j]) < tolerance)) {
        ++near;
        break;
      }
    }
  }
  return near;
}

template struct GeneralPosition<double>;
template struct GeneralPosition<Mpfr>;

}  // namespace ndc::crossing_detail
