// The 3-D view of the report's application figures: see perspective.hpp.
#include "experiments/report/perspective.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "experiments/report/table.hpp"

namespace ndc::report {
namespace {

std::array<double, 3> normalize(std::array<double, 3> a) {
  const double length = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (double& x : a) x = length > 0 ? x / length : 0;
  return a;
}

std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace

/// The perspective view from `eye` towards `target`, world z up.
View perspectiveView(const std::array<double, 3>& eye, const std::array<double, 3>& target) {
  View v;
  v.perspective = true;
  v.eye = eye;
  v.forward = normalize({target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]});
  v.right = normalize(cross(v.forward, {0, 0, 1}));
  if (v.right == std::array<double, 3>{0, 0, 0}) v.right = {1, 0, 0};  // looking straight down
  v.up = cross(v.right, v.forward);
  return v;
}

View orthographicView(double rotX, double rotZ) {
  // gnuplot turns the scene by rotZ about z, then by rotX about x, and looks down the turned z
  // axis: the unturned direction towards the viewer is this one.
  const double x = rotX * std::numbers::pi / 180, z = rotZ * std::numbers::pi / 180;
  View v;
  v.toViewer = {std::sin(x) * std::sin(z), -std::sin(x) * std::cos(z), std::cos(x)};
  return v;
}

/// A mesh's vertices through `view`.
std::vector<std::array<double, 3>> viewed(const std::vector<std::array<double, 3>>& xyz,
                                          const View& view) {
  std::vector<std::array<double, 3>> out;
  out.reserve(xyz.size());
  for (const auto& p : xyz) out.push_back(view(p));
  return out;
}

/// A mesh's triangles for `with pm3d` (shaded, lit): each a 2 x 2 grid a b / c m (m the
/// midpoint of b and c, so that gnuplot's lighting finds a normal), a blank line inside and two
/// after it.
std::vector<std::vector<double>> trianglePm3d(const PlyMesh& m, const View& view, double pushBack) {
  std::vector<std::array<double, 3>> p = viewed(m.xyz, view);
  for (auto& q : p)
    for (int j = 0; j < 3; ++j) q[j] -= pushBack * view.toViewer[j];
  std::vector<std::vector<double>> rows;
  for (const auto& s : m.simplices) {
    if (s.size() != 3) continue;
    const auto row = [&](int v) { return std::vector<double>{p[v][0], p[v][1], p[v][2]}; };
    // The midpoint of the image of b and c: a projection keeps it on the image of the edge.
    std::vector<double> mid(3);
    for (int j = 0; j < 3; ++j) mid[j] = 0.5 * (p[s[1]][j] + p[s[2]][j]);
    rows.insert(rows.end(), {row(s[0]), row(s[1]), {}, row(s[2]), mid, {}, {}});
  }
  return rows;
}

double drawnDiagonal(const std::vector<std::array<double, 3>>& points, const View& view) {
  const auto box = boundingBox(viewed(points, view));
  double squared = 0;
  for (const auto& b : box)
    if (b[1] >= b[0]) squared += (b[1] - b[0]) * (b[1] - b[0]);
  return std::sqrt(squared);
}

/// The bounding box of points: {min, max} per axis.
std::array<std::array<double, 2>, 3> boundingBox(const std::vector<std::array<double, 3>>& points) {
  std::array<std::array<double, 2>, 3> box;
  for (auto& b : box) b = {HUGE_VAL, -HUGE_VAL};
  for (const auto& p : points)
    for (int j = 0; j < 3; ++j)
      if (std::isfinite(p[j])) box[j] = {std::min(box[j][0], p[j]), std::max(box[j][1], p[j])};
  return box;
}

/// The axes of a perspective panel: the world axes x, y, z drawn from the data's lowest corner
/// through the eye, labelled with their end values (gnuplot's own axes would be the image's).
void perspectiveAxes(GnuplotScript& gp, const View& view,
                     const std::array<std::array<double, 2>, 3>& box, std::size_t p) {
  gp.command("set view 0, 0, 2.4");
  gp.command("set view equal xy");
  gp.command("unset border; unset xtics; unset ytics; unset ztics");
  gp.command("unset xlabel; unset ylabel; unset zlabel");
  // Fit the picture exactly (autoscaling would extend the ranges to tic values).
  gp.command("set autoscale fix");
  const std::array<double, 3> origin = {box[0][0], box[1][0], box[2][0]};
  std::vector<std::vector<double>> rows;
  gp.command("unset label");
  const char* names[] = {"x", "y", "z"};
  for (int j = 0; j < 3; ++j) {
    std::array<double, 3> end = origin;
    end[j] = box[j][1];
    const auto a = view(origin), b = view(end);
    rows.push_back({a[0], a[1], a[2]});
    rows.push_back({b[0], b[1], b[2]});
    rows.push_back({});
    rows.push_back({});
    gp.command("set label " + std::to_string(j + 1) + " \"" + names[j] + " = " +
               formatNumber(box[j][1], 2) + "\" at " + formatNumber(b[0], 6) + "," +
               formatNumber(b[1], 6) + "," + formatNumber(b[2], 6) + " front");
  }
  gp.data("axes" + std::to_string(p), rows);
}

}  // namespace ndc::report
