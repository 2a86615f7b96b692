// Gluing the meshes of a split solve along the faces their boxes share (glue.hpp).
#include "framework/mesh/glue.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include "framework/util/disjoint_sets.hpp"

namespace ndc {

namespace {

/// The farthest a vertex inserted into an edge of the other side's polyline may lie from it,
/// relative to the edge's length.
constexpr double kMaxRelativeDistance = 0.25;

/// The key of an undirected edge between two vertex numbers.
std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  const auto lo = static_cast<std::uint32_t>(std::min(a, b));
  const auto hi = static_cast<std::uint32_t>(std::max(a, b));
  return (std::uint64_t{lo} << 32) | hi;
}

/// A face two pieces share: piece p below the plane x_axis = value, piece q above it.
struct SharedFace {
  int p = 0, q = 0, axis = 0;
  double value = 0;
};

/// The state of a gluing: every piece's vertices numbered globally, a union-find over them, and
/// each piece's triangles (or segments) with its boundary edges (k = 2).
class Gluer {
 public:
  Gluer(int n, int k, const std::vector<MeshPiece>& pieces, double tolerance)
      : n_(n), k_(k), tol_(tolerance), pieces_(pieces) {
    // Global vertex numbers: piece p's vertex v is first_[p] + v.
    first_.push_back(0);
    for (const MeshPiece& piece : pieces) {
      const auto count = static_cast<std::int32_t>(piece.vertices.size() / n);
      for (std::int32_t v = 0; v < count; ++v)
        owner_.push_back(static_cast<int>(first_.size()) - 1);
      first_.push_back(first_.back() + count);
      coords_.insert(coords_.end(), piece.vertices.begin(), piece.vertices.end());
    }
    sets_ = DisjointSets(owner_.size());
    simplices_.resize(pieces.size());
    boundary_.resize(pieces.size());
    for (std::size_t p = 0; p < pieces.size(); ++p) {
      for (const std::int32_t v : pieces[p].simplices) simplices_[p].push_back(first_[p] + v);
      if (k_ == 2) indexBoundary(p);
    }
  }

  /// The faces the pieces share (boxes that meet along a whole plane piece of positive size).
  std::vector<SharedFace> sharedFaces() const {
    std::vector<SharedFace> faces;
    for (std::size_t p = 0; p < pieces_.size(); ++p)
      for (std::size_t q = 0; q < pieces_.size(); ++q)
        for (int a = 0; a < n_; ++a)
          if (p != q && std::abs(pieces_[p].box.hi[a] - pieces_[q].box.lo[a]) <= tol_ &&
              overlapOff(pieces_[p].box, pieces_[q].box, a))
            faces.push_back({static_cast<int>(p), static_cast<int>(q), a, pieces_[p].box.hi[a]});
    return faces;
  }

  /// Identifies the vertices of p and q on their shared face that agree within the tolerance.
  void match(const SharedFace& f) {
    std::vector<std::int32_t> below = verticesOnFace(f.p, f), above = verticesOnFace(f.q, f);
    // Sorted along one axis of the face, so each vertex compares with a narrow window.
    const int b = f.axis == 0 ? 1 : 0;
    const auto along = [&](std::int32_t v) { return at(v)[b]; };
    std::sort(above.begin(), above.end(),
              [&](std::int32_t x, std::int32_t y) { return along(x) < along(y); });
    for (const std::int32_t v : below) {
      auto it = std::lower_bound(above.begin(), above.end(), along(v) - tol_,
                                 [&](std::int32_t x, double value) { return along(x) < value; });
      for (; it != above.end() && along(*it) <= along(v) + tol_; ++it)
        if (close(v, *it) && find(v) != find(*it)) {
          unite(v, *it);
          ++matched_;
        }
    }
  }

  /// k = 2: makes the two boundary polylines on the face have the same vertices, inserting each
  /// vertex one side lacks into the other side's nearest boundary edge on the face.
  void completePolylines(const SharedFace& f) {
    insertMissing(f, f.p, f.q);
    insertMissing(f, f.q, f.p);
  }

