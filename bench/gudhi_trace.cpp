// Peer benchmark (bench/, docs/performance.md): GUDHI's manifold tracing in a Coxeter
// triangulation (Gudhi::coxeter_triangulation::manifold_tracing_algorithm with an
// Implicit_manifold_intersection_oracle) on the benchmark problems, given by the same polynomials
// as their problem files. The traced k-simplices of the triangulation (k the codimension) and
// their intersection points are the vertices; GUDHI's Cell_complex gives the dual cells, whose
// 1-cells are the edges (curves) and whose 2-cells, polygons, are fanned into triangles
// (surfaces). For k = 3 each 3-cell, a polytope bounded by polygons, is split into tetrahedra:
// its polygons are fanned from their lowest-numbered vertex (the same fan in both cells that
// share a polygon), and every triangle is coned from one new vertex per 3-cell, the barycentre
// of the cell's vertices moved onto M by Gauss-Newton steps (so that every vertex lies on M, as
// GUDHI's own 0-cells do). Writes ASCII PLY (x y z u0.., as ndcontour does; for k = 3 a `face`
// element of 4-vertex lists, as ndcontour's mesh.ply) and prints one JSON line.
//
// Usage: gudhi_trace PROBLEM [--scale S] [--out mesh.ply]
//   PROBLEM: torus, clifford-torus-rotated, sphere-r5, flat-torus-r6, circle-r8, genus2 (k <= 2);
//   sphere3-r5, sphere3-r6, s1xs2-r5, flat-3torus-r6, o3-r9 (k = 3, experiments/problems/); or
//   section:FILE, the unit sphere cut by the hyperplanes M x + d = 0 of FILE (bench/scale.py's
//   k-spheres): n, then one row "a_1 .. a_n d" per hyperplane, whitespace-separated
//   S: the scale of the Coxeter triangulation (the length of its edges is about S)
#include <gudhi/Coxeter_triangulation.h>
#include <gudhi/Coxeter_triangulation/Cell_complex/Cell_complex.h>
#include <gudhi/Implicit_manifold_intersection_oracle.h>
#include <gudhi/Manifold_tracing.h>

#include <Eigen/Dense>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A problem: n variables, n - k equations F, and a point on each component of the manifold (the
// seeds).
struct Problem {
  int n = 0, equations = 0;
  std::function<VectorXd(const VectorXd&)> f;
  std::vector<VectorXd> seeds;
};

// The function object GUDHI's oracle needs (amb_d, cod_d, seed, operator()).
struct Function {
  const Problem* p;
  VectorXd operator()(const VectorXd& x) const { return p->f(x); }
  std::size_t amb_d() const { return static_cast<std::size_t>(p->n); }
  std::size_t cod_d() const { return static_cast<std::size_t>(p->equations); }
  VectorXd seed() const { return p->seeds.front(); }
};

// Sphere |x - c| = r (the unit sphere by default) cut by the affine hyperplanes M x + d = 0
// (sphere-r5, circle-r8, sphere3-r5, sphere3-r6): a point on it is the foot c0 of c on the flat
// plus rho times a unit direction in the flat.
Problem sphereSection(const MatrixXd& m, const VectorXd& d, VectorXd c = VectorXd(),
                      double radius = 1) {
  if (c.size() == 0) c = VectorXd::Zero(m.cols());
  Problem p;
  p.n = static_cast<int>(m.cols());
  p.equations = static_cast<int>(m.rows()) + 1;
  p.f = [m, d, c, radius](const VectorXd& x) {
    VectorXd r(m.rows() + 1);
    r(0) = (x - c).squaredNorm() - radius * radius;
    r.tail(m.rows()) = m * x + d;
    return r;
  };
  const MatrixXd gram = m * m.transpose();
  const VectorXd c0 = c - m.transpose() * gram.ldlt().solve(m * c + d);
  VectorXd u = VectorXd::Ones(p.n);
  u -= m.transpose() * gram.ldlt().solve(m * u);
  p.seeds = {c0 + std::sqrt(radius * radius - (c0 - c).squaredNorm()) * u.normalized()};
  return p;
}

