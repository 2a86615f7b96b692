/// \file perspective.hpp
/// The 3-D view of the report's application figures (fig-app-*): gnuplot's own orthographic
/// view, or a perspective from an eye point (the sweep silhouette's), with the meshes' triangles
/// for `with pm3d` and the world axes of a perspective panel.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "experiments/report/gnuplot.hpp"
#include "framework/io/io.hpp"

namespace ndc::report {

/// Where a 3-D point is drawn: unchanged (gnuplot's own orthographic view), or projected
/// through an eye point (x, y: the perspective image, z: minus the distance along the view
/// direction, so that `set view 0,0` shows the perspective picture and pm3d sorts by depth).
struct View {
  bool perspective = false;         ///< false: points are drawn as they are
  std::array<double, 3> eye{};      ///< the eye point
  std::array<double, 3> right{};    ///< the image's x direction (unit)
  std::array<double, 3> up{};       ///< the image's y direction (unit)
  std::array<double, 3> forward{};  ///< the view direction (unit)

  /// Where `p` is drawn.
  std::array<double, 3> operator()(const std::array<double, 3>& p) const {
    if (!perspective) return p;
    const std::array<double, 3> d = {p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]};
    const auto dot = [&](const std::array<double, 3>& a) {
      return a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
    };
    const double depth = std::max(dot(forward), 1e-9);
    return {dot(right) / depth, dot(up) / depth, -depth};
  }
};

/// The perspective view from `eye` towards `target`, world z up.
View perspectiveView(const std::array<double, 3>& eye, const std::array<double, 3>& target);

/// A mesh's vertices through `view`.
std::vector<std::array<double, 3>> viewed(const std::vector<std::array<double, 3>>& xyz,
                                          const View& view);

/// A mesh's triangles for `with pm3d` (shaded, lit): each a 2 x 2 grid a b / c c, a blank line
/// inside and two after it.
std::vector<std::vector<double>> trianglePm3d(const PlyMesh& m, const View& view);

/// The bounding box of points: {min, max} per axis (HUGE_VAL, -HUGE_VAL without finite points).
std::array<std::array<double, 2>, 3> boundingBox(const std::vector<std::array<double, 3>>& points);

/// The axes of a perspective panel `p`: the world axes x, y, z drawn from the lowest corner of
/// `box` through `view` as the data block `$axes<p>`, labelled with their end values (gnuplot's
/// own axes would be the image's).
void perspectiveAxes(GnuplotScript& gp, const View& view,
                     const std::array<std::array<double, 2>, 3>& box, std::size_t p);

}  // namespace ndc::report