  /// The glued mesh: one vertex per class of identified vertices that a simplex uses, simplices
  /// that identification made degenerate dropped; then the check of the shared faces.
  GlueResult result(const std::vector<SharedFace>& faces) {
    GlueResult out;
    std::vector<std::int32_t> number(owner_.size(), -1);
    for (const auto& list : simplices_)
      for (std::size_t s = 0; s + k_ < list.size(); s += k_ + 1) {
        std::int32_t ids[3];
        bool degenerate = false;
        for (int j = 0; j <= k_; ++j) {
          ids[j] = find(list[s + j]);
          for (int i = 0; i < j; ++i) degenerate |= ids[i] == ids[j];
        }
        if (degenerate) continue;
        for (int j = 0; j <= k_; ++j) {
          if (number[ids[j]] < 0) {
            number[ids[j]] = static_cast<std::int32_t>(out.vertices.size() / n_);
            const double* x = at(ids[j]);
            out.vertices.insert(out.vertices.end(), x, x + n_);
          }
          out.simplices.push_back(number[ids[j]]);
        }
      }
    out.matched = matched_;
    out.inserted = inserted_;
    check(out, faces);
    return out;
  }

 private:
  const double* at(std::int32_t v) const {
    return coords_.data() + static_cast<std::size_t>(v) * n_;
  }

  std::int32_t find(std::int32_t v) { return sets_.find(v); }
  void unite(std::int32_t a, std::int32_t b) { sets_.unite(a, b); }

  bool close(std::int32_t a, std::int32_t b) const {
    for (int j = 0; j < n_; ++j)
      if (std::abs(at(a)[j] - at(b)[j]) > tol_) return false;
    return true;
  }

  /// Whether two boxes overlap with positive width on every axis but `axis`.
  bool overlapOff(const Box<double>& x, const Box<double>& y, int axis) const {
    for (int j = 0; j < n_; ++j)
      if (j != axis && std::min(x.hi[j], y.hi[j]) - std::max(x.lo[j], y.lo[j]) <= tol_)
        return false;
    return true;
  }

  /// Whether vertex v lies on the face: on its plane and within both boxes on the other axes.
  bool onFace(std::int32_t v, const SharedFace& f) const {
    const double* x = at(v);
    if (std::abs(x[f.axis] - f.value) > tol_) return false;
    const Box<double>& p = pieces_[f.p].box;
    const Box<double>& q = pieces_[f.q].box;
    for (int j = 0; j < n_; ++j)
      if (j != f.axis &&
          (x[j] < std::max(p.lo[j], q.lo[j]) - tol_ || x[j] > std::min(p.hi[j], q.hi[j]) + tol_))
        return false;
    return true;
  }

  /// The vertices of piece p on the face (those its simplices use).
  std::vector<std::int32_t> verticesOnFace(int p, const SharedFace& f) const {
    std::vector<std::int32_t> out;
    for (std::int32_t v = first_[p]; v < first_[p + 1]; ++v)
      if (onFace(v, f)) out.push_back(v);
    return out;
  }

  /// Piece p's boundary edges (in one triangle each), keyed by edgeKey, to the triangle.
  void indexBoundary(std::size_t p) {
    std::unordered_map<std::uint64_t, std::int32_t> count;
    const auto& tris = simplices_[p];
    for (std::size_t t = 0; t + 2 < tris.size(); t += 3)
      for (int e = 0; e < 3; ++e) ++count[edgeKey(tris[t + e], tris[t + (e + 1) % 3])];
    for (std::size_t t = 0; t + 2 < tris.size(); t += 3)
      for (int e = 0; e < 3; ++e) {
        const std::uint64_t key = edgeKey(tris[t + e], tris[t + (e + 1) % 3]);
        if (count[key] == 1) boundary_[p][key] = static_cast<std::int32_t>(t / 3);
      }
  }