// Round spheres |x_I - c_I| = r_I in disjoint blocks I of coordinates (s1xs2-r5: a circle times
// a 2-sphere; flat-3torus-r6: three circles): one equation per block.
Problem sphereProduct(const std::vector<int>& blocks, const VectorXd& c,
                      const std::vector<double>& radius) {
  Problem p;
  p.n = static_cast<int>(c.size());
  p.equations = static_cast<int>(blocks.size());
  p.f = [blocks, c, radius](const VectorXd& x) {
    VectorXd r(static_cast<Eigen::Index>(blocks.size()));
    int start = 0;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      r(static_cast<Eigen::Index>(b)) =
          (x - c).segment(start, blocks[b]).squaredNorm() - radius[b] * radius[b];
      start += blocks[b];
    }
    return r;
  };
  VectorXd seed = c;
  int start = 0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    seed(start) += radius[b];
    start += blocks[b];
  }
  p.seeds = {seed};
  return p;
}

// The orthogonal group O(3): R^T R = I for R = [[x0, x1, x2], [x3, x4, x5], [x6, x7, x8]], the
// columns' norms and dot products (o3-r9). Two components: seeds I and diag(-1, 1, 1).
Problem orthogonalGroup() {
  Problem p;
  p.n = 9;
  p.equations = 6;
  p.f = [](const VectorXd& x) {
    auto col = [&](int j) { return Eigen::Vector3d(x(j), x(3 + j), x(6 + j)); };
    VectorXd r(6);
    r << col(0).squaredNorm() - 1, col(1).squaredNorm() - 1, col(2).squaredNorm() - 1,
        col(0).dot(col(1)), col(0).dot(col(2)), col(1).dot(col(2));
    return r;
  };
  VectorXd id = VectorXd::Zero(9);
  id(0) = id(4) = id(8) = 1;
  VectorXd reflection = id;
  reflection(0) = -1;
  p.seeds = {id, reflection};
  return p;
}

// x moved onto M = F^-1(0) by Gauss-Newton steps with the minimum-norm step and a central
// difference Jacobian (for the new vertex of a 3-cell, a point near M).
VectorXd ontoM(const Problem& p, VectorXd x) {
  for (int step = 0; step < 8; ++step) {
    const VectorXd fx = p.f(x);
    if (fx.norm() < 1e-13) break;
    MatrixXd jac(p.equations, p.n);
    for (int j = 0; j < p.n; ++j) {
      VectorXd a = x, b = x;
      a(j) += 1e-7;
      b(j) -= 1e-7;
      jac.col(j) = (p.f(a) - p.f(b)) / 2e-7;
    }
    x -= jac.transpose() * (jac * jac.transpose()).ldlt().solve(fx);
  }
  return x;
}

// The Clifford torus q1^2 + q2^2 = q3^2 + q4^2 = 0.5, q5 = .. = 0 in the coordinates q = R x.
Problem rotatedClifford(const MatrixXd& r) {
  Problem p;
  p.n = static_cast<int>(r.rows());
  p.equations = p.n - 2;
  p.f = [r](const VectorXd& x) {
    const VectorXd q = r * x;
    VectorXd v(r.rows() - 2);
    v(0) = q(0) * q(0) + q(1) * q(1) - 0.5;
    v(1) = q(2) * q(2) + q(3) * q(3) - 0.5;
    for (int i = 4; i < r.rows(); ++i) v(i - 2) = q(i);
    return v;
  };
  VectorXd q = VectorXd::Zero(p.n);
  q(0) = q(2) = std::sqrt(0.5);
  p.seeds = {r.transpose() * q};
  return p;
}

MatrixXd planeRotation(int n, int i, int j, double c, double s) {
  MatrixXd g = MatrixXd::Identity(n, n);
  g(i, i) = g(j, j) = c;
  g(i, j) = -s;
  g(j, i) = s;
  return g;
}

