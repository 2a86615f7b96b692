// Application problem files (paper Sec. 3): the common tables ([[surfaces]], [motion], eye,
// alpha) are read and validated here; the application's builder then forms its system.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "applications/applications.hpp"
#include "applications/load.hpp"

namespace ndc {

namespace {

/// Largest degree and number of control points per direction accepted (bounded work).
constexpr long kMaxDegree = 12;
constexpr long kMaxControlPoints = 64;

struct Reader {
  const TomlReader& r;

  std::array<double, 3> point(const toml::node& node, const std::string& what) const {
    const toml::array& a = r.arrayOf(node, what);
    if (a.size() != 3)
      r.fail(node,
             what + " must be [x, y, z] (3 numbers), got " + std::to_string(a.size()) + " values");
    return {r.numberOf(a[0], what + ".x"), r.numberOf(a[1], what + ".y"),
            r.numberOf(a[2], what + ".z")};
  }

  std::array<double, 2> range(const toml::node& node, const std::string& what) const {
    const toml::array& a = r.arrayOf(node, what);
    if (a.size() != 2) r.fail(node, what + " must be [lo, hi]");
    const double lo = r.numberOf(a[0], what + ": lo"), hi = r.numberOf(a[1], what + ": hi");
    if (!(lo < hi)) r.fail(node, what + " is empty or inverted: lo must be less than hi");
    // The same rule as a problem's domain: a width that overflows has no cells.
    if (!std::isfinite(hi - lo))
      r.fail(node, what + " is too wide: hi - lo = " + TomlReader::format(hi) + " - " +
                       TomlReader::format(lo) + " overflows a double");
    return {lo, hi};
  }

  std::vector<double> knots(const toml::node& node, const std::string& what, int degree,
                            int count) const {
    const toml::array& a = r.arrayOf(node, what);
    std::vector<double> k;
    for (std::size_t i = 0; i < a.size(); ++i)
      k.push_back(r.numberOf(a[i], what + "[" + std::to_string(i) + "]"));
    if (static_cast<int>(k.size()) != count + degree + 1)
      r.fail(node, what + " needs count + degree + 1 = " + std::to_string(count + degree + 1) +
                       " knots, got " + std::to_string(k.size()));
    for (std::size_t i = 0; i + 1 < k.size(); ++i)
      if (k[i + 1] < k[i]) r.fail(node, what + " must be non-decreasing");
    if (!(k[degree] < k[count])) r.fail(node, what + ": the parameter range is empty");
    // Interior knots of multiplicity > degree would cut the surface apart.
    for (std::size_t i = 0; i < k.size(); ++i) {
      const long mult = std::count(k.begin(), k.end(), k[i]);
      if (k[i] > k[degree] && k[i] < k[count] && mult > degree)
        r.fail(node, what + ": interior knot " + TomlReader::format(k[i]) +
                         " has multiplicity above the degree");
    }
    return k;
  }

  /// Control points: rows (v index) of points (u index), into s.points, s.countU, s.countV.
  void controlPoints(const toml::node& pointsNode, const std::string& what, SurfaceSpec& s) const {
    const toml::array& rows = r.arrayOf(pointsNode, what + ".points");
    if (rows.size() < 2 || static_cast<long>(rows.size()) > kMaxControlPoints)
      r.fail(pointsNode, what + ".points needs 2 to 64 rows of control points");
    s.countV = static_cast<int>(rows.size());
    for (std::size_t j = 0; j < rows.size(); ++j) {
      const toml::array& row = r.arrayOf(rows[j], what + ".points[" + std::to_string(j) + "]");
      if (j == 0) s.countU = static_cast<int>(row.size());
      if (static_cast<int>(row.size()) != s.countU)
        r.fail(rows[j], what + ".points: every row needs the same number of points (" +
                            std::to_string(s.countU) + ")");
      if (s.countU < 2 || s.countU > kMaxControlPoints)
        r.fail(rows[j], what + ".points needs 2 to 64 points per row");
      for (std::size_t i = 0; i < row.size(); ++i)
        s.points.push_back(
            point(row[i], what + ".points[" + std::to_string(j) + "][" + std::to_string(i) + "]"));
    }
  }