  /// Piece p's boundary edges with both ends on the face.
  std::vector<std::uint64_t> faceEdges(int p, const SharedFace& f) const {
    std::vector<std::uint64_t> edges;
    for (const auto& [key, triangle] : boundary_[p]) {
      const auto a = static_cast<std::int32_t>(key >> 32);
      const auto b = static_cast<std::int32_t>(key & 0xffffffffu);
      if (onFace(a, f) && onFace(b, f)) edges.push_back(key);
    }
    std::sort(edges.begin(), edges.end());  // a deterministic order
    return edges;
  }

  /// How far vertex v lies from the segment between vertices a and b, relative to the segment's
  /// length, when its foot on the line falls strictly inside the segment; infinity otherwise.
  double relativeDistance(std::int32_t v, std::int32_t a, std::int32_t b) const {
    double dot = 0, length = 0;
    for (int j = 0; j < n_; ++j) {
      const double d = at(b)[j] - at(a)[j];
      dot += (at(v)[j] - at(a)[j]) * d;
      length += d * d;
    }
    const double s = length > 0 ? dot / length : -1.0;
    if (!(s > 0 && s < 1)) return std::numeric_limits<double>::infinity();
    double sum = 0;
    for (int j = 0; j < n_; ++j) {
      const double d = at(a)[j] + s * (at(b)[j] - at(a)[j]) - at(v)[j];
      sum += d * d;
    }
    return std::sqrt(sum / length);
  }

  /// Inserts into `into`'s polyline on the face every vertex of `from`'s polyline it lacks.
  void insertMissing(const SharedFace& f, int from, int into) {
    std::vector<std::uint64_t> source = faceEdges(from, f), target = faceEdges(into, f);
    if (target.empty()) return;  // nothing to insert into: the check counts the edges
    std::unordered_set<std::int32_t> present;
    for (const std::uint64_t key : target) {
      present.insert(find(static_cast<std::int32_t>(key >> 32)));
      present.insert(find(static_cast<std::int32_t>(key & 0xffffffffu)));
    }
    std::vector<std::int32_t> missing;
    for (const std::uint64_t key : source)
      for (const auto v :
           {static_cast<std::int32_t>(key >> 32), static_cast<std::int32_t>(key & 0xffffffffu)})
        if (present.insert(find(v)).second) missing.push_back(v);
    for (const std::int32_t v : missing) {
      // The nearest edge of the other side's polyline between whose ends v falls, within a
      // quarter of its length (a finer polyline along the same curve); ties to the first in key
      // order. None: v stays unmatched, and the check counts the edges that differ.
      std::size_t best = target.size();
      double distance = std::numeric_limits<double>::infinity();
      for (std::size_t e = 0; e < target.size(); ++e) {
        const double d = relativeDistance(v, static_cast<std::int32_t>(target[e] >> 32),
                                          static_cast<std::int32_t>(target[e] & 0xffffffffu));
        if (d < distance) distance = d, best = e;
      }
      if (best == target.size() || distance > kMaxRelativeDistance) continue;
      const std::uint64_t key = target[best];
      const auto [left, right] = splitEdge(into, key, v);
      target[best] = left;
      target.push_back(right);
      ++inserted_;
    }
  }

  /// Splits the triangle of piece p's boundary edge `key` at vertex v into two, keeping its
  /// orientation; returns the keys of the two new boundary edges.
  std::pair<std::uint64_t, std::uint64_t> splitEdge(int p, std::uint64_t key, std::int32_t v) {
    auto& tris = simplices_[p];
    auto& boundary = boundary_[p];
    const std::int32_t t = boundary.at(key);
    std::int32_t* corner = tris.data() + static_cast<std::size_t>(t) * 3;
    int i = 0;
    while (edgeKey(corner[i], corner[(i + 1) % 3]) != key) ++i;
    const std::int32_t a = corner[i], b = corner[(i + 1) % 3], o = corner[(i + 2) % 3];
    const auto second = static_cast<std::int32_t>(tris.size() / 3);
    // (a, b, o) becomes (a, v, o) in its slot and (v, b, o) at the end.
    corner[0] = a, corner[1] = v, corner[2] = o;
    tris.insert(tris.end(), {v, b, o});
    boundary.erase(key);
    boundary[edgeKey(a, v)] = t;
    boundary[edgeKey(v, b)] = second;
    if (auto it = boundary.find(edgeKey(b, o)); it != boundary.end()) it->second = second;
    return {edgeKey(a, v), edgeKey(v, b)};
  }