bool makeProblem(const std::string& name, Problem& p) {
  if (name == "torus") {
    p.n = 3;
    p.equations = 1;
    p.f = [](const VectorXd& x) {
      const double s = x.squaredNorm() + 0.84;
      return VectorXd::Constant(1, s * s - 4 * (x(0) * x(0) + x(1) * x(1)));
    };
    p.seeds = {Eigen::Vector3d(1.4, 0, 0)};
  } else if (name == "genus2") {
    p.n = 3;
    p.equations = 1;
    p.f = [](const VectorXd& x) {
      const double r = x(0) * x(0) + x(1) * x(1);
      const double f = r * r - x(0) * x(0) + x(1) * x(1);
      return VectorXd::Constant(1, f * f + x(2) * x(2) - 0.01);
    };
    p.seeds = {Eigen::Vector3d(std::sqrt((1 + std::sqrt(1.4)) / 2), 0, 0)};
  } else if (name == "clifford-torus-rotated") {
    // bench/problems/clifford-torus-rotated.toml: q = H x, H the 4x4 Hadamard matrix / 2.
    MatrixXd h(4, 4);
    h << 1, 1, 1, 1, 1, -1, 1, -1, 1, 1, -1, -1, 1, -1, -1, 1;
    p = rotatedClifford(0.5 * h);
  } else if (name == "flat-torus-r6") {
    // bench/problems/flat-torus-r6.toml: R a product of five plane rotations by (0.6, 0.8).
    const MatrixXd r = planeRotation(6, 0, 3, 0.6, 0.8) * planeRotation(6, 1, 4, 0.8, 0.6) *
                       planeRotation(6, 2, 5, 0.6, 0.8) * planeRotation(6, 3, 1, 0.8, 0.6) *
                       planeRotation(6, 4, 2, 0.6, 0.8);
    p = rotatedClifford(r);
  } else if (name == "sphere-r5") {
    MatrixXd m(2, 5);
    m << 1, 1, -1, 0, 0.5, 0, 1, 0.5, -1, 1;
    VectorXd d(2);
    d << 0.1, -0.05;
    p = sphereSection(m, d);
  } else if (name == "circle-r8") {
    MatrixXd m(6, 8);
    m << 1, 1, -1, 0, 0.5, 0, 0, 0.25,    //
        0, 1, 0.5, -1, 1, 0.25, 0, 0,     //
        0.5, 0, 1, 1, -1, 1, 0, 0,        //
        1, -0.5, 0, 1, 0.25, -1, 0.5, 0,  //
        0, 0, 1, 0, 0.5, 1, -1, 1,        //
        0.25, 1, 0, 0.5, 0, 0, 1, -1;
    VectorXd d(6);
    d << 0.1, -0.05, 0.15, -0.1, 0.05, -0.1;
    p = sphereSection(m, d);
  } else if (name == "sphere3-r5" || name == "sphere3-r6") {
    // experiments/problems/sphere3-r5.toml, sphere3-r6.toml: |x - c| = 0.93 in a 4-flat through c
    // (the files' coefficients, 6 significant digits).
    const int n = name == "sphere3-r5" ? 5 : 6;
    VectorXd c(n);
    for (int i = 0; i < n; ++i)
      c(i) = std::array<double, 6>{0.0317, -0.0211, 0.0143, -0.0378, 0.0259, -0.0096}[i];
    MatrixXd m(n - 4, n);
    VectorXd d(n - 4);
    if (n == 5) {
      m << -0.010174, 0.587131, -0.532017, 0.540751, 0.282348;
      d << 0.0334464;
    } else {
      m << 0.824223, -0.437238, -0.310599, 0.114575, -0.0962254, -0.103056,  //
          0.187423, 0.62032, -0.347973, 0.532667, 0.112204, 0.40332;
      d << -0.0250782, 0.0332241;
    }
    p = sphereSection(m, d, c, 0.93);
  } else if (name == "s1xs2-r5") {
    VectorXd c(5);
    c << 0.0213, -0.0147, -0.0181, 0.0262, 0.0119;
    p = sphereProduct({2, 3}, c, {0.83, 0.61});
  } else if (name == "flat-3torus-r6") {
    VectorXd c(6);
    c << 0.0213, -0.0147, -0.0181, 0.0262, 0.0119, -0.0231;
    p = sphereProduct({2, 2, 2}, c, {0.71, 0.67, 0.63});
  } else if (name == "o3-r9") {
    p = orthogonalGroup();
  } else if (name.rfind("section:", 0) == 0) {
    // The file: n, then one row per hyperplane, M's row and d's entry (none for a sphere).
    std::ifstream in(name.substr(8));
    int n = 0;
    if (!(in >> n) || n < 2) return false;
    std::vector<double> values;
    for (double v; in >> v;) values.push_back(v);
    if (values.size() % static_cast<std::size_t>(n + 1) != 0) return false;
    const auto rows = static_cast<Eigen::Index>(values.size() / static_cast<std::size_t>(n + 1));
    MatrixXd m(rows, n);
    VectorXd d(rows);
    for (Eigen::Index i = 0; i < rows; ++i) {
      for (Eigen::Index j = 0; j < n; ++j)
        m(i, j) = values[static_cast<std::size_t>(i * (n + 1) + j)];
      d(i) = values[static_cast<std::size_t>(i * (n + 1) + n)];
    }
    p = sphereSection(m, d);
  } else {
    return false;
  }
  return true;
}

