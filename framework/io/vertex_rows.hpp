/// \file vertex_rows.hpp
/// The vertex rows of the mesh files (mesh.ply, mesh.vtu/.vtp, mesh.obj): the point in R^3 that
/// a viewer shows, then the n coordinates, then an application's second image.
#pragma once

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

#include "framework/io/result.hpp"
#include "framework/problem/application.hpp"

namespace ndc {

/// The values of the vertex properties of mesh.ply (x y z, u0.., x2 y2 z2), in header order.
/// Row v: `x y z` (the first three coordinates, zero-padded for n = 2, or an application's image
/// in R^3), `u0 .. u{n-1}` (an application's surface parameters), and `x2 y2 z2` for an
/// application with a second image.
class VertexRows {
 public:
  explicit VertexRows(const RunResult& r)
      : r_(r), app_(r.application.get()), second_(app_ && app_->secondImage) {
    row_.resize(3 + r.n + (second_ ? 3 : 0));
  }
  std::size_t count() const { return r_.n ? r_.vertices.size() / r_.n : 0; }
  std::size_t width() const { return row_.size(); }
  bool second() const { return second_; }

  /// The row of vertex v (valid until the next call).
  std::span<const double> operator()(std::size_t v) {
    const double* p = r_.vertices.data() + v * r_.n;
    const std::size_t n = static_cast<std::size_t>(r_.n);
    if (!app_) {
      // The 3-D image: the first three coordinates, zero-padded.
      for (std::size_t j = 0; j < 3; ++j) row_[j] = j < n ? p[j] : 0.0;
      std::copy(p, p + n, row_.begin() + 3);
      return row_;
    }
    // The application's map to R^3, and the surface parameters of B-spline variables.
    const std::span<const double> x(p, n);
    const auto image = app_->image(x);
    std::copy(image.begin(), image.end(), row_.begin());
    for (std::size_t j = 0; j < n; ++j) row_[3 + j] = app_->parameter(static_cast<int>(j), p[j]);
    if (second_) {
      const auto y = (*app_->secondImage)(x);
      std::copy(y.begin(), y.end(), row_.begin() + 3 + n);
    }
    return row_;
  }

 private:
  const RunResult& r_;
  const ApplicationData* app_;
  bool second_;
  std::vector<double> row_;
};

}  // namespace ndc