  /// Counts the shared faces' elements left without a partner: for k = 2 the edges with both
  /// ends on a shared face in other than two triangles, for k = 1 the vertices on one in other
  /// than two segments.
  void check(GlueResult& out, const std::vector<SharedFace>& faces) const {
    const auto count = static_cast<std::int32_t>(out.vertices.size() / n_);
    const auto onShared = [&](std::int32_t v) -> int {
      const double* x = out.vertices.data() + static_cast<std::size_t>(v) * n_;
      for (std::size_t i = 0; i < faces.size(); ++i)
        if (std::abs(x[faces[i].axis] - faces[i].value) <= tol_) return static_cast<int>(i);
      return -1;
    };
    std::vector<int> face(count);
    for (std::int32_t v = 0; v < count; ++v) face[v] = onShared(v);
    if (k_ == 1) {
      std::vector<int> degree(count, 0);
      for (const std::int32_t v : out.simplices) ++degree[v];
      for (std::int32_t v = 0; v < count; ++v) out.unmatched += face[v] >= 0 && degree[v] != 2;
      if (out.unmatched)
        out.reason =
            std::to_string(out.unmatched) + " curve ends on faces the pieces share have no partner";
      return;
    }
    std::unordered_map<std::uint64_t, int> uses;
    for (std::size_t t = 0; t + 2 < out.simplices.size(); t += 3)
      for (int e = 0; e < 3; ++e)
        ++uses[edgeKey(out.simplices[t + e], out.simplices[t + (e + 1) % 3])];
    const auto onPlane = [&](std::int32_t v, const SharedFace& f) {
      return std::abs(out.vertices[static_cast<std::size_t>(v) * n_ + f.axis] - f.value) <= tol_;
    };
    for (const auto& [key, times] : uses) {
      const auto a = static_cast<std::int32_t>(key >> 32);
      const auto b = static_cast<std::int32_t>(key & 0xffffffffu);
      bool shared = false;
      for (const SharedFace& f : faces) shared |= onPlane(a, f) && onPlane(b, f);
      out.unmatched += shared && times != 2;
    }
    if (out.unmatched)
      out.reason = std::to_string(out.unmatched) +
                   " edges on faces the pieces share lie in other than two triangles";
  }

  int n_, k_;
  double tol_;
  const std::vector<MeshPiece>& pieces_;
  std::vector<std::int32_t> first_;
  std::vector<int> owner_;
  std::vector<double> coords_;
  DisjointSets sets_{0};
  std::vector<std::vector<std::int32_t>> simplices_;
  std::vector<std::unordered_map<std::uint64_t, std::int32_t>> boundary_;
  std::int64_t matched_ = 0, inserted_ = 0;
};

}  // namespace

GlueResult gluePieces(int n, int k, const std::vector<MeshPiece>& pieces, double tolerance) {
  Gluer gluer(n, k, pieces, tolerance);
  const std::vector<SharedFace> faces = gluer.sharedFaces();
  // Identify first, everywhere, so that vertices on several faces (where three or more pieces
  // meet) are one before any polyline is completed.
  for (const SharedFace& f : faces) gluer.match(f);
  if (k == 2)
    for (const SharedFace& f : faces) gluer.completePolylines(f);
  return gluer.result(faces);
}

}  // namespace ndc