[[noreturn]] void usage(const char* message) {
  std::fprintf(stderr,
               "gudhi_trace: %s\nusage: gudhi_trace PROBLEM [--scale S] [--out mesh.ply]\n"
               "  PROBLEM: torus, clifford-torus-rotated, sphere-r5, flat-torus-r6, circle-r8, "
               "genus2, sphere3-r5, sphere3-r6, s1xs2-r5, flat-3torus-r6, o3-r9, section:FILE\n",
               message);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace Gudhi::coxeter_triangulation;
  if (argc < 2) usage("no problem");
  const std::string name = argv[1];
  std::string out;
  double scale = 0.1;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) usage(("missing value after " + a).c_str());
    const char* v = argv[++i];
    if (a == "--scale") {
      scale = std::atof(v);
    } else if (a == "--out") {
      out = v;
    } else {
      usage(("unknown option " + a).c_str());
    }
  }
  Problem problem;
  if (!makeProblem(name, problem)) usage(("unknown problem " + name).c_str());
  const int n = problem.n, k = n - problem.equations;

  const auto start = std::chrono::steady_clock::now();
  const Function function{&problem};
  auto oracle = make_oracle(function);
  Coxeter_triangulation<> cox(static_cast<std::size_t>(n));
  // A fixed, generic offset (no randomness: the runs are repeatable), then the scale.
  VectorXd offset(n);
  for (int i = 0; i < n; ++i) offset(i) = 0.1234567 + 0.0712345 * i;
  cox.change_offset(offset);
  cox.change_matrix(scale * cox.matrix());
  using MT = Manifold_tracing<Coxeter_triangulation<>>;
  using Out_simplex_map = MT::Out_simplex_map;
  Out_simplex_map traced;
  manifold_tracing_algorithm(problem.seeds, cox, oracle, traced);
  Cell_complex<Out_simplex_map> complex(static_cast<std::size_t>(k));
  complex.construct_complex(traced);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Vertices: the 0-cells with their points; simplices: edges, fanned polygons or coned 3-cells.
  using Cell = Cell_complex<Out_simplex_map>::Hasse_cell;
  std::map<Cell*, int> index;
  std::vector<VectorXd> points;
  for (const auto& [cell, point] : complex.cell_point_map()) {
    index.emplace(cell, static_cast<int>(points.size()));
    points.push_back(point);
  }
  auto ends = [&](Cell* edge) {
    auto& b = edge->get_boundary();
    return std::array<int, 2>{index.at(b.at(0).first), index.at(b.at(1).first)};
  };
  // A polygon (2-cell) as the cycle of its vertices, from its lowest-numbered vertex.
  auto polygon = [&](Cell* cell) {
    std::map<int, std::vector<int>> next;
    for (auto& [edge, incidence] : cell->get_boundary()) {
      const auto e = ends(edge);
      next[e[0]].push_back(e[1]);
      next[e[1]].push_back(e[0]);
    }
    std::vector<int> cycle{next.begin()->first};
    int previous = -1;
    while (true) {
      const auto& around = next[cycle.back()];
      if (around.size() != 2) break;  // not a cycle (never seen): fan what was walked
      const int following = around[0] != previous ? around[0] : around[1];
      if (following == cycle.front() || cycle.size() > next.size()) break;
      previous = cycle.back();
      cycle.push_back(following);
    }
    return cycle;
  };
  std::vector<std::vector<int>> simplices;
  std::size_t cells[4] = {points.size(), 0, 0, 0};
  const auto& maps = complex.interior_simplex_cell_maps();
  for (std::size_t d = 1; d < 4; ++d)
    if (maps.size() > d) cells[d] = maps[d].size();
  if (k == 1) {
    for (const auto& [simplex, cell] : maps[1]) {
      const auto e = ends(cell);
      simplices.push_back({e[0], e[1]});
    }
  } else if (k == 2 && maps.size() > 2) {
    for (const auto& [simplex, cell] : maps[2]) {
      // Order the polygon's vertices by walking its boundary edges, then fan it.
      const std::vector<int> cycle = polygon(cell);
      for (std::size_t i = 1; i + 1 < cycle.size(); ++i)
        simplices.push_back({cycle[0], cycle[i], cycle[i + 1]});
    }
  } else if (k == 3 && maps.size() > 3) {
    // Each polygon fanned once (the same triangles in the two 3-cells that share it).
    std::map<Cell*, std::vector<std::array<int, 3>>> fans;
    for (const auto& [simplex, cell] : maps[2]) {
      const std::vector<int> cycle = polygon(cell);
      auto& fan = fans[cell];
      for (std::size_t i = 1; i + 1 < cycle.size(); ++i)
        fan.push_back({cycle[0], cycle[i], cycle[i + 1]});
    }
    // Each 3-cell: a new vertex on M near the barycentre of its vertices, coned over its
    // polygons' triangles.
    for (const auto& [simplex, cell] : maps[3]) {
      std::vector<std::array<int, 3>> triangles;
      std::set<int> vertices;
      for (auto& [face, incidence] : cell->get_boundary())
        for (const auto& t : fans.at(face)) {
          triangles.push_back(t);
          vertices.insert(t.begin(), t.end());
        }
      VectorXd centre = VectorXd::Zero(n);
      for (int v : vertices) centre += points[static_cast<std::size_t>(v)];
      centre /= static_cast<double>(vertices.size());
      const int apex = static_cast<int>(points.size());
      points.push_back(ontoM(problem, centre));
      for (const auto& t : triangles) simplices.push_back({apex, t[0], t[1], t[2]});
    }
  }

  if (!out.empty()) {
    std::ofstream o(out);
    o.precision(17);
    o << "ply\nformat ascii 1.0\ncomment gudhi_trace " << name << "\nelement vertex "
      << points.size() << "\nproperty double x\nproperty double y\nproperty double z\n";
    for (int j = 0; j < n; ++j) o << "property double u" << j << "\n";
    if (k == 1)
      o << "element edge " << simplices.size() << "\nproperty int vertex1\nproperty int vertex2\n";
    // k >= 2: a `face` element of (k + 1)-vertex lists, as ndcontour's mesh.ply
    else
      o << "element face " << simplices.size() << "\nproperty list uchar int vertex_indices\n";
    o << "end_header\n";
    for (const VectorXd& p : points) {
      for (int j = 0; j < 3; ++j) o << (j < n ? p(j) : 0.0) << ' ';
      for (int j = 0; j < n; ++j) o << p(j) << (j + 1 < n ? ' ' : '\n');
    }
    for (const auto& s : simplices) {
      if (k != 1) o << s.size() << ' ';
      for (std::size_t i = 0; i < s.size(); ++i) o << s[i] << (i + 1 < s.size() ? ' ' : '\n');
    }
  }
  std::printf(
      "{\"tool\": \"gudhi\", \"problem\": \"%s\", \"n\": %d, \"k\": %d, \"scale\": %g, "
      "\"vertices\": %zu, \"cells\": [%zu, %zu, %zu, %zu], \"simplices\": %zu, "
      "\"time_s\": %.6f}\n",
      name.c_str(), n, k, scale, points.size(), cells[0], cells[1], cells[2], cells[3],
      simplices.size(), seconds);
  return 0;
}
