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
  /// Where the viewer is, as a unit direction in drawn coordinates: a point moved along it is
  /// drawn at the same place of the picture, only nearer (see trianglePm3d's `pushBack`).
  std::array<double, 3> toViewer{0, 0, 1};

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

/// gnuplot's orthographic view `set view ROT_X, ROT_Z` (degrees; with `set view equal xyz`):
/// points are drawn as they are, and View::toViewer is the direction towards the viewer.
View orthographicView(double rotX, double rotZ);

/// A mesh's vertices through `view`.
std::vector<std::array<double, 3>> viewed(const std::vector<std::array<double, 3>>& xyz,
                                          const View& view);

/// A mesh's triangles for `with pm3d` (shaded, lit): each a 2 x 2 grid a b / c m, where m is
/// the midpoint of b and c, with a blank line inside and two after it. The quadrangle a b m c is
/// the triangle, and every three of its corners span its plane: gnuplot's lighting takes the
/// normal from three corners, and a grid a b / c c (two equal corners) has none, so it drew
/// every triangle in one flat colour. `pushBack` > 0 moves every point that far away from the
/// viewer (View::toViewer): the picture is the same, but where this surface touches another one
/// (the input surfaces along a blend's rails, the body along a sweep's characteristic curves)
/// pm3d's depth sorting puts the other one in front, instead of interleaving their triangles in
/// stripes.
std::vector<std::vector<double>> trianglePm3d(const PlyMesh& m, const View& view,
                                              double pushBack = 0);

/// The length of the diagonal of the bounding box of `points` as drawn through `view`.
double drawnDiagonal(const std::vector<std::array<double, 3>>& points, const View& view);

/// The bounding box of points: {min, max} per axis (HUGE_VAL, -HUGE_VAL without finite points).
std::array<std::array<double, 2>, 3> boundingBox(const std::vector<std::array<double, 3>>& points);

/// The axes of a perspective panel `p`: the world axes x, y, z drawn from the lowest corner of
/// `box` through `view` as the data block `$axes<p>`, labelled with their end values (gnuplot's
/// own axes would be the image's).
void perspectiveAxes(GnuplotScript& gp, const View& view,
                     const std::array<std::array<double, 2>, 3>& box, std::size_t p);

}  // namespace ndc::report
