// Peer benchmark (bench/, docs/performance.md): CGAL's Surface_mesher (make_surface_mesh, the
// Boissonnat-Oudot Delaunay refinement) on the implicit surfaces of the benchmark problems in R^3:
// the torus of experiments/problems/torus.toml and the genus-2 surface of genus2.toml, given by
// the same polynomials. Writes the mesh as ASCII PLY (x y z u0 u1 u2, as ndcontour does) and
// prints one JSON line: problem, criteria, vertex and face counts, seconds of meshing.
//
// Usage: cgal_torus [--problem torus|genus2] [--angle DEG] [--radius R] [--distance D]
//                   [--error E] [--out mesh.ply]
#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Surface_mesh_default_criteria_3.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace {

using Tr = CGAL::Surface_mesh_default_triangulation_3;
using C2t3 = CGAL::Complex_2_in_triangulation_3<Tr>;
using GT = Tr::Geom_traits;
using Point_3 = GT::Point_3;
using Sphere_3 = GT::Sphere_3;
using FT = GT::FT;
using Function = FT (*)(Point_3);
using Surface_3 = CGAL::Implicit_surface_3<GT, Function>;

// torus.toml: (x^2 + y^2 + z^2 + 0.84)^2 - 4 (x^2 + y^2), negative inside.
FT torus(Point_3 p) {
  const double x = p.x(), y = p.y(), z = p.z();
  const double s = x * x + y * y + z * z + 0.84;
  return s * s - 4 * (x * x + y * y);
}

// genus2.toml: f^2 + z^2 - 0.01 with f = (x^2 + y^2)^2 - x^2 + y^2, negative inside.
FT genus2(Point_3 p) {
  const double x = p.x(), y = p.y(), z = p.z();
  const double r = x * x + y * y;
  const double f = r * r - x * x + y * y;
  return f * f + z * z - 0.01;
}

[[noreturn]] void usage(const char* message) {
  std::fprintf(stderr,
               "cgal_torus: %s\nusage: cgal_torus [--problem torus|genus2] [--angle DEG] "
               "[--radius R] [--distance D] [--error E] [--out mesh.ply]\n",
               message);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  std::string problem = "torus", out;
  double angle = 30, radius = 0.1, distance = 0.01, error = 1e-6;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) usage(("missing value after " + a).c_str());
    const char* v = argv[++i];
    if (a == "--problem") {
      problem = v;
    } else if (a == "--angle") {
      angle = std::atof(v);
    } else if (a == "--radius") {
      radius = std::atof(v);
    } else if (a == "--distance") {
      distance = std::atof(v);
    } else if (a == "--error") {
      error = std::atof(v);
    } else if (a == "--out") {
      out = v;
    } else {
      usage(("unknown option " + a).c_str());
    }
  }

  // The bounding sphere's centre has to lie inside the surface (function value < 0).
  Function function = nullptr;
  Sphere_3 bound;
  if (problem == "torus") {
    function = torus;
    bound = Sphere_3(Point_3(1, 0, 0), 2.5 * 2.5);
  } else if (problem == "genus2") {
    function = genus2;
    bound = Sphere_3(Point_3(0, 0, 0), 1.2 * 1.2);
  } else {
    usage(("unknown problem " + problem).c_str());
  }

  const auto start = std::chrono::steady_clock::now();
  Tr tr;
  C2t3 c2t3(tr);
  Surface_3 surface(function, bound, error);
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(angle, radius, distance);
  CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The facets of the complex, on indexed vertices.
  std::map<Tr::Vertex_handle, int> index;
  std::vector<Point_3> points;
  std::vector<std::array<int, 3>> faces;
  for (auto f = c2t3.facets_begin(); f != c2t3.facets_end(); ++f) {
    std::array<int, 3> face{};
    for (int k = 0; k < 3; ++k) {
      const Tr::Vertex_handle v = f->first->vertex((f->second + 1 + k) & 3);
      const auto [it, inserted] = index.emplace(v, static_cast<int>(points.size()));
      if (inserted) points.push_back(v->point());
      face[k] = it->second;
    }
    faces.push_back(face);
  }

  if (!out.empty()) {
    std::ofstream o(out);
    o.precision(17);
    o << "ply\nformat ascii 1.0\ncomment cgal_torus " << problem << "\nelement vertex "
      << points.size()
      << "\nproperty double x\nproperty double y\nproperty double z\nproperty double "
         "u0\nproperty double u1\nproperty double u2\nelement face "
      << faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Point_3& p : points)
      o << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << p.x() << ' ' << p.y() << ' ' << p.z()
        << '\n';
    for (const auto& f : faces) o << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
  }
  std::printf(
      "{\"tool\": \"cgal\", \"problem\": \"%s\", \"angle\": %g, \"radius\": %g, \"distance\": "
      "%g, \"error\": %g, \"vertices\": %zu, \"faces\": %zu, \"time_s\": %.6f}\n",
      problem.c_str(), angle, radius, distance, error, points.size(), faces.size(), seconds);
  return 0;
}