  /// Positive weights in the shape of the points, scaled by a power of two.
  void weights(const toml::node& w, const std::string& what, SurfaceSpec& s) const {
    const toml::array& wr = r.arrayOf(w, what + ".weights");
    if (static_cast<int>(wr.size()) != s.countV)
      r.fail(w, what + ".weights must have the shape of points");
    for (std::size_t j = 0; j < wr.size(); ++j) {
      const toml::array& row = r.arrayOf(wr[j], what + ".weights[" + std::to_string(j) + "]");
      if (static_cast<int>(row.size()) != s.countU)
        r.fail(wr[j], what + ".weights must have the shape of points");
      for (std::size_t i = 0; i < row.size(); ++i) {
        const double v = r.numberOf(row[i], what + ".weights");
        if (!(v > 0))
          r.fail(row[i], what + ": weights must be positive (the denominator stays positive)");
        s.weights.push_back(v);
      }
    }
    // A rational surface is unchanged when all its weights are scaled alike: scale them by a
    // power of two (exact) so the largest lies in [1, 2), or weights near 1e-300 underflow to 0
    // in the products the equations are built from and the run solves garbage.
    const double largest = *std::max_element(s.weights.begin(), s.weights.end());
    int exponent = 0;
    std::frexp(largest, &exponent);
    for (double& weight : s.weights) weight = std::ldexp(weight, 1 - exponent);
  }

  SurfaceSpec surface(const toml::node& node, int index) const {
    const std::string what = "surfaces[" + std::to_string(index) + "]";
    const toml::table& t = r.tableOf(node, what);
    r.onlyKeys(t, {"name", "degree", "points", "weights", "knots_u", "knots_v", "box"}, what);
    SurfaceSpec s;
    s.name = t.get("name") ? r.stringOf(*t.get("name"), what + ".name")
                           : "S" + std::to_string(index + 1);
    const toml::node& pointsNode = r.require(t, "points");
    controlPoints(pointsNode, what, s);
    // Degrees: given, or count - 1 (Bezier).
    if (const toml::node* d = t.get("degree")) {
      const toml::array& a = r.arrayOf(*d, what + ".degree");
      if (a.size() != 2) r.fail(*d, what + ".degree must be [degree_u, degree_v]");
      s.degreeU = static_cast<int>(r.integerOf(a[0], what + ".degree[0]", 1, kMaxDegree));
      s.degreeV = static_cast<int>(r.integerOf(a[1], what + ".degree[1]", 1, kMaxDegree));
    } else {
      s.degreeU = s.countU - 1;
      s.degreeV = s.countV - 1;
      if (s.degreeU > kMaxDegree || s.degreeV > kMaxDegree)
        r.fail(pointsNode, what + ": a Bezier patch of degree above 12 is not supported");
    }
    const toml::node* ku = t.get("knots_u");
    const toml::node* kv = t.get("knots_v");
    if (ku) s.knotsU = knots(*ku, what + ".knots_u", s.degreeU, s.countU);
    if (kv) s.knotsV = knots(*kv, what + ".knots_v", s.degreeV, s.countV);
    if (!ku && s.countU != s.degreeU + 1)
      r.fail(pointsNode, what + ": a Bezier direction needs degree + 1 = " +
                             std::to_string(s.degreeU + 1) + " points per row, got " +
                             std::to_string(s.countU) + " (or give knots_u for a B-spline)");
    if (!kv && s.countV != s.degreeV + 1)
      r.fail(pointsNode,
             what + ": a Bezier direction needs degree + 1 = " + std::to_string(s.degreeV + 1) +
                 " rows, got " + std::to_string(s.countV) + " (or give knots_v for a B-spline)");
    if (const toml::node* b = t.get("box")) {
      if (ku || kv)
        r.fail(*b, what + ".box is for Bezier patches (a B-spline's range is its knots)");
      const toml::array& a = r.arrayOf(*b, what + ".box");
      if (a.size() != 2) r.fail(*b, what + ".box must be [[u0, u1], [v0, v1]]");
      const auto bu = range(a[0], what + ".box[0]"), bv = range(a[1], what + ".box[1]");
      s.box = {bu[0], bu[1], bv[0], bv[1]};
    }
    if (const toml::node* w = t.get("weights")) weights(*w, what, s);
    return s;
  }

  MotionSpec motion(const toml::node& node) const {
    const toml::table& t = r.tableOf(node, "motion");
    r.onlyKeys(t, {"translation", "rotation", "time"}, "motion");
    MotionSpec m;
    const toml::node& tr = r.require(t, "translation");
    const toml::array& ta = r.arrayOf(tr, "motion.translation");
    if (ta.empty() || static_cast<long>(ta.size()) > kMaxDegree + 1)
      r.fail(tr, "motion.translation needs 1 to 13 control points");
    for (std::size_t i = 0; i < ta.size(); ++i)
      m.translation.push_back(point(ta[i], "motion.translation[" + std::to_string(i) + "]"));
    const toml::node& ro = r.require(t, "rotation");
    const toml::array& ra = r.arrayOf(ro, "motion.rotation");
    if (ra.empty() || static_cast<long>(ra.size()) > kMaxDegree + 1)
      r.fail(ro, "motion.rotation needs 1 to 13 quaternion control points");
    for (std::size_t i = 0; i < ra.size(); ++i) {
      const std::string what = "motion.rotation[" + std::to_string(i) + "]";
      const toml::array& q = r.arrayOf(ra[i], what);
      if (q.size() != 4) r.fail(ra[i], what + " must be a quaternion [q0, q1, q2, q3]");
      m.rotation.push_back({r.numberOf(q[0], what), r.numberOf(q[1], what), r.numberOf(q[2], what),
                            r.numberOf(q[3], what)});
    }
    if (const toml::node* time = t.get("time")) m.time = range(*time, "motion.time");
    return m;
  }
};

}  // namespace

void ApplicationInput::fail(const std::string& message) const {
  if (root && root->get("application")) reader->fail(*root->get("application"), message);
  reader->fail(message);
}

Problem buildApplication(const toml::table& root, TomlReader& reader) {
  reader.onlyKeys(
      root, {"name", "application", "description", "surfaces", "motion", "eye", "alpha", "expect"},
      "an application problem");
  ApplicationInput in;
  in.reader = &reader;
  in.root = &root;
  const toml::node& name = reader.require(root, "name");
  in.name = reader.stringOf(name, "name");
  if (!isProblemName(in.name)) reader.fail(name, "name '" + in.name + "' must match [a-z0-9._-]+");
  reader.setProblem(in.name);
  const toml::node& app = reader.require(root, "application");
  in.application = reader.stringOf(app, "application");
  if (const toml::node* d = root.get("description"))
    in.description = reader.stringOf(*d, "description");
  const Reader read{reader};
  if (const toml::node* s = root.get("surfaces")) {
    const toml::array& list = reader.arrayOf(*s, "surfaces");
    if (list.size() > 8) reader.fail(*s, "at most 8 surfaces are supported");
    for (std::size_t i = 0; i < list.size(); ++i)
      in.surfaces.push_back(read.surface(list[i], static_cast<int>(i)));
  }
  if (const toml::node* m = root.get("motion")) in.motion = read.motion(*m);
  if (const toml::node* e = root.get("eye")) in.eye = read.point(*e, "eye");
  if (const toml::node* a = root.get("alpha")) {
    const toml::array& list = reader.arrayOf(*a, "alpha");
    if (list.size() != 2) reader.fail(*a, "alpha must be [[lo1, hi1], [lo2, hi2]]");
    const auto a1 = read.range(list[0], "alpha[0]"), a2 = read.range(list[1], "alpha[1]");
    in.alpha = std::array<double, 4>{a1[0], a1[1], a2[0], a2[1]};
  }
  if (const toml::node* e = root.get("expect")) in.expect = reader.expectOf(*e);

  struct Entry {
    const char* name;
    Problem (*build)(const ApplicationInput&);
  };
  const Entry entries[] = {{"convex-hull", &buildConvexHull},
                           {"sweep-silhouette", &buildSweepSilhouette},
                           {"bisector", &buildBisector},
                           {"sweep-envelope", &buildSweepEnvelope},
                           {"blending", &buildBlending}};
  for (const Entry& entry : entries) {
    if (in.application != entry.name) continue;
    Problem p;
    try {
      p = entry.build(in);
    } catch (const InputError& error) {
      // Messages from the geometry (knots off the dyadic grid, too many B-spline patches) do
      // not know the file: name it.
      if (std::string(error.what()).rfind(reader.file(), 0) == 0) throw;
      in.fail(error.what());
    } catch (const std::exception& error) {
      in.fail(error.what());
    }
    p.path = reader.file();
    p.name = in.name;
    if (p.description.empty()) p.description = in.description;
    p.expect = in.expect;
    // The same size limit as for plain equations.
    for (std::size_t i = 0; i < p.equations.size(); ++i) {
      double coefficients = 1;
      for (int d : p.equations[i].degrees()) coefficients *= d + 1.0;
      if (coefficients > kMaxCoefficients) {
        std::ostringstream message;
        message << "equation " << i + 1 << " of " << in.application << " needs " << coefficients
                << " Bernstein coefficients; at most " << kMaxCoefficients
                << " are supported (lower the surface degrees)";
        in.fail(message.str());
      }
    }
    return p;
  }
  reader.fail(app, "unknown application '" + in.application +
                       "' (known: convex-hull, sweep-silhouette, bisector, sweep-envelope, "
                       "blending)");
}

Problem parseProblem(const std::string& text, const std::string& file) {
  return parseProblemWith(text, file, buildApplication);
}

Problem loadProblem(const std::filesystem::path& file) {
  return parseProblem(readInputFile(file, "problem file"), file.string());
}

}  // namespace ndc
